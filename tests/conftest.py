"""Shared fixtures (one small generated dataset per test session, made by the real pipeline) and
the lanes, one folder each: tests/fast simulates nothing (the pure core, planning, the audit, the
command lines: `make test-fast`, a few minutes), tests/sim runs our simulator, tests/libero runs
LIBERO's worlds. The reference checks, the tests marked `reference` (all in tests/libero), drive
LIBERO's own environment (`.venv-libero`: its physics, its pictures, replays and exams in its
simulator) and are long: `make test` runs every test but them, `make test-reference` runs them, and
CI runs both."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

sys.path.insert(0, str(Path(__file__).parent))  # helpers.py and hubserver.py, for every lane's tests
from helpers import make_dataset  # noqa: E402

LANES = ("fast", "sim", "libero")  # tests/<lane>/: the folder decides a test's lane


def pytest_configure(config: pytest.Config) -> None:
    for lane in LANES:
        config.addinivalue_line("markers", f"{lane}: a test of tests/{lane}/")
    config.addinivalue_line("markers", "reference: drives LIBERO's own environment (make test-reference)")


# The longest test files first: `make test` runs files side by side on two cores (xdist --dist
# loadfile hands them out in collection order), and a long file started last would run alone.
LONGEST_FIRST = (
    "test_libero_axes", "test_libero_world", "test_libero_spatial", "test_libero_goal", "test_libero_pro", "test_battery",
    "test_libero", "test_own_code", "test_mixed", "test_train", "test_resume", "test_lerobot_policy",
)  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        lane = item.path.parent.name
        if lane in LANES:
            item.add_marker(getattr(pytest.mark, lane))
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.module.__name__, len(rank)))  # stable: a file's tests keep their order


@pytest.fixture(scope="session")
def object_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 object-referent episodes at 64 px."""
    return make_dataset(tmp_path_factory.mktemp("ds") / "object", "referent=object", "n=4", "image_size=64", "seed=7")
