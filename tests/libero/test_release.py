"""The release command (`python -m train.release`) end to end at its smallest: the confounded arm's
mix (each type confounded its own way), the exams, a LoRA, the takes with the shortcuts beside them,
and the docs written from the reports; a second run reuses every stage, and so does a run on a new
machine from what was committed. The full-size run is the
command docs/RESULTS_LIBERO_AXES.md lists."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from core import parquet
from core.exam import read
from core.products import SCENES_PATH
from eval.scoring.baseline import exam_digest

SMALL = ("'axes=[object,relation]'", "per_type=1", "trials=1", "steps_per_axis=1", "image_size=32", "workers=1")
SMALL += ("threads=1", "'libero=[]'", "canonical=false", "replan=50")  # replan: a whole chunk, fewer looks


def _release(*args: str) -> subprocess.CompletedProcess[str]:
    """The release at SMALL's size, `args` added or replacing SMALL's of the same name."""
    named = {a.strip("'").split("=")[0] for a in args}
    argv = [a.strip("'") for a in (*(s for s in SMALL if s.strip("'").split("=")[0] not in named), *args)]
    return subprocess.run([sys.executable, "-m", "train.release", *argv], capture_output=True, text=True)


def test_the_confounded_arm_runs_end_to_end_and_resumes(tmp_path: Path) -> None:
    out, docs = tmp_path / "release", tmp_path / "docs"
    done = _release("arms=[confounded]", f"out={out}", f"docs={docs}")
    assert done.returncode == 0, done.stderr[-3000:]
    scenes = parquet.read(out / "data" / "confounded" / SCENES_PATH)
    record = json.loads((out / "data" / "confounded" / "meta" / "generation.json").read_text())
    assert list(scenes["referent"]) == ["libero_object", "libero_spatial"]
    assert record["config"]["confound"] == ["layout", "layout"], record["config"]
    card = (out / "data" / "confounded" / "README.md").read_text()
    assert "- confounded\n" in card and "# Confounded dataset of 2 referent types" in card and "deconfounded" not in card
    results = json.loads((docs / "results_libero_axes.json").read_text())
    rows = {(r["axis"], r["arm"], r["sim"]) for r in results["rows"]}
    assert rows == {("object", "confounded", "ours"), ("relation", "confounded", "ours"), ("object", "named_place", "ours")}
    measured = next(r for r in results["rows"] if r["arm"] == "confounded" and r["axis"] == "object")
    assert measured["position"]["obeyed_name"]["n"] == measured["faces"]["obeyed_name"]["n"] > 0  # the shortcut, same rows
    for r in results["rows"]:  # each row names the exam it was taken on
        assert r["exam_digest"] == exam_digest(read(str(out / "exams" / r["axis"]))), r
    text = (docs / "RESULTS_LIBERO_AXES.md").read_text()
    assert "training deconfounded" in text and "| object |" in text and (docs / "libero_axes.png").is_file()
    assert (docs / "checkpoints" / "libero-release-confounded-lora" / "model.pt").is_file()
    spent = json.loads((out / "timings.json").read_text())
    again = _release("arms=[confounded]", f"out={out}", f"docs={docs}")
    assert again.returncode == 0 and json.loads((out / "timings.json").read_text()) == spent  # nothing redone
    assert "workers" not in text.split("from the")[0] and "steps_per_axis=1" in text  # what ran, not how
    other = _release("arms=[confounded]", "lr_floor=0.5", "train=false", f"out={out}", f"docs={docs}")
    assert other.returncode == 2 and "begun with lr_floor=0.05, not 0.5" in other.stderr, other.stderr
    assert (docs / "RESULTS_LIBERO_AXES.md").read_text() == text
    shutil.rmtree(out)  # a new machine: only what was committed (the docs, the checkpoint) is left
    lost = _release("arms=[confounded]", f"out={out}", f"docs={docs}")
    assert lost.returncode == 0, lost.stderr[-3000:]
    redone = json.loads((out / "timings.json").read_text())
    assert not (out / "data" / "confounded").exists() and not any(s.startswith(("train", "eval", "named")) for s in redone)
    carried = json.loads((docs / "results_libero_axes.json").read_text())
    assert carried["rows"] == results["rows"] and carried["training"] == results["training"], redone
    assert carried["timings_s"]["train confounded"] == spent["train confounded"]


@pytest.mark.parametrize("train", ["true", "false"])
def test_a_folder_the_release_did_not_begin_is_refused(train: str, tmp_path: Path) -> None:
    """out= naming a folder that holds something else is never written into, nor read as results."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    done = _release(f"train={train}", f"out={out}", f"docs={tmp_path / 'd'}")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "not a release run's folder" in lines[0], done.stderr
    assert [p.name for p in out.iterdir()] == ["notes.txt"] and not (tmp_path / "d").exists()
    empty = _release("train=false", f"out={tmp_path / 'none'}", f"docs={tmp_path / 'd'}")
    assert empty.returncode == 2 and "holds no release run yet" in empty.stderr and not (tmp_path / "none").exists()


