"""The full look (core/spec.py LOOKS): `look=full` draws every mesh whole and MuJoCo's reflections,
as LIBERO's own simulator does. A dataset made so is drawn so (its physics untouched), says so in
every record that rebuilds it, and what replays its episodes draws them the same way. How close
each look comes to LIBERO's own frames is the picture tests' (tests/libero/test_libero_*.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # before any GL context (docs/GENERATE.md: why these pins)

from core.exam import read
from core.profiles import ACTION_KEY, LIBERO, STATE_KEY
from core.spec import FAST, FULL, EpisodeSpec
from eval.env import ExamEnv
from gen.config import parse
from gen.products import scenes
from gen.products.canonical import CanonicalOptions, build
from helpers import make_dataset
from jobs.cli import UserError
from oracle.scene import spec_scene

WORLD = "libero_spatial"  # its stove's mirror top is what the two looks draw most differently


@pytest.fixture(scope="module")
def both(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("looks")
    return {look: make_dataset(root / look, f"referent={WORLD}", "n=1", "image_size=64", f"look={look}") for look in (FAST, FULL)}


def test_the_full_look_changes_the_pictures_and_nothing_else(both: dict[str, Path]) -> None:
    fast, full = (LeRobotDataset(f"local/{look}", root=both[look]) for look in (FAST, FULL))
    assert len(fast) == len(full)
    for key in (ACTION_KEY, STATE_KEY):
        assert np.array_equal(np.stack(fast.hf_dataset[key]), np.stack(full.hf_dataset[key])), f"{key} differs between looks"
    agentview = LIBERO.image_keys[0]
    differs = float((fast[0][agentview] - full[0][agentview]).abs().mean()) * 255
    assert differs > 0.5, f"the looks' first agentview frames differ by only {differs:.2f}/255: look=full was not drawn"


def test_the_full_look_is_recorded_wherever_the_dataset_is_rebuilt(both: dict[str, Path]) -> None:
    generation = json.loads((both[FULL] / "meta/generation.json").read_text())
    assert generation["run"]["look"] == FULL and generation["config"]["look"] == FULL
    assert "look=full" in (both[FULL] / "README.md").read_text()  # the card's regenerating command and exam's
    assert all(spec.setup.look == FULL for spec in scenes.specs(both[FULL]))
    assert "look" not in json.loads(scenes.read(both[FAST])["spec"].iloc[0])["sim"]  # fast specs keep their old JSON


def test_an_exam_and_a_canonical_exam_replay_in_their_look(tmp_path: Path) -> None:
    exam = tmp_path / "exam"
    make_dataset(exam, f"referent={WORLD}", "n=1", "image_size=32", "split=exam", "look=full")
    env = ExamEnv(exam, row=0)
    assert env.scene.look == FULL and env.cameras.scene is env.scene
    build(CanonicalOptions(world=WORLD, states=1, tasks=1, image_size=32, out=str(tmp_path / "canonical"), look=FULL))
    specs = [EpisodeSpec.from_json(s) for s in read(tmp_path / "canonical").trials["spec"]]
    assert specs and all(spec_scene(spec).look == FULL for spec in specs)


def test_an_unknown_look_is_refused_in_one_line() -> None:
    with pytest.raises(UserError, match="look must be one of fast, full, got 'shiny'"):
        parse([f"referent={WORLD}", "look=shiny"])
