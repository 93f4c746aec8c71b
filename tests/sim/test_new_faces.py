"""The two faces no benchmark measured before.

Switch: the instruction replaced mid-course, after the approach has committed, by one naming
another object. The oracle replans at the switch and goes to the newly named one; the `position`
shortcut, and a policy that reads the instruction only at step 0, go on as they started. The
schedule is in the exam: `trials.parquet` gives the step and the new instruction, the runner and
the gymnasium env show it from that step on, and a step outside the row's horizon is refused in
one line. A switch row's horizon counts from its switch, and the builder keeps one only where the
oracle finishes it, saying in exam.json why a trial has none.

Prediction: a policy's first predicted point, judged by the exam's segmentation of the first
frame: the oracle's (the object its plan acts on) follows the renamed object, `position`'s does
not; a prediction of the wrong shape breaks its rollout by name, a log's is refused in one line,
and an exam made before the maps says its predictions went unscored."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pandas as pd
import pytest

from core.exam import FRAME_OBJECTS, NO_SWITCH, SWITCH, ExamError, read
from core.spec import EpisodeSpec
from eval.policies import Context, Oracle
from eval.policies.registry import make
from eval.scoring.battery import take
from eval.scoring.score import score
from eval.sims.log import LogError
from helpers import make_dataset, rows_of


class FirstInstruction(Oracle):
    """Reads the instruction at step 0 only: does what it first said, whatever it says later."""

    def reset(self, context: Context) -> None:
        if context.switch is not None:  # what it was shown at step 0: the original ask
            context = dataclasses.replace(context, target=context.spec.target, program=context.spec.task.program, switch=None)
        super().reset(context)


@pytest.fixture(scope="module")
def exam(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 trials, a switch row to each of the 3 other objects: a blind policy's switch rows then land
    where its swaps do, so its two rates are equal, not only equal on average. 64 px: every
    object covers pixels of the first frame."""
    args = ("n=4", "split=exam", "seed=4", "image_size=64", "workers=1", "switches=3")
    return make_dataset(tmp_path_factory.mktemp("switch") / "exam", *args)


@pytest.fixture(scope="module")
def reports(exam: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict]:
    taken, out = read(exam), tmp_path_factory.mktemp("takes")
    policies = (("oracle", make("oracle")), ("position", make("position")), ("first", FirstInstruction()))
    # the rows of the faces the tests read of each (the oracle's prediction on task and occ rows too)
    read_of = {"oracle": ["task", "occ", "swap", "switch"], "position": ["swap", "switch"], "first": ["swap", "switch"]}
    return {name: take(taken, rows_of(taken, read_of[name]), policy, out / name, baseline=False)[0] for name, policy in policies}


def test_the_oracle_replans_at_the_switch_and_the_blind_go_on(exam: Path, reports: dict[str, dict]) -> None:
    switched = read(exam).trials.query("face == 'switch'")
    assert len(switched) == 12 and all(json.loads(s)["step"] > 0 for s in switched[SWITCH])
    faces = {name: report["faces"] for name, report in reports.items()}
    assert faces["oracle"]["switch_obeyed"]["rate"] >= 0.95 and faces["oracle"]["switch_blind"]["k"] == 0
    for blind in ("position", "first"):
        assert faces[blind]["switch_obeyed"]["rate"] <= faces[blind]["obeyed_name"]["rate"], blind
    assert faces["first"]["switch_obeyed"]["k"] == 0 and faces["first"]["switch_blind"]["rate"] == 1.0
    assert faces["first"]["obeyed_name"]["rate"] == 1.0  # it reads the words: only what it was shown first


def test_a_switch_rows_horizon_counts_from_the_switch(exam: Path) -> None:
    trials = read(exam).trials
    horizon = dict(zip(trials.query("face == 'task'")["trial"], trials.query("face == 'task'")["max_steps"]))
    for _, row in trials.query("face == 'switch'").iterrows():
        assert row["max_steps"] == json.loads(row[SWITCH])["step"] + horizon[row["trial"]]


