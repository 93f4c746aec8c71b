"""The battery's statistics as a reviewer reads them: three landing levels, intervals that
resample trials rather than rollouts, the measured shortcut beside every policy, a grounding
readout, and a report whose tables and heat map show what they claim."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from core import contact, worlds
from core.exam import Exam, read
from core.rates import Rate, cluster_ci
from core.spec import EpisodeSpec
from eval.scoring.report import html, plots
from eval.scoring.score import score
from eval.sims.log import LogError
from helpers import make_dataset

FAR = [-0.5, 0.0, 1.3]  # where the hand is when it goes nowhere: above the robot's base


@pytest.fixture(scope="module")
def exam(tmp_path_factory: pytest.TempPathFactory) -> Exam:
    root = make_dataset(tmp_path_factory.mktemp("exam") / "object-exam", "n=4", "split=exam", "seed=5", "image_size=32")
    return read(root)


def _log(row: pd.Series, mode: str, located: list[float] | None = None) -> dict:
    """A two-step rollout: the hand ends on the asked-for contact point ('achieved': and the
    object is lifted), 1 cm above it ('2cm'), 3.5 cm above it ('5cm'), or nowhere ('far')."""
    spec = EpisodeSpec.from_json(row["spec"])
    start = {o.id: np.asarray(o.pos, float) for o in spec.objects}
    end = {k: v + ([0.0, 0.0, 0.1] if mode == "achieved" and k == row["target"] else 0.0) for k, v in start.items()}
    objects = {k: np.stack([start[k], end[k]]) for k in start}
    point = _contact(spec, objects, row["target"], row["program"])
    lift = {"achieved": 0.0, "2cm": 0.01, "5cm": 0.035}
    start = list(row["initial_ee"])  # step 0: the hand where the trial starts
    ee = [start, (point + [0.0, 0.0, lift[mode]]).tolist() if mode in lift else start]
    return {
        "row": int(row["row"]),
        "steps": 1,
        "ee": ee,
        "objects": json.dumps({k: v.tolist() for k, v in objects.items()}),
        "error": None,
        "located": located,
    }


def _contact(spec: EpisodeSpec, objects: dict[str, np.ndarray], target: str, program: str) -> np.ndarray:
    """Where the oracle's hand meets `target` at the rollout's end: its grasp point, or over a destination the release point."""
    kind = worlds.kind(spec.object(target).kind, spec.setup.world)
    if program == "place":
        carried = worlds.kind(spec.object(spec.task.params["object"]).kind, spec.setup.world)
        return contact.release_point(kind, objects[target][1], carried)
    return contact.grasp_point(kind, objects[target][1])


MODES = ("achieved", "2cm", "5cm", "far")


def test_known_landings_give_known_rates_at_every_level(exam: Exam) -> None:
    swaps = exam.trials[exam.trials.face == "swap"]
    modes = {int(r): MODES[i % len(MODES)] for i, r in enumerate(swaps["row"])}
    logs = pd.DataFrame([_log(row, modes.get(int(row["row"]), "far")) for _, row in exam.trials.iterrows()])
    faces = score(exam, logs, "synthetic")["faces"]
    want = {m: sum(v == m for v in modes.values()) for m in MODES}
    obeyed = faces["obeyed_name"]["by_level"]
    assert obeyed["achieved"]["k"] == want["achieved"]
    assert obeyed["2cm"]["k"] == want["achieved"] + want["2cm"]
    assert obeyed["5cm"]["k"] == want["achieved"] + want["2cm"] + want["5cm"] == faces["obeyed_name"]["k"]
    assert all(level["n"] == len(swaps) for level in obeyed.values())
    assert faces["swap_success"]["k"] == want["achieved"] and faces["true_target"]["k"] == 0
    assert all(faces[f]["k"] == 0 for f in ("task", "occ", "nonsense"))
    for face in faces.values():
        lo, hi = face["ci_trials"]
        assert 0.0 <= lo <= face["rate"] <= hi <= 1.0


def test_the_trial_bootstrap_widens_when_one_trials_swaps_are_duplicated() -> None:
    outcomes = [1, 1, 0, 1, 0, 1, 1, 0, 1, 0, 1, 1]
    trials = [0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3]
    lo, hi = cluster_ci(outcomes, trials)
    more_outcomes, more_trials = outcomes + [0] * 9, trials + [3] * 9  # trial 3's failures, counted many times
    lo2, hi2 = cluster_ci(more_outcomes, more_trials)
    assert hi2 - lo2 > hi - lo
    wilson_lo, wilson_hi = Rate(sum(more_outcomes), len(more_outcomes)).ci
    assert hi2 - lo2 > wilson_hi - wilson_lo  # the naive interval shrinks as duplicates pile up


def test_grounding_reads_the_first_frame_prediction(exam: Exam) -> None:
    rows = []
    for i, (_, row) in enumerate(exam.trials.iterrows()):
        spec = EpisodeSpec.from_json(row["spec"])
        named = np.asarray(spec.object(row["target"]).pos)
        rows.append(_log(row, "far", located=(named + [0.01, 0.0, 0.0]).tolist() if i % 2 == 0 else FAR))
    report = score(exam, pd.DataFrame(rows), "synthetic")
    swaps = exam.trials[exam.trials.face == "swap"].reset_index(drop=True)
    g = report["grounding"]
    assert g["n"] == len(swaps)
    assert g["k"] == sum(1 for r in swaps.itertuples() if r.row % 2 == 0 or _nearest_is_target(r, FAR))


def _nearest_is_target(row: object, point: list[float]) -> bool:
    spec = EpisodeSpec.from_json(row.spec)
    nearest = min(spec.objects, key=lambda o: float(np.linalg.norm(np.subtract(o.pos, point))))
    return nearest.id == row.target


def test_html_renders_tables_and_the_heat_map_shows_zero_cells(exam: Exam) -> None:
    logs = pd.DataFrame([_log(row, "far") for _, row in exam.trials.iterrows()])
    report = score(exam, logs, "synthetic")
    page = html(report)
    assert "<table>" in page and "<pre>" not in page and "| face |" not in page
    import matplotlib.pyplot as plt

    captured = []
    original = plt.Axes.text

    def spy(self, x, y, s, *args, **kwargs):  # noqa: ANN001, ANN202
        captured.append(s)
        return original(self, x, y, s, *args, **kwargs)

    plt.Axes.text = spy
    try:
        plots(report)
    finally:
        plt.Axes.text = original
    cells = sum(len(v) for v in report["per_slot"].values())
    assert captured.count("0%") == cells  # every 0% cell is labelled, not left blank


def test_the_scorer_refuses_duplicated_rows_and_a_wrong_step_zero(exam: Exam, tmp_path: Path) -> None:
    logs = [_log(row, "far") for _, row in exam.trials.iterrows()]
    with pytest.raises(LogError, match="row 3 more than once"):
        score(exam, pd.DataFrame([*logs, logs[3]]), "synthetic")
    moved = json.loads(logs[2]["objects"])
    first = next(iter(moved))
    moved[first][0][0] += 0.03  # step 0 is not where the trial starts: a log from another state
    with pytest.raises(LogError, match=rf"row 2: step 0 is not the trial's recorded initial state \({first} is 3.0 cm"):
        score(exam, pd.DataFrame([*logs[:2], {**logs[2], "objects": json.dumps(moved)}, *logs[3:]]), "synthetic")
    swap = next(i for i, f in enumerate(exam.trials["face"]) if f == "swap")
    reached = _log(exam.trials.iloc[swap], "achieved")
    without_step_0 = {
        **reached,
        "ee": reached["ee"][1:],
        "objects": json.dumps({k: v[1:] for k, v in json.loads(reached["objects"]).items()}),
    }
    with pytest.raises(LogError, match=rf"row {swap}: step 0 is not the trial's recorded initial state \(the end effector is"):
        score(exam, pd.DataFrame([*logs[:swap], without_step_0, *logs[swap + 1 :]]), "synthetic")
    path = tmp_path / "rollouts.parquet"
    pd.DataFrame([*logs, logs[0]]).to_parquet(path)
    result = subprocess.run(
        [sys.executable, "-m", "eval.score", f"exam={exam.root}", f"logs={path}"], capture_output=True, text=True
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and "more than once" in lines[0], result.stderr


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (lambda logs: [*logs, {**logs[0], "row": 999}], "the logs hold row 999, which the exam does not have (its rows are 0.."),
        (lambda logs: [{**log, "row": str(log["row"])} for log in logs], "column 'row' must hold integers"),
        (lambda logs: [{**log, "ee": "left"} for log in logs], "column 'ee' must hold each rollout's end-effector positions"),
        (lambda logs: [{**log, "objects": 7} for log in logs], "column 'objects' must hold a JSON string"),
        (lambda logs: [{**log, "turns": 7} for log in logs], "column 'turns' must hold a JSON string"),
        (lambda logs: [{**log, "turns": json.dumps({"basket": [[1, 0, 0, 0]] * 99})} for log in logs], "one orientation per"),
    ],
)
def test_the_scorer_names_a_stray_row_or_a_column_of_the_wrong_type(exam: Exam, tmp_path: Path, change, needle: str) -> None:  # noqa: ANN001
    path = tmp_path / "rollouts.parquet"
    pd.DataFrame(change([_log(row, "far") for _, row in exam.trials.iterrows()])).to_parquet(path)
    result = subprocess.run(
        [sys.executable, "-m", "eval.score", f"exam={exam.root}", f"logs={path}"], capture_output=True, text=True
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and needle in lines[0], result.stderr
