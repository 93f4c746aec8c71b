"""Shared fixtures: one small generated dataset per test session, made by the real pipeline."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

from helpers import make_dataset  # noqa: E402


@pytest.fixture(scope="session")
def object_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 object-referent episodes at 64 px."""
    return make_dataset(tmp_path_factory.mktemp("ds") / "object", "referent=object", "n=4", "image_size=64", "seed=7")