def test_every_trial_has_its_switch_row_or_says_why_and_the_oracle_finishes_each(tmp_path: Path) -> None:
    """Seed 31: before the switch came where the hand takes hold and a changed course rose over the
    objects first, the oracle missed one of its six switches; now each trial has its switch row or a
    reason in exam.json, and the oracle achieves every switch the exam keeps."""
    root = make_dataset(tmp_path / "exam", "n=6", "split=exam", "seed=31", "image_size=32", "workers=1")
    built = read(root)
    switched = set(built.trials.query("face == 'switch'")["trial"])
    without = {int(t) for t in built.meta.get(NO_SWITCH, {})}
    assert switched | without == set(built.trials["trial"]) and not switched & without and len(switched) >= 5
    report, _ = take(built, rows_of(built, ["switch"]), make("oracle"), tmp_path / "oracle", baseline=False)
    assert report["faces"]["switch_obeyed"]["k"] == report["faces"]["switch_obeyed"]["n"] == len(switched)


def test_a_switch_the_oracle_cannot_finish_is_left_out_saying_why(exam: Path) -> None:
    """The trial's first switch names an object set out of the arm's reach: the oracle cannot
    achieve it, switched or not, so the builder keeps no such row and says so."""
    import numpy as np

    from gen.products.exam import switch_rows
    from oracle.ik import ArmIK
    from oracle.scene import Scene
    from referents import registry

    row = read(exam).trials.query("face == 'task' and trial == 0").iloc[0]
    spec = EpisodeSpec.from_json(row["spec"])
    away = spec.choice(spec.counterfactuals[0])[0]
    objects = tuple(dataclasses.replace(o, pos=(o.pos[0] + 1.5, *o.pos[1:])) if o.id == away else o for o in spec.objects)
    moved = dataclasses.replace(spec, objects=objects)
    scene, ik = (
        Scene(moved.assets, moved.setup.profile, moved.setup.world),
        ArmIK(np.asarray(moved.setup.robot_home), moved.setup.world),
    )
    scene.reset(moved)
    state = scene.physics_state().astype(np.float64).tolist()
    kept, why = switch_rows(scene, ik, registry.load(moved.referent, world=moved.setup.world), moved, state, 0, 1)
    assert kept == () and "the oracle does not achieve" in why and "switched or not" in why, why


def test_the_gymnasium_env_shows_the_new_instruction_from_the_switch_step(exam: Path) -> None:
    import gymnasium as gym

    row = read(exam).trials.query("face == 'switch'").iloc[0]
    switch = json.loads(row[SWITCH])
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=str(exam), row=int(row["row"]))
    _, info = env.reset()
    hold = env.unwrapped.features.hold_action(env.unwrapped.episode.setup.robot_home)
    seen = [info["instruction"]]
    for _ in range(switch["step"] + 1):
        _, _, _, _, info = env.step(hold)
        seen.append(info["instruction"])
    env.close()
    assert seen[: switch["step"]] == [row["instruction"]] * switch["step"]
    assert seen[switch["step"] :] == [switch["instruction"]] * 2


def test_an_exam_without_switch_rows_still_loads_and_a_late_switch_is_refused(exam: Path, tmp_path: Path) -> None:
    old = make_dataset(tmp_path / "old", "n=1", "split=exam", "seed=4", "image_size=32", "workers=1", "switches=0")
    assert SWITCH not in pd.read_parquet(old / "trials.parquet").columns and read(old).trials[SWITCH].eq("{}").all()
    late = tmp_path / "late"
    late.mkdir()
    for name in ("exam.json", "answers.parquet"):
        (late / name).write_bytes((exam / name).read_bytes())
    trials = pd.read_parquet(exam / "trials.parquet")
    at = trials.index[trials[SWITCH] != "{}"][0]
    trials.loc[at, SWITCH] = json.dumps({"step": int(trials.loc[at, "max_steps"]) + 5, "instruction": "lift the lemon"})
    trials.to_parquet(late / "trials.parquet")
    with pytest.raises(ExamError, match=r"switches its instruction at step \d+, outside its 1\.\.\d+ steps"):
        read(late)


def test_the_predicted_point_follows_the_renamed_object_for_the_oracle_and_not_for_position(reports: dict[str, dict]) -> None:
    oracle, position = reports["oracle"]["prediction"], reports["position"]["prediction"]
    assert oracle["name"]["rate"] == 1.0 and oracle["original"]["k"] == 0 and oracle["task"]["rate"] == 1.0
    assert oracle["occ"]["rate"] == 1.0  # it reads no camera: blanking them cannot move its point
    assert oracle["name"]["n"] == 12 and 0 < oracle["name"]["chance"] < 1
    assert position["name"]["rate"] < oracle["name"]["rate"]
    assert position["name"]["rate"] == reports["position"]["faces"]["obeyed_name"]["rate"]  # it points where it goes


