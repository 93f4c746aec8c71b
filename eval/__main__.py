"""Take an exam: run every rollout with a policy, log it, score it, write the reports.

python -m eval policy=oracle exam=datasets/object-exam workers=2

Runs the exam's rollouts in our simulator with the policy (oracle, position, nothing, random,
remote:HOST:PORT, ckpt:PATH or any other registered one: eval/registry.py), logs them to
`rollouts.parquet`, scores the logs with eval/score.py and writes report.json, report.md and
report.html to `out` (eval/battery.py).
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)
from core.exam import ExamError, read
from core.layout import LIBERO
from eval.policies import FeatureMismatch, PolicyError
from eval.registry import make
from gen.cli import Failed, UserError, main


@dataclass
class EvalOptions:
    policy: str  # oracle, position, nothing, random, remote:HOST:PORT, ckpt:PATH (eval/registry.py)
    exam: str  # the exam folder (python -m gen ... split=exam)
    out: str | None = None  # report folder; default runs/<exam folder>/<policy>
    rows: int | None = None  # take only the first N rollouts; default all
    workers: int = 1  # processes running rollouts (the logs are the same either way)
    keys: str = "dataset"  # remote policies: dataset (the exam's keys) | libero (what openpi's LIBERO client sends)
    replan: int | None = None  # chunking policies (ckpt, remote): actions executed per predicted chunk; default theirs
    device: str | None = None  # lerobot checkpoints: the torch device to run on (default cpu)


def evaluate(options: EvalOptions) -> None:
    if options.workers < 1:
        raise UserError(f"workers must be at least 1, got {options.workers}")
    if options.rows is not None and options.rows < 1:
        raise UserError(f"rows must be at least 1, got {options.rows}")
    from eval.battery import take  # the simulator stack loads only for valid input
    from eval.rollout import ProfileMismatch

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
        policy = make(options.policy, **policy_options)
    except (ExamError, PolicyError) as exc:
        raise UserError(str(exc)) from None
    rows = exam.trials if options.rows is None else exam.trials.head(options.rows)
    out = Path(options.out or Path("runs") / exam.root.name / re.sub(r"[^A-Za-z0-9_.-]+", "_", options.policy))
    try:
        report, seconds = take(exam, rows, policy, out, options.workers, options.policy, policy_options=policy_options)
    except (ProfileMismatch, FeatureMismatch) as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:
        raise Failed(f"{type(exc).__name__}: {exc}") from None
    faces = report["faces"]
    print(f"{report['policy']} on {report['exam']}: {len(rows)} rollouts in {seconds:.0f} s ({60 * len(rows) / seconds:.1f}/min)")
    for face in ("task", "obeyed_name", "true_target", "occ", "nonsense"):
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
