"""Shared fixtures (products made by the real pipeline once per run, shared by both of xdist's
workers: helpers.Shared) and the lanes, one folder each: tests/fast simulates nothing (the pure
core, planning, the audit, the command lines: `make test-fast`, a few minutes), tests/sim runs
our simulator, tests/libero runs LIBERO's worlds. The reference checks, the tests marked
`reference` (all in tests/libero), drive LIBERO's own environment (`.venv-libero`: its physics,
its pictures, replays and exams in its simulator) or sweep LIBERO's own suites (the canonical exams
on every task's initial states, every LIBERO-PRO suite) and are long: `make test` runs every test
but them, `make test-reference` runs them, and CI runs both."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

sys.path.insert(0, str(Path(__file__).parent))  # helpers.py and hubserver.py, for every lane's tests
from helpers import Shared  # noqa: E402

LANES = ("fast", "sim", "libero")  # tests/<lane>/: the folder decides a test's lane


def pytest_configure(config: pytest.Config) -> None:
    for lane in LANES:
        config.addinivalue_line("markers", f"{lane}: a test of tests/{lane}/")
    config.addinivalue_line("markers", "reference: drives LIBERO's own environment, or sweeps its suites (make test-reference)")


# The longest test files first: `make test` runs files side by side on two cores (xdist --dist
# loadfile hands them out in collection order), and a long file started last would run alone.
LONGEST_FIRST = (
    "test_libero_axes", "test_release", "test_libero_world", "test_battery", "test_own_code", "test_libero_pro",
    "test_axes_datasets", "test_libero_goal", "test_mixed", "test_libero_spatial", "test_libero", "test_lerobot_policy",
    "test_resume", "test_train", "test_export",
)  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        lane = item.path.parent.name
        if lane in LANES:
            item.add_marker(getattr(pytest.mark, lane))
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.module.__name__, len(rank)))  # stable: a file's tests keep their order


@pytest.fixture(scope="session")
def shared(tmp_path_factory: pytest.TempPathFactory) -> Shared:
    """The products built once per run (helpers.Shared), in the run's own temporary folder: under
    xdist each worker's folder is in it, so both workers find the same products."""
    run = tmp_path_factory.getbasetemp()
    root = (run.parent if os.environ.get("PYTEST_XDIST_WORKER") else run) / "shared"
    root.mkdir(exist_ok=True)
    return Shared(root)


@pytest.fixture(scope="session")
def object_dataset(shared: Shared) -> Path:
    """4 object-referent episodes at 64 px."""
    return shared.dataset("object", "referent=object", "n=4", "image_size=64", "seed=7")
