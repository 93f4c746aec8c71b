"""Training sets whose episodes change course (`switched=`) replay in LIBERO's own environment:
each episode rebuilt from its record, its recorded actions stepped there, and LIBERO's own
check_success() judging the second instruction's goal where the instruction changed
(tests/helpers.py liberos_replay). LIBERO-Object's switches turn to another grocery before the
grasp; LIBERO-Goal's also carry a held object on to another place."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # noqa: F401  (before any GL context: docs/GENERATE.md)

from core import worlds
from gen.products import scenes
from helpers import liberos_own, liberos_replay, make_dataset


@pytest.mark.reference
@pytest.mark.parametrize(("world", "n", "seed"), [("libero_object", 4, 0), ("libero_goal", 8, 7)])
def test_switched_episodes_succeed_in_liberos_own_environment(world: str, n: int, seed: int, tmp_path: Path) -> None:
    args = (f"referent={world}", f"n={n}", f"seed={seed}", "switched=0.5", "image_size=32", "workers=1")
    root = make_dataset(tmp_path / "switched", *args)
    switched = [json.loads(s) for s in scenes.read(root).sort_values("episode_index")["switch"] if isinstance(s, str)]
    assert len(switched) == n // 2
    request = liberos_replay(root, worlds.world(world))
    results = json.loads(liberos_own("replay", request, tmp_path / "replay.json").read_text())
    assert [r["success"] for r in results] == [True] * n, results
