"""The course command (`python -m train.course`) end to end at its smallest: a switched LIBERO-Object
set, the held-out exam with its switch row, a LoRA, its take with the shortcut beside it, and the
tables written between RESULTS_FACES.md's markers; a second run reuses every stage. The full-size
run is the command docs/RESULTS_FACES.md lists."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from core import parquet
from core.products import SCENES_PATH

DOCS = Path(__file__).resolve().parents[2] / "docs"
SMALL = ("shares=[0.5]", "n=2", "steps=2", "decay=1", "trials=1", "image_size=32", "workers=1", "threads=1")
SMALL += ("sims=[ours]", "exams=[exam]", "without=")


def _course(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "train.course", *SMALL, *args], capture_output=True, text=True)


def test_a_switched_share_runs_end_to_end_and_resumes(tmp_path: Path) -> None:
    out, docs = tmp_path / "course", tmp_path / "docs"
    docs.mkdir()
    page = (DOCS / "RESULTS_FACES.md").read_text()
    (docs / "RESULTS_FACES.md").write_text(page)
    done = _course(f"out={out}", f"docs={docs}")
    assert done.returncode == 0, done.stderr[-3000:]
    scenes = parquet.read(out / "data" / "switched-50" / SCENES_PATH)
    assert scenes["switch"].notna().sum() == 1  # round(0.5 x 2)
    results = json.loads((docs / "results_course.json").read_text())
    [row] = results["rows"]
    assert (row["policy"], row["share"], row["exam"], row["sim"]) == ("switched-50", 0.5, "exam", "ours")
    assert row["faces"]["switch_obeyed"]["n"] == 1 and row["position"]["obeyed_name"]["n"] == row["faces"]["obeyed_name"]["n"]
    text = (docs / "RESULTS_FACES.md").read_text()
    before, after = page.split("<!-- course:")
    assert text.startswith(before) and text.endswith(after.split("<!-- /course -->")[1])
    assert "| switched-50 |" in text and "| position |" in text
    assert (docs / "checkpoints" / "libero_object-switch-lora" / "model.pt").is_file()
    _reads_the_instruction_it_is_shown(out / "ckpt" / "switched-50")
    spent = json.loads((out / "timings.json").read_text())
    again = _course(f"out={out}", f"docs={docs}")
    assert again.returncode == 0 and json.loads((out / "timings.json").read_text()) == spent  # nothing redone
    assert (docs / "RESULTS_FACES.md").read_text() == text
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "RESULTS_FACES.md").write_text("# mine\n")  # no markers: no place for the tables
    refused = _course("train=false", f"out={out}", f"docs={mine}")
    assert refused.returncode == 2 and "markers" in refused.stderr and [p.name for p in mine.iterdir()] == ["RESULTS_FACES.md"]
    assert (mine / "RESULTS_FACES.md").read_text() == "# mine\n"
    other = _course("lr_floor=0.5", "train=false", f"out={out}", f"docs={docs}")
    assert other.returncode == 2 and "begun with lr_floor=0.05, not 0.5" in other.stderr, other.stderr


@pytest.mark.parametrize(
    ("option", "needle"),
    [({"shares": [1.5]}, "shares must be"), ({"docs": "/nowhere"}, "markers"), ({"sims": ["gazebo"]}, "sims must be"),
     ({"exams": ["final"]}, "exams must be"), ({"without": "nowhere"}, "holds no checkpoint"),
     ({"shares": [], "without": ""}, "nothing to train or take"), ({"switched_share": 1.0}, "switched_share is a share")],
)  # fmt: skip
def test_bad_options_are_refused_before_anything_is_made(option: dict, needle: str, tmp_path: Path) -> None:
    """Each is one line (a UserError: the command line prints it, exit 2) before any folder is made."""
    from jobs.cli import UserError
    from train.course import CourseOptions, course

    docs = tmp_path / "d"
    docs.mkdir()
    (docs / "RESULTS_FACES.md").write_text((DOCS / "RESULTS_FACES.md").read_text())
    chosen = CourseOptions(**({"out": str(tmp_path / "r"), "docs": str(docs)} | option))
    with pytest.raises(UserError, match=needle):
        course(chosen)
    assert not (tmp_path / "r").exists() and [p.name for p in docs.iterdir()] == ["RESULTS_FACES.md"]


def _reads_the_instruction_it_is_shown(ckpt: Path) -> None:
    """The tiny policy embeds the instruction of the observation each chunk is predicted from, so a
    switch reaches it at its next chunk (`replan` actions), not only at the row's start."""
    import numpy as np

    from core.profiles import STATE_KEY, TASK_KEY
    from train.policy import CheckpointPolicy

    policy = CheckpointPolicy(str(ckpt), replan=2)
    config = policy.model.config
    frames = {config.features.image_key(c): np.zeros((config.image_size,) * 2 + (3,), np.uint8) for c in policy.model.cameras}
    shown = []
    for said in ("pick up the ketchup and place it in the basket",) * 2 + ("pick up the milk and place it in the basket",) * 2:
        policy.act({**frames, STATE_KEY: np.zeros(policy.model.state_mean.shape, np.float32), TASK_KEY: said})
        shown.append(list(policy._embeddings))
    assert shown[1] == shown[0] == ["pick up the ketchup and place it in the basket"] and len(shown[2]) == 2
