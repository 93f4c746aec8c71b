"""The switch face: the instruction replaced mid-course, after the approach has committed, by one
naming another object. The oracle replans at the switch and goes to the newly named one; the
`position` shortcut, and a policy that reads the instruction only at step 0, go on as they
started. The schedule is in the exam: `trials.parquet` gives the step and the new instruction,
the runner and the gymnasium env show it from that step on, and a step outside the row's horizon
is refused in one line."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pandas as pd
import pytest

from core.exam import SWITCH, ExamError, read
from eval.battery import take
from eval.policies import Context, Oracle
from eval.registry import make
from helpers import make_dataset


class FirstInstruction(Oracle):
    """Reads the instruction at step 0 only: does what it first said, whatever it says later."""

    def reset(self, context: Context) -> None:
        if context.switch is not None:  # what it was shown at step 0: the original ask
            context = dataclasses.replace(context, target=context.spec.target, program=context.spec.task.program, switch=None)
        super().reset(context)


@pytest.fixture(scope="module")
def exam(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 trials, a switch row to each of the 3 other objects: a blind policy's switch rows then land
    where its swaps do, so its two rates are equal, not only equal on average."""
    args = ("n=4", "split=exam", "seed=4", "image_size=32", "workers=1", "switches=3")
    return make_dataset(tmp_path_factory.mktemp("switch") / "exam", *args)


def test_the_oracle_replans_at_the_switch_and_the_blind_go_on(exam: Path, tmp_path: Path) -> None:
    taken = read(exam)
    switched = taken.trials[taken.trials["face"] == "switch"]
    assert len(switched) == 12 and all(json.loads(s)["step"] > 0 for s in switched[SWITCH])
    faces = {}
    for name, policy in (("oracle", make("oracle")), ("position", make("position")), ("first", FirstInstruction())):
        faces[name] = take(taken, taken.trials, policy, tmp_path / name, baseline=False)[0]["faces"]
    assert faces["oracle"]["switch_obeyed"]["rate"] >= 0.95 and faces["oracle"]["switch_blind"]["k"] == 0
    for blind in ("position", "first"):
        assert faces[blind]["switch_obeyed"]["rate"] <= faces[blind]["obeyed_name"]["rate"], blind
    assert faces["first"]["switch_obeyed"]["k"] == 0 and faces["first"]["switch_blind"]["rate"] == 1.0
    assert faces["first"]["obeyed_name"]["rate"] == 1.0  # it reads the words: only what it was shown first


def test_the_gymnasium_env_shows_the_new_instruction_from_the_switch_step(exam: Path) -> None:
    import gymnasium as gym

    row = read(exam).trials.query("face == 'switch'").iloc[0]
    switch = json.loads(row[SWITCH])
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=str(exam), row=int(row["row"]))
    _, info = env.reset()
    hold = env.unwrapped.features.hold_action(env.unwrapped.episode.sim.robot_home)
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
