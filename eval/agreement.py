"""Does a policy do the same in our rebuild of a LIBERO world as in LIBERO's own simulator?

    python -m eval.agreement exam=<exam> ours=<report folder> libero=<report folder> [out=<json>] [overwrite=true]

Takes two takes of one exam by one policy, one in our simulator and one with `sim=libero` (their
`rollouts.parquet`), and says, per face, the rate in each (with the interval that resamples
trials) and, rollout by rollout from the same initial state, how often the two agree: a swap row
lands on the same alternative (or on none in both), a task, occ or nonsense row has the same
outcome. It also counts how often LIBERO's own verdict on a row (`sim_success`, its `In`/`On`
predicates) agrees with our scorer's on the same LIBERO rollout.

Before anything is computed it checks, from what each take recorded (its rollouts.parquet's
metadata, else its report.json), that the two are what they claim, and refuses in one line (exit 2)
otherwise: `ours` must have run in our simulator and `libero` in LIBERO's (`simulator`), they must
be two folders, by the same policy, and both of the given exam (the digest of its files, which
takes record since `exam_digest` existed). A take from before then is accepted with a warning
(on stderr): each of its rows' initial state is still checked against the exam's, but not that it
is the same exam; retake it for that. `out=` is checked first too: a file there is replaced only
with `overwrite=true`, and never one of the takes' own files.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from core.exam import Exam, ExamError, read
from core.products import REPORTS, ROLLOUTS
from core.rates import Rate
from eval.scoring.baseline import exam_digest
from eval.scoring.score import clustered_rate, judge, landed, parsed_logs, score
from eval.sims.log import SIM_SUCCESS, LogError, read_logs
from jobs.cli import UserError, main
from jobs.output import check_writable

FACES = ("task", "obeyed_name", "true_target", "swap_success", "occ", "nonsense", "switch_obeyed", "switch_blind")


def outcomes(exam: Exam, logs: pd.DataFrame) -> tuple[dict[int, object], dict[int, bool]]:
    """row -> what the rollout did (the alternative a swap row landed on, None for none; whether a
    task, occ or nonsense row achieved its ask), and row -> whether our scorer says it achieved its ask."""
    parsed, did, achieved = parsed_logs(logs, exam), {}, {}
    for _, row in exam.trials.iterrows():
        r = int(row["row"])
        log = parsed[r]
        judged = judge(exam, row, log.ee, log.objects, turns=log.turns)
        achieved[r] = not log.error and judged[(row["target"], row["program"])]["achieved"]
        did[r] = (None if log.error else landed(judged)) if row["face"] == "swap" else achieved[r]
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
        "simulator_versions": {"ours": ours["simulator_versions"], "libero": theirs["simulator_versions"]},
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
    ran = {k: ", ".join(f"{p} {v}" for p, v in got.items()) or "not recorded" for k, got in result["simulator_versions"].items()}
    out.append(f"  ran on: {ran['ours']} | {ran['libero']}")
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
    overwrite: bool = False  # replace the file already at `out`


def check_out(out: Path, overwrite: bool, takes: list[Path]) -> None:
    """Before anything is computed: `out` must be a file that can be written, not an existing one
    unless `overwrite`, and never one of the takes' own files (their reports and logs)."""
    if out.is_dir():
        raise UserError(f"out={out} is a folder; name the JSON file to write (e.g. out={out / 'agreement.json'})")
    own = {(take / name).resolve() for take in takes for name in (*REPORTS, ROLLOUTS)}
    if out.resolve() in own:
        raise UserError(f"out={out} is one of the takes' own files, which the comparison would replace: choose another out")
    if out.exists() and not overwrite:
        raise UserError(f"out={out} already exists; pass overwrite=true to replace it, or choose another out")
    check_writable(out)


class Take:
    """What a take's folder records about itself: its logs, and who took it, where and on which exam."""

    def __init__(self, option: str, folder: Path) -> None:
        self.option, self.folder = option, folder
        self.logs, policy = read_logs(folder / ROLLOUTS)
        try:  # what the report says, for anything its rollouts.parquet does not record
            report = json.loads((folder / "report.json").read_text())
        except (OSError, ValueError):
            report = {}
        report = report if isinstance(report, dict) else {}
        self.policy = policy or report.get("policy")
        self.sim = self.logs.attrs.get("sim") or report.get("simulator")
        self.exam = self.logs.attrs.get("exam_digest") or report.get("exam_digest")


def check_takes(exam: Exam, ours: Take, libero: Take) -> list[str]:
    """Refuse (UserError) two takes that are not this exam's take in our simulator and in LIBERO's by
    one policy; returns the warnings for takes that predate the exam digest."""
    if ours.folder.resolve() == libero.folder.resolve():
        raise UserError(f"ours= and libero= are the same folder ({ours.folder}): give the take in each simulator")
    for take, wanted in ((ours, "ours"), (libero, "libero")):
        if take.sim != wanted:
            where = f"ran in simulator {take.sim!r}" if take.sim and take.sim != "not recorded" else "records no simulator"
            hint = " (are ours= and libero= swapped?)" if take.sim in ("ours", "libero") else ""
            raise UserError(f"{take.option}={take.folder} {where}, not {wanted!r}: give a take with sim={wanted}{hint}")
    for take in (ours, libero):
        if not take.policy:
            raise UserError(f"{take.option}={take.folder} records no policy; retake it with python -m eval")
    if ours.policy != libero.policy:
        raise UserError(
            f"the takes are by different policies (ours={ours.policy!r}, libero={libero.policy!r}): compare one policy's takes"
        )
    digest, warnings = exam_digest(exam), []
    for take in (ours, libero):
        if take.exam is None:
            warnings.append(
                f"warning: {take.option}={take.folder} does not record which exam it took (taken before takes recorded it): "
                f"its rows start as exam={exam.root}'s do, but only a retake shows it is that exam"
            )
        elif take.exam != digest:
            raise UserError(
                f"{take.option}={take.folder} was taken on another exam (digest {take.exam[:12]}, exam={exam.root} is "
                f"{digest[:12]}): give takes of this exam"
            )
    return warnings


def run(options: AgreementOptions) -> None:
    out = Path(options.out) if options.out else None
    if out is not None:
        check_out(out, options.overwrite, [Path(options.ours), Path(options.libero)])
    try:
        exam = read(options.exam)
        ours, libero = Take("ours", Path(options.ours)), Take("libero", Path(options.libero))
        for warning in check_takes(exam, ours, libero):
            print(warning, file=sys.stderr)
        result = compare(exam, ours.logs, libero.logs, ours.policy)
    except (ExamError, LogError) as exc:
        raise UserError(str(exc)) from None
    print("\n".join(lines(result)))
    if out is not None:
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            staged = out.with_name(f".{out.name}.tmp")
            staged.write_text(json.dumps(result, indent=2))
            staged.replace(out)
        except OSError as exc:
            raise UserError(f"cannot write out={out} ({exc.strerror or exc})") from None
        print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main("python -m eval.agreement", AgreementOptions, run, doc=__doc__))