class WrongShape(Oracle):
    def predicted(self) -> list[float]:
        return [1.0, 2.0, 3.0]


def test_a_prediction_of_the_wrong_shape_breaks_its_rollout_by_name_and_a_log_of_one_is_refused(
    exam: Path, reports: dict[str, dict], tmp_path: Path
) -> None:
    taken = read(exam)
    rows = taken.trials.head(2)
    report = take(taken, rows, WrongShape(), tmp_path / "wrong", baseline=False)[0]
    assert [e["row"] for e in report["errors"]] == [0, 1]
    assert "step 0: prediction has shape (3,): expected a point [column, row] (2,)" in report["errors"][0]["error"]
    assert report["faces"]["task"]["k"] == 0
    logs = pd.read_parquet(tmp_path / "wrong" / "rollouts.parquet")
    logs["predicted"] = [[1.0, 2.0, 3.0]] * len(logs)
    with pytest.raises(LogError, match=r"row 0: column 'predicted' must hold 2 finite numbers or null"):
        score(dataclasses.replace(taken, trials=rows.reset_index(drop=True)), logs, "wrong")


class BrokenReset(Oracle):
    def reset(self, context: Context) -> None:
        raise RuntimeError("no weights here")


def test_a_rollout_broken_before_its_first_step_is_an_error_in_the_report_not_a_crash(exam: Path, tmp_path: Path) -> None:
    """A policy whose reset fails (or a simulator that cannot start the row) logs no step; the
    report still comes out, the row failed and named (a long run must not lose its report)."""
    taken = read(exam)
    rows = taken.trials.head(2)
    report = take(taken, rows, BrokenReset(), tmp_path / "broken", baseline=False)[0]
    assert [e["row"] for e in report["errors"]] == [0, 1]
    assert report["errors"][0]["error"] == "policy reset failed: RuntimeError: no weights here"
    assert report["faces"]["task"]["k"] == 0


def test_an_exam_made_before_the_maps_says_its_predictions_went_unscored(exam: Path, tmp_path: Path) -> None:
    old = tmp_path / "old"
    old.mkdir()
    for name in ("exam.json", "trials.parquet"):
        (old / name).write_bytes((exam / name).read_bytes())
    pd.read_parquet(exam / "answers.parquet").drop(columns=[FRAME_OBJECTS]).to_parquet(old / "answers.parquet")
    report = take(read(old), read(old).trials.head(3), make("oracle"), tmp_path / "take", baseline=False)[0]
    assert "make the exam again" in report["prediction"]["unscored"] and report["faces"]["task"]["k"] == 1


def test_the_switch_picture_shows_each_policy_on_the_same_switch_row(exam: Path, tmp_path: Path) -> None:
    """scripts/switch_picture.py (Figure 9's illustration): a row of frames per policy, the same switch
    row for both, each judged beside its row; a row that is not a switch row is one line."""
    import subprocess
    import sys

    import numpy as np
    from PIL import Image

    script = Path(__file__).resolve().parents[2] / "scripts" / "switch_picture.py"
    out = tmp_path / "switch.png"
    args = [sys.executable, str(script), f"exam={exam}", "policies=[oracle,position]", f"out={out}"]
    done = subprocess.run(args, capture_output=True, text=True)
    assert done.returncode == 0 and out.is_file(), done.stderr[-2000:]
    picture = np.asarray(Image.open(out).convert("L"), float)
    top, bottom = picture[: len(picture) // 2], picture[len(picture) // 2 :]
    assert top.std() > 10 and bottom.std() > 10 and not np.array_equal(top, bottom)
    task = read(exam).trials.query("face == 'task'")["row"].iloc[0]
    refused = subprocess.run([*args[:-1], f"row={task}", f"out={tmp_path / 'no.png'}"], capture_output=True, text=True)
    lines = refused.stderr.strip().splitlines()
    assert refused.returncode == 2 and len(lines) == 1 and "not a switch row" in lines[0] and not (tmp_path / "no.png").exists()
