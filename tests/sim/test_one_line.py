"""Bad input gets one line and exit 2 and writes nothing; the exam format doc says what the
files and the env hand a policy, and `trials.parquet` gives away nothing but the instruction.

Tests marked `fast` simulate nothing (`make test-fast`); the others make a small exam first."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from core import programs, worlds
from core.exam import PUBLIC_COLUMNS, SWITCH, read
from gen.config import GenConfig
from gen.planning.plan import default_setup, plan
from helpers import SMALL_EXAM, Shared
from referents import registry

ROOT = Path(__file__).resolve().parents[2]
EXAM_FORMAT_DOC = ROOT / "docs" / "EXAM_FORMAT.md"


def run(*argv: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """A command line (`gen`, `eval.score`, ...) as a user runs it."""
    env = {**os.environ, "MUJOCO_GL": "egl"}
    return subprocess.run([sys.executable, "-m", *argv], capture_output=True, text=True, env=env, cwd=cwd or ROOT)


def one_line(result: subprocess.CompletedProcess[str]) -> str:
    """The single `error: ...` line of a refused command (exit 2), without its prefix."""
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: "), (result.returncode, result.stderr)
    return lines[0].removeprefix("error: ")


def doc_section(heading: str) -> str:
    """One `## ` section of docs/EXAM_FORMAT.md, whose heading starts with `heading`."""
    sections = re.split(r"^## ", EXAM_FORMAT_DOC.read_text(), flags=re.M)
    return next(s for s in sections if s.startswith(heading))


@pytest.fixture
def kept(tmp_path: Path) -> Path:
    """A folder holding something the user cares about."""
    folder = tmp_path / "kept"
    folder.mkdir()
    (folder / "keep.txt").write_text("do not delete")
    return folder


def untouched(folder: Path) -> bool:
    return sorted(p.name for p in folder.iterdir()) == ["keep.txt"] and (folder / "keep.txt").read_text() == "do not delete"


# --- item 9: a negative seed -------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["gen", "n=2"],
        ["gen", "n=2", "plan_only=true"],
        ["gen", "n=1", "split=exam"],
        ["gen.canonical", "states=1"],
    ],
    ids=["dataset", "plan", "exam", "canonical"],
)
def test_a_negative_seed_is_one_line_and_writes_nothing(argv: list[str], tmp_path: Path) -> None:
    out = tmp_path / "new"
    line = one_line(run(*argv, "seed=-1", f"out={out}"))
    assert "seed must be a non-negative integer, got -1" in line, line
    assert not any(tmp_path.iterdir())


# --- item 10: an `out` that cannot be written --------------------------------------------------


@pytest.fixture(scope="module")
def plan_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("plan") / "object"
    assert run("gen", "n=2", "plan_only=true", f"out={out}").returncode == 0
    return out


def test_preview_refuses_a_folder_or_a_name_it_cannot_write_as_out(plan_folder: Path, kept: Path, tmp_path: Path) -> None:
    line = one_line(run("gen.preview", str(plan_folder), f"out={kept}"))
    assert f"out={kept} is a folder" in line and ".png" in line, line
    assert untouched(kept)
    line = one_line(run("gen.preview", str(plan_folder), f"out={tmp_path / 'sheet.txt'}"))
    assert "sheet.txt" in line and ".png" in line, line
    assert not (tmp_path / "sheet.txt").exists()


# --- item 15: what gen.check, objects_per_scene=, world= and --help say ------------------------


def test_check_says_a_plan_is_a_plan(plan_folder: Path) -> None:
    line = one_line(run("gen.check", str(plan_folder)))
    assert "is a plan (plan_only=true)" in line and "info.json" not in line, line


@pytest.mark.parametrize(
    ("argv", "needles"),
    [
        (
            ["referent=libero_object", "objects_per_scene=3"],
            ["objects_per_scene=3 does not fit referent libero_object", "accepted: objects_per_scene=6"],
        ),
        (
            ["referent=goal", "objects_per_scene=3"],
            ["objects_per_scene=3 does not fit referent goal", "accepted: objects_per_scene=4"],
        ),
        (
            ["spec=referents/in_worlds/libero_object/object.yaml", "world=libero_goal"],
            [
                "spec=referents/in_worlds/libero_object/object.yaml lays out scenes in world libero_object, not libero_goal",
                "leave world= out",
            ],
        ),
    ],
    ids=["libero_object", "goal", "spec-in-another-world"],
)
def test_an_option_the_referent_cannot_take_is_named_with_what_it_takes(argv: list[str], needles: list[str], kept: Path) -> None:
    line = one_line(run("gen", *argv, "n=2", f"out={kept}", "overwrite=true"))
    assert all(n in line for n in needles), line
    assert "referent object" not in line and "layout.slots" not in line, line
    assert untouched(kept)


def test_gen_help_explains_every_option() -> None:
    shown = run("gen", "--help")
    rows = {m[1]: m[2] for m in re.finditer(r"^  (\w+)=\S*(?:\s{2,}(.*))?$", shown.stdout, re.M)}
    fields = [f for f in GenConfig.__dataclass_fields__]
    assert sorted(rows) == sorted(fields), shown.stdout
    assert all(rows[f] for f in fields), [f for f in fields if not rows[f]]
    assert "libero" in rows["profile"] and "libero_goal" in rows["world"]


# --- items 14 and 15: the exam format doc ------------------------------------------------------


def test_the_exam_format_doc_has_every_program_and_every_worlds_frame() -> None:
    predicates = doc_section("Success predicates")
    assert all(f"`{program}`" in predicates for program in programs.PROGRAMS), predicates
    frames = doc_section("World frame")
    rows = {m[1]: m[2] for m in re.finditer(r"^\| `(\w+)` \| (.*) \|$", frames, re.M)}
    for name in worlds.names():
        height = f"{worlds.world(name).surface_z:g}"
        assert name in rows and re.search(rf"z = {re.escape(height)}(?![\d.])", rows[name]), (name, height)


def test_the_exam_format_doc_says_the_face_is_readable_and_achieved_is_the_answers() -> None:
    observations = doc_section("Observations and actions")
    assert "`achieved`" in observations and "reward" in observations and "never as the policy's input" in observations
    trials = doc_section("`trials.parquet`")
    assert "face of every row is readable" in trials and f"`{'xxx'}`" in trials


@pytest.mark.parametrize("name", registry.available())
def test_a_scenes_object_order_is_the_scenes_not_the_answers(name: str) -> None:
    """The objects of a trial's public scene come in slot order or in one fixed order of their
    ids, so where the target stands in the list says no more than its slot or its name."""
    referent = registry.load(name)
    scenes = [spec.public() for spec in plan(referent, 24, 0, default_setup(referent), split="exam")]
    by_slot = all([o.slot for o in s.objects] == sorted(o.slot for o in s.objects) for s in scenes)
    before = {(a.id, b.id) for s in scenes for i, a in enumerate(s.objects) for b in s.objects[i + 1 :]}
    by_id = not any((b, a) in before for a, b in before)
    assert by_slot or by_id, name


# --- the slow ones: a small exam of each program family ---------------------------------------


@pytest.fixture(scope="module")
def exams(shared: Shared) -> dict[str, Path]:
    """2-trial exams at 32 px: pick (object), place (goal) and two programs in one trial (verb)."""
    return {r: shared.dataset(f"{r}-exam", f"referent={r}", *SMALL_EXAM) for r in ("object", "goal", "verb")}


@pytest.mark.parametrize("referent", ["object", "goal", "verb"])
def test_trials_parquet_gives_away_nothing_but_the_instruction(exams: dict[str, Path], referent: str) -> None:
    """Within a trial only the instruction and the blanking differ between rows (and a switch
    row's horizon, which counts from its switch); the scene withholds every answer field, and
    nothing in it but the object list (and the inventory of kinds, the same in every trial) names
    an object."""
    trials = pd.read_parquet(exams[referent] / "trials.parquet")
    assert tuple(trials.columns) == (*PUBLIC_COLUMNS, SWITCH)
    shared = [c for c in trials.columns if c not in ("row", "instruction", "occluded", SWITCH)]
    assert trials["scene"].map(lambda s: json.dumps(json.loads(s)["assets"])).nunique() == 1  # the referent's inventory
    for _, rows in trials.groupby("trial"):
        unswitched = rows[rows[SWITCH] == "{}"]
        for column in shared:
            assert unswitched[column].map(lambda v: json.dumps(v, default=list)).nunique() == 1, column
        assert rows["occluded"].sum() == 1
        switched = [json.loads(v) for v in rows[SWITCH] if v != "{}"]  # one switch row, to a swap's instruction
        assert len(switched) == 1 and switched[0]["instruction"] in set(rows["instruction"]) - {rows["instruction"].iloc[0]}
        switch_row = rows[rows[SWITCH] != "{}"].iloc[0]
        assert switch_row["max_steps"] == switched[0]["step"] + unswitched["max_steps"].iloc[0]
        for column in set(shared) - {"max_steps"}:
            same = [json.dumps(v, default=lambda a: a.tolist()) for v in (switch_row[column], unswitched[column].iloc[0])]
            assert same[0] == same[1], column
        scene = json.loads(rows["scene"].iloc[0])
        assert (scene["target"], scene["instruction"], scene["template"], scene["counterfactuals"]) == ("", "", "", [])
        assert (scene["task"]["program"], scene["task"]["params"]) == ("", {})
        rest = json.dumps({k: v for k, v in scene.items() if k not in ("objects", "assets")})
        assert not [o["id"] for o in scene["objects"] if f'"{o["id"]}"' in rest], rest


def test_score_replaces_a_report_only_when_asked_as_eval_does(exams: dict[str, Path], tmp_path: Path) -> None:
    """One rule for `python -m eval` and `python -m eval.score`: a folder holding a report is refused
    without overwrite=true (the own-code loop scores into the logs' folder), and with it exactly the
    report files are replaced."""
    logs = nothing_logs(exams["object"], tmp_path / "rollouts.parquet")
    (tmp_path / "report.json").write_text("an earlier report")
    (tmp_path / "analysis.txt").write_text("mine")
    line = one_line(run("eval.score", f"exam={exams['object']}", f"logs={logs}"))
    assert f"out={tmp_path} already holds a report (report.json); pass overwrite=true" in line, line
    assert (tmp_path / "report.json").read_text() == "an earlier report"
    assert run("eval.score", f"exam={exams['object']}", f"logs={logs}", "policy=nothing", "overwrite=true").returncode == 0
    assert json.loads((tmp_path / "report.json").read_text())["policy"] == "nothing"
    assert (tmp_path / "analysis.txt").read_text() == "mine"


def test_score_refuses_an_out_that_is_a_file(exams: dict[str, Path], tmp_path: Path) -> None:
    logs = nothing_logs(exams["object"], tmp_path / "rollouts.parquet")
    taken = tmp_path / "report"
    taken.write_text("mine")
    line = one_line(run("eval.score", f"exam={exams['object']}", f"logs={logs}", f"out={taken}"))
    assert f"out={taken} exists and is not a folder" in line, line
    assert taken.read_text() == "mine" and sorted(p.name for p in tmp_path.iterdir()) == ["report", "rollouts.parquet"]


def test_check_says_an_exam_is_an_exam_and_what_checks_it(exams: dict[str, Path]) -> None:
    line = one_line(run("gen.check", str(exams["object"])))
    assert "is an exam" in line and "python -m eval.score" in line and "info.json" not in line, line


def test_every_key_of_the_envs_info_is_in_the_exam_format_doc(exams: dict[str, Path]) -> None:
    import gymnasium as gym
    import numpy as np

    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=str(exams["object"]), row=0)
    _, reset_info = env.reset()
    _, _, _, _, info = env.step(np.append(env.unwrapped.episode.setup.robot_home, -1.0).astype(np.float32))
    env.close()
    observations = doc_section("Observations and actions")
    assert [k for k in {*reset_info, *info} if f"`{k}`" not in observations] == []


def nothing_logs(exam: Path, path: Path) -> Path:
    """Logs of a policy that never moves: every rollout's two steps at the trial's start."""
    rows = read(exam).trials
    logs = []
    for _, row in rows.iterrows():
        scene = json.loads(row["scene"])
        objects = {o["id"]: [o["pos"], o["pos"]] for o in scene["objects"]}
        logs.append({"row": int(row["row"]), "ee": [list(row["initial_ee"])] * 2, "objects": json.dumps(objects), "error": None})
    pd.DataFrame(logs).to_parquet(path)
    return path


def test_a_canonical_exams_report_is_labelled_as_its_suites(exams: dict[str, Path], shared: Shared, tmp_path: Path) -> None:
    labels = {
        shared.canonical(): "LIBERO-Object canonical exam: LIBERO's own initial states, 1 per task",
        exams["object"]: "object-exam/seed5/2trials",
    }
    for exam, label in labels.items():
        logs = nothing_logs(exam, tmp_path / f"{exam.name}.parquet")
        out = tmp_path / f"{exam.name}-report"
        assert run("eval.score", f"exam={exam}", f"logs={logs}", f"out={out}", "policy=nothing").returncode == 0
        report = json.loads((out / "report.json").read_text())
        assert label in report["exam"] and label in (out / "report.md").read_text().splitlines()[0], report["exam"]
