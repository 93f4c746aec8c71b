"""A LIBERO-Object training set whose episodes change course (`switched=`, issue 52) replays in
LIBERO's own environment: each episode rebuilt from its record, its recorded actions stepped
there, and LIBERO's own check_success() judging the second instruction's goal where the
instruction changed (tests/helpers.py liberos_replay)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # noqa: F401  (before any GL context: docs/GENERATE.md)

from core import worlds
from gen.products import scenes
from helpers import liberos_own, liberos_replay, make_dataset


@pytest.mark.reference
def test_switched_episodes_succeed_in_liberos_own_environment(tmp_path: Path) -> None:
    root = make_dataset(tmp_path / "switched", "referent=libero_object", "n=4", "switched=0.5", "image_size=32", "workers=1")
    switched = [json.loads(s) for s in scenes.read(root).sort_values("episode_index")["switch"] if isinstance(s, str)]
    assert len(switched) == 2
    request = liberos_replay(root, worlds.world("libero_object"))
    results = json.loads(liberos_own("replay", request, tmp_path / "replay.json").read_text())
    assert [r["success"] for r in results] == [True] * 4, results