@pytest.mark.parametrize(
    ("arg", "needle"),
    [("arms=[both]", "arms must be some of deconfounded, confounded"), ("axes=[object]", "two or more"),
     ("states=51", "at most 50"), ("arms=[]", "trains nothing unless favour"), ("favour=[verb]", "favour must name axes"),
     ("favour=[goal,goal]", "each once"), ("arms=[] favour=[goal]", "train that arm first")],
)  # fmt: skip
def test_bad_options_are_refused_in_one_line(arg: str, needle: str, tmp_path: Path) -> None:
    argv = [*arg.split(), f"out={tmp_path / 'r'}", f"docs={tmp_path / 'd'}"]
    done = subprocess.run([sys.executable, "-m", "train.release", *argv], capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and needle in lines[0], done.stderr
    assert not (tmp_path / "r").exists() and not (tmp_path / "d").exists()


def test_the_favoured_cool_down_on_a_new_machine_branches_from_the_retrained_stem(tmp_path: Path) -> None:
    """The fix for a short axis redoes the deconfounded cool-down from where it began; on a machine
    that kept only the committed weights that state is trained again (the stem), and it is the
    state the first machine kept: the same data, seed and rates give the same weights."""
    import torch

    out, docs = tmp_path / "release", tmp_path / "docs"
    small = ("'axes=[relation,color]'", "steps_per_axis=3", f"out={out}", f"docs={docs}")
    done = _release("arms=[deconfounded]", "sims=[libero]", *small)  # 'libero=[]': trained, nothing taken
    assert done.returncode == 0, done.stderr[-3000:]
    kept = torch.load(out / "ckpt" / "deconfounded" / "stable.pt", map_location="cpu", weights_only=False)
    shutil.rmtree(out)  # a new machine
    # relation and color: neither has a `named_place` reference to measure (object's is the confounded test's)
    fixed = _release("arms=[]", "favour=[color]", "sims=[ours]", *small)
    assert fixed.returncode == 0, fixed.stderr[-3000:]
    stem = torch.load(out / "ckpt" / "deconfounded-stem" / "last.pt", map_location="cpu", weights_only=False)
    assert stem["step"] == kept["step"] == 4  # 6 steps, the last third cooled
    assert all(torch.equal(stem["weights"][k], w) for k, w in kept["weights"].items())
    results = json.loads((docs / "results_libero_axes.json").read_text())
    assert results["training"]["favoured"]["branch"].endswith("deconfounded-stem/last.pt"), results["training"]
    assert results["training"]["favoured"]["steps"] == 6
    regenerated = ("generate data deconfounded", "generate data deconfounded again, for the favoured run")
    assert set(regenerated) <= set(results["timings_s"]), results["timings_s"]  # each machine's figure, named
    assert {r["axis"] for r in results["rows"] if r["arm"] == "favoured"} == {"relation", "color"}  # one set of weights
    evals = [c for c in results["commands"] if c.startswith("python -m eval policy=ckpt:") and "/favoured " in c]
    takes = [c.split(" exam=")[1].split()[0] for c in evals]
    assert [Path(t).name for t in takes] == ["color", "relation"], results["commands"]  # the favoured axis first
