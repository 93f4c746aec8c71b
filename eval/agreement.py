"""Does a policy do the same in our rebuild of a LIBERO world as in LIBERO's own simulator?

    python -m eval.agreement exam=<exam> ours=<report folder> libero=<report folder> [out=<json>]

Takes two takes of one exam by one policy, one in our simulator and one with `sim=libero` (their
`rollouts.parquet`), and says, per face, the rate in each (with the interval that resamples
trials) and, rollout by rollout from the same initial state, how often the two agree: a swap row
lands on the same alternative (or on none in both), a task, occ or nonsense row has the same
outcome. It also counts how often LIBERO's own verdict on a row (`sim_success`, its `In`/`On`
predicates) agrees with our scorer's on the same LIBERO rollout.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from core.exam import Exam, ExamError, read
from core.products import ROLLOUTS
from core.rates import Rate
from eval.score import SIM_SUCCESS, LogError, clustered_rate, judge, landed, parsed_logs, read_logs, score
from jobs.cli import UserError, main

FACES = ("task", "obeyed_name", "true_target", "swap_success", "occ", "nonsense", "switch_obeyed", "switch_blind")


def outcomes(exam: Exam, logs: pd.DataFrame) -> tuple[dict[int, object], dict[int, bool]]:
    """row -> what the rollout did (the alternative a swap row landed on, None for none; whether a
    task, occ or nonsense row achieved its ask), and row -> whether our scorer says it achieved its ask."""
    parsed, did, achieved = parsed_logs(logs, exam), {}, {}
    for _, row in exam.trials.iterrows():
        r = int(row["row"])
        ee, objects, error, *_ = parsed[r]
        judged = judge(exam, row, ee, objects)
        achieved[r] = not error and judged[(row["target"], row["program"])]["achieved"]
        did[r] = (None if error else landed(judged)) if row["face"] == "swap" else achieved[r]
    return did, achieved


def compare(exam: Exam, ours_logs: pd.DataFrame, libero_logs: pd.DataFrame, policy: str) -> dict:
    """Both takes' faces, and the rollout-by-rollout agreement between them, over the rows both took."""
    both = set(ours_logs["row"]) & set(libero_logs["row"])
    exam = dataclasses.replace(exam, trials=exam.trials[exam.trials["row"].isin(both)].reset_index(drop=True))
    ours_logs, libero_logs = (logs[logs["row"].isin(both)].reset_index(drop=True) for logs in (ours_logs, libero_logs))
    ours, theirs = score(exam, ours_logs, policy), score(exam, libero_logs, policy)
    (a, _), (b, achieved) = outcomes(exam, ours_logs), outcomes(exam, libero_logs)
    trial = dict(zip(exam.trials["row"].astype(int), exam.trials["trial"].astype(int)))
    face = dict(zip(exam.trials["row"].astype(int), exam.trials["face"]))
    paired = {}
    for kind, rows in (("swap", [r for r in a if face[r] == "swap"]), ("task", [r for r in a if face[r] == "task"])):
        same = [float(a[r] == b[r]) for r in rows]
        paired[kind] = clustered_rate(same, [trial[r] for r in rows]) if rows else {}
    checks = {}
    if SIM_SUCCESS in libero_logs:
        verdicts = dict(zip(libero_logs["row"].astype(int), libero_logs[SIM_SUCCESS]))
        judged = [r for r in achieved if verdicts[r] is not None and not pd.isna(verdicts[r])]
        agree = [float(bool(verdicts[r]) == achieved[r]) for r in judged]
        checks = Rate(sum(agree), len(agree)).to_dict()
    return {
        "policy": policy,
        "exam": ours["exam"],
        "faces": {f: {"ours": ours["faces"][f], "libero": theirs["faces"][f]} for f in FACES if f in ours["faces"]},
        "sim_success": theirs.get("sim_success", {}),
        "paired": paired,
        "libero_check_agrees_with_ours": checks,
    }


def lines(result: dict) -> list[str]:
    """The comparison as a few lines of text."""

    def rate(r: dict) -> str:
        lo, hi = r["ci_trials"]
        return f"{r['rate']:.1%} ({r['k']}/{r['n']}; {lo:.0%}-{hi:.0%})"

    out = [f"{result['policy']} on {result['exam']}: ours | LIBERO's own simulator"]
    out += [f"  {f:<12} {rate(v['ours']):<28} {rate(v['libero'])}" for f, v in result["faces"].items()]
    for kind, r in result["paired"].items():
        if r:
            what = "landed on the same alternative" if kind == "swap" else "the same task outcome"
            out.append(f"  paired {kind} rows, {what}: {rate(r)}")
    if result["libero_check_agrees_with_ours"]:
        c = result["libero_check_agrees_with_ours"]
        out.append(f"  LIBERO's own predicates agree with our scorer's success on {c['k']}/{c['n']} of its rollouts")
    return out


@dataclass
class AgreementOptions:
    exam: str  # the exam both takes took
    ours: str  # the report folder of the take in our simulator (its rollouts.parquet)
    libero: str  # the report folder of the take with sim=libero
    out: str | None = None  # write the comparison (JSON) here


def run(options: AgreementOptions) -> None:
    try:
        exam = read(options.exam)
        ours, policy = read_logs(Path(options.ours) / ROLLOUTS)
        theirs, _ = read_logs(Path(options.libero) / ROLLOUTS)
        result = compare(exam, ours, theirs, policy or "unknown")
    except (ExamError, LogError) as exc:
        raise UserError(str(exc)) from None
    print("\n".join(lines(result)))
    if options.out:
        Path(options.out).write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    sys.exit(main("python -m eval.agreement", AgreementOptions, run, doc=__doc__))
