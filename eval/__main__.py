"""Take an exam: run every rollout with a policy, log it, score it, write the reports.

python -m eval policy=oracle exam=datasets/object-exam workers=2

Runs the exam's rollouts in our simulator (or, with sim=libero, in LIBERO's own: eval/sims/libero.py)
with the policy (oracle, position, named_place, nothing, random, remote:HOST:PORT, lerobot:PATH,
ckpt:PATH or any other registered one: eval/policies/registry.py), logs them to
`rollouts.parquet`, scores the logs with eval/scoring/score.py and writes report.json, report.md and
report.html to `out` (eval/scoring/battery.py). Every finished rollout is kept as it ends: an interrupted
take continues with resume=true.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)
from core.exam import ExamError, read
from core.profiles import LIBERO
from eval.policies import FeatureMismatch, PolicyError
from eval.policies.registry import make
from jobs.cli import Failed, UserError, main


@dataclass
class EvalOptions:
    policy: str  # oracle, position, named_place, nothing, random, remote:HOST:PORT, lerobot:PATH, ckpt:PATH (eval/policies/)
    exam: str  # the exam folder (python -m gen ... split=exam)
    out: str | None = None  # report folder; default runs/<exam folder>-<exam digest>/<policy>
    overwrite: bool = False  # replace the report at `out`, and discard an interrupted take's rollouts
    resume: bool = False  # continue an interrupted take with the same options
    rows: int | None = None  # take only the first N rollouts; default all
    workers: int = 1  # processes running rollouts (the logs are the same either way)
    keys: str = "dataset"  # remote policies: dataset (the exam's keys) | libero (what openpi's LIBERO client sends)
    replan: int | None = None  # chunking policies (ckpt, remote): actions executed per predicted chunk; default theirs
    device: str | None = None  # lerobot checkpoints: the torch device to run on (default cpu)
    sim: str = "ours"  # where the rollouts run: ours (our rebuild of the exam's world) | libero (LIBERO's own simulator)


def check_out(out: Path, overwrite: bool) -> None:
    """Before the policy loads and any rollout runs: `out` must be a folder that can be written
    (as must its parent, where the rollouts are kept), and hold no report unless `overwrite`."""
    from eval.scoring.battery import REPORT_FILES
    from eval.scoring.report import check_out as check_report_out
    from jobs.output import check_writable

    check_report_out(out, overwrite, REPORT_FILES)
    check_writable(out, inside=True)


def evaluate(options: EvalOptions) -> None:
    if options.workers < 1:
        raise UserError(f"workers must be at least 1, got {options.workers}")
    if options.rows is not None and options.rows < 1:
        raise UserError(f"rows must be at least 1, got {options.rows}")
    from eval.scoring.baseline import exam_digest
    from eval.scoring.battery import kept_rollouts, take  # the simulator stack loads only for valid input
    from eval.sims import libero as libero_sim
    from eval.sims.rollout import ProfileMismatch

    if options.sim not in libero_sim.SIMS:
        raise UserError(f"sim must be one of {', '.join(libero_sim.SIMS)}, got {options.sim!r}")

    if options.replan is not None and options.replan < 1:
        raise UserError(f"replan must be at least 1, got {options.replan}")
    policy_options = {} if options.keys == "dataset" else {"keys": options.keys}
    if options.replan is not None:
        policy_options["replan"] = options.replan
    if options.device is not None:
        policy_options["device"] = options.device
    try:
        exam = read(options.exam)
        if options.keys == LIBERO.name and exam.profile != LIBERO.name:
            raise UserError(
                f"keys=libero sends LIBERO's features; this exam is profile {exam.profile} (make it with profile=libero)"
            )
        if options.sim == "libero":
            libero_sim.check(exam, options.policy)
        # the default report folder names the exam by its content too: two exams of one folder name never share it
        named = f"{exam.root.resolve().name}-{exam_digest(exam)[:8]}"
        where = "" if options.sim == "ours" else f"-{options.sim}"
        out = Path(options.out or Path("runs") / named / (re.sub(r"[^A-Za-z0-9_.-]+", "_", options.policy) + where))
        check_out(out, options.overwrite)
        policy = make(options.policy, **policy_options)
    except (ExamError, PolicyError, libero_sim.SimUnavailable) as exc:
        raise UserError(str(exc)) from None
    rows = exam.trials if options.rows is None else exam.trials.head(options.rows)
    kept = len(kept_rollouts(out).saved()) if options.resume else 0
    try:
        report, seconds = take(
            exam,
            rows,
            policy,
            out,
            options.workers,
            options.policy,
            policy_options=policy_options,
            resume=options.resume,
            discard=options.overwrite,
            sim=options.sim,
        )
    except (ProfileMismatch, FeatureMismatch) as exc:
        raise UserError(str(exc)) from None
    except (OSError, libero_sim.SimFailed) as exc:
        raise Failed(f"{type(exc).__name__}: {exc}") from None
    faces, ran = report["faces"], len(rows) - kept
    rate = f" ({60 * ran / seconds:.1f}/min)" if ran and seconds > 0 else ""
    resumed = f", {kept} kept from the interrupted take" if kept else ""
    where = " in LIBERO's own simulator" if options.sim == "libero" else ""
    print(f"{report['policy']} on {report['exam']}{where}: {ran} rollouts in {seconds:.0f} s{rate}{resumed}")
    for face in ("task", "obeyed_name", "true_target", "occ", "nonsense", "switch_obeyed", "switch_blind"):
        if face in faces:
            f = faces[face]
            print(
                f"  {face:<12} {f['rate']:.1%}  ({f['k']}/{f['n']}, "
                f"95% CI {f['ci'][0]:.1%}-{f['ci'][1]:.1%}, chance {f['chance']:.0%})"
            )
    if not report["init_value"]["trusted"]:
        print("  init-value check FAILED: a do-nothing rollout scores above 0; do not trust these rates")
    print(f"wrote {out}/report.json, report.md, report.html, rollouts.parquet")


if __name__ == "__main__":
    sys.exit(main("python -m eval", EvalOptions, evaluate, doc=__doc__))
