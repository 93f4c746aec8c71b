"""Shared fixtures (one small generated dataset per test session, made by the real pipeline) and
the fast lane: `make test-fast` runs the tests marked `fast` — the pure core, planning, the audit
and the command lines, nothing that simulates — in a few minutes; `make test` runs everything."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from helpers import make_dataset  # noqa: E402

# Modules whose tests simulate nothing (a test among them that does is marked `slow`).
FAST_MODULES = {
    "test_spec", "test_vocabulary", "test_plan", "test_shape", "test_fuzz", "test_referent_specs", "test_cli", "test_reader",
}  # fmt: skip


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "fast: simulator-free; part of `make test-fast`")
    config.addinivalue_line("markers", "slow: simulates or trains, though its module is in the fast lane")


# The longest test files first: `make test` runs files side by side on two cores (xdist --dist
# loadfile hands them out in collection order), and a long file started last would run alone.
LONGEST_FIRST = (
    "test_libero_axes", "test_libero_world", "test_libero_spatial", "test_libero_goal", "test_libero_pro", "test_battery",
    "test_libero", "test_own_code", "test_mixed", "test_train", "test_resume", "test_lerobot_policy",
)  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if item.module.__name__ in FAST_MODULES and not item.get_closest_marker("slow"):
            item.add_marker(pytest.mark.fast)
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.module.__name__, len(rank)))  # stable: a file's tests keep their order


@pytest.fixture(scope="session")
def object_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 object-referent episodes at 64 px."""
    return make_dataset(tmp_path_factory.mktemp("ds") / "object", "referent=object", "n=4", "image_size=64", "seed=7")
