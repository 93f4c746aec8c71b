"""The report read alone: what each face and the chance column count and the verdict, in its own
words; prediction rows that are no prediction (a pointer never trained) labelled so; a partial take
(`rows=N`) saying how much of the exam it covers; and a threshold sentence that says what the
landing threshold changes, with the rates at each.

The tables come from synthetic logs of a 2-trial exam (the hand put on, near or far from what a
row asks for) scored by the real scorer; the prediction and partial-take reports from takes of
7 rows (the first trial) by the `position` reference policy, which predicts."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from core import contact, worlds
from core.exam import Exam, read
from core.spec import EpisodeSpec
from eval.scoring.report import html, markdown
from eval.scoring.score import score
from helpers import SMALL_EXAM, Shared

ROOT = Path(__file__).resolve().parents[2]
UNTRAINED = "(pointer not trained: not a prediction)"


@pytest.fixture(scope="module")
def exam(shared: Shared) -> Exam:
    return read(shared.dataset("object-exam", "referent=object", *SMALL_EXAM))


def _log(row: pd.Series, mode: str) -> dict:
    """A two-step rollout whose hand ends on the asked-for contact point and lifts it ('achieved'),
    1 cm above it ('2cm'), 3.5 cm above it ('5cm') or stays where it starts ('far')."""
    spec = EpisodeSpec.from_json(row["spec"])
    start = {o.id: np.asarray(o.pos, float) for o in spec.objects}
    end = {k: v + ([0.0, 0.0, 0.1] if mode == "achieved" and k == row["target"] else 0.0) for k, v in start.items()}
    kind = worlds.kind(spec.object(row["target"]).kind, spec.setup.world)
    point = contact.grasp_point(kind, end[row["target"]])
    lift = {"achieved": 0.0, "2cm": 0.01, "5cm": 0.035}
    ee = [list(row["initial_ee"]), (point + [0.0, 0.0, lift[mode]]).tolist() if mode in lift else list(row["initial_ee"])]
    objects = {k: [start[k].tolist(), end[k].tolist()] for k in start}
    return {"row": int(row["row"]), "steps": 1, "ee": ee, "objects": json.dumps(objects), "error": None}


def scored(exam: Exam, swaps: list[str], others: str = "far") -> dict:
    """The report of logs whose swap rows do `swaps` in turn and whose other rows do `others`."""
    swap_rows = [int(r) for r in exam.trials.loc[exam.trials["face"] == "swap", "row"]]
    assert len(swap_rows) == len(swaps)
    modes = dict(zip(swap_rows, swaps))
    return score(exam, pd.DataFrame([_log(row, modes.get(int(row["row"]), others)) for _, row in exam.trials.iterrows()]), "p")


def test_the_report_says_how_to_read_it(exam: Exam) -> None:
    """6a: each face in a line, what chance counts (with this report's own number), and the verdict
    in one sentence from the numbers: against chance and against the measured shortcut."""
    far = scored(exam, ["far"] * 6)
    report = {**scored(exam, ["2cm"] * 6), "baseline": far["faces"]}
    text = markdown(report)
    assert "## How to read this" in text and "How to read this" in html(report)
    for face in report["faces"]:
        assert sum(line.startswith(f"- `{face}`: ") for line in text.splitlines()) == 1, face
    chance = report["faces"]["task"]["chance"]
    assert "one over the things it could land on" in text
    assert f"task's {chance:.0%} is about one in {1 / chance:.1f}" in text
    [verdict] = [line for line in text.splitlines() if line.startswith("Verdict: ")]
    assert "obeyed_name 100.0%" in verdict and f"above chance ({chance:.0%})" in verdict
    assert "above the shortcut's 0.0%" in verdict and "goes where the words say" in verdict
    mirror = [line for line in markdown({**report, "baseline": report["faces"]}).splitlines() if line.startswith("Verdict: ")]
    assert "not distinguishable from the shortcut's 100.0%" in mirror[0] and "does not tell it from" in mirror[0]
    nowhere = [line for line in markdown({**far, "baseline": far["faces"]}).splitlines() if line.startswith("Verdict: ")]
    assert "obeyed_name 0.0%" in nowhere[0] and "no evidence" in nowhere[0]


@pytest.fixture(scope="module")
def untrained_take(exam: Exam, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`position` (which predicts the object its plan acts on) posing as a policy whose pointer was never trained."""
    from eval.policies.registry import make
    from eval.scoring.battery import take

    policy = make("position")
    policy.prediction_trained = False
    out = tmp_path_factory.mktemp("untrained") / "take"
    take(exam, exam.trials.head(7), policy, out, baseline=False)
    return out


def test_prediction_rows_of_a_pointer_never_trained_are_labelled(untrained_take: Path) -> None:
    """6b: a policy that says its prediction head was never trained: the take records it
    (rollouts.parquet metadata and report.json `prediction_trained`) and every prediction row says so."""
    report = json.loads((untrained_take / "report.json").read_text())
    assert report["prediction_trained"] is False and "task" in report["prediction"]
    assert pq.read_schema(untrained_take / "rollouts.parquet").metadata[b"deconfound.prediction_trained"] == b"false"
    text = (untrained_take / "report.md").read_text()
    rows = [line for line in text.splitlines() if line.startswith("| prediction")]
    assert rows and all(UNTRAINED in line for line in rows), rows
    assert "pointer was never trained" in text and UNTRAINED in (untrained_take / "report.html").read_text()


@pytest.mark.parametrize(("checkpoint", "trained"), [("axes-lora", False), ("libero_object-deconfounded-lora", True)])
def test_a_checkpoint_says_whether_its_pointer_was_trained(checkpoint: str, trained: bool, monkeypatch) -> None:
    """6b: the signal is the checkpoint's own training config: point_weight > 0 trained the pointer;
    axes-lora was trained before point_weight existed (none recorded: 0), the LIBERO-Object LoRA with 1.
    (The committed records are read as they are; the model itself is not built, which takes long.)"""
    import torch

    import train.policy

    record = torch.load(ROOT / "docs" / "checkpoints" / checkpoint / "model.pt", map_location="cpu", weights_only=False)
    monkeypatch.setattr(train.policy, "load", lambda path: (SimpleNamespace(config=SimpleNamespace(chunk=10)), record))
    threads = torch.get_num_threads()
    try:
        assert train.policy.CheckpointPolicy(checkpoint).prediction_trained is trained
    finally:
        torch.set_num_threads(threads)


def test_a_partial_take_says_how_many_of_the_exams_rows_it_took(exam: Exam, tmp_path: Path, capsys) -> None:
    """6c: python -m eval ... rows=7 of a 14-row exam: report.json has the exam's total, the report's
    first line says "partial take: 7 of 14 rows"; a policy that says nothing of its pointer gets no label."""
    from eval.__main__ import EvalOptions, evaluate
    from jobs.cli import main

    out = tmp_path / "take"
    argv = ["policy=position", f"exam={exam.root}", "rows=7", f"out={out}"]
    assert main("python -m eval", EvalOptions, evaluate, argv) == 0, capsys.readouterr().err
    report = json.loads((out / "report.json").read_text())
    assert report["rollouts"] == 7 and report["exam_rollouts"] == len(exam.trials) == 14
    header = (out / "report.md").read_text().split("\n\n")[1]
    assert "partial take: 7 of 14 rows" in header, header
    assert "partial take: 7 of 14 rows" in (out / "report.html").read_text()
    assert "prediction_trained" not in report and UNTRAINED not in (out / "report.md").read_text()
    whole = markdown(scored(exam, ["far"] * 6))
    assert "partial take" not in whole


def test_the_threshold_sentence_says_what_the_threshold_changes(exam: Exam) -> None:
    """6d: "Verdict does not depend on the threshold" was printed beside 83% at 2 cm and 100% at 5 cm.
    The sentence gives the rate at each threshold and says whether the rate, and separately the
    verdict against chance, depends on it."""
    robust = scored(exam, ["2cm"] * 5 + ["5cm"])  # 5/6 within 2 cm, 6/6 within 5 cm: above chance at both
    text = markdown(robust)
    assert "Verdict does not depend on the threshold" not in text
    assert "Obeyed name is 83.3% within 2 cm and 100.0% within 5 cm: the rate depends on the threshold" in text
    assert "its verdict against chance does not (above chance at each)" in text
    assert robust["distances"]["against_chance"] == {"0.02": "above", "0.05": "above"}
    shifting = scored(exam, ["2cm"] * 2 + ["5cm"] * 4)  # 2/6 within 2 cm overlaps chance, 6/6 within 5 cm does not
    d = shifting["distances"]
    assert d["against_chance"] == {"0.02": "overlaps", "0.05": "above"} and not d["threshold_robust"]
    assert (
        "Obeyed name is 33.3% within 2 cm and 100.0% within 5 cm: the rate **and its verdict against chance depend on the "
        "threshold** (not distinguishable from chance at 2 cm, above chance at 5 cm)"
    ) in markdown(shifting)
    same = markdown(scored(exam, ["2cm"] * 6))
    assert "Obeyed name is 100.0% within 2 cm and 100.0% within 5 cm: the landing threshold does not change the rate" in same
