"""Battery throughput: rollouts per minute for the reference policies.

    python bench/battery.py [trials=40] [referent=object] [profile=native] ['policies=[oracle,random]'] ['workers=[1,2]']

Builds an exam (trials x (task + swaps + occ + nonsense) rollouts), takes it with each policy
at each worker count, and prints rollouts/min. Reference policies read no cameras, so this is
physics and planning; a camera policy adds two renders per step (see bench/generate.py).
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

from core.exam import read
from eval.policies import PolicyError
from eval.policies.registry import make
from eval.scoring.battery import take
from gen.config import parse
from gen.products.run import generate
from jobs.cli import UserError, main


@dataclass
class BenchOptions:
    trials: int = 40  # exam trials (each one task + swaps + occ + nonsense rollouts)
    referent: str = "object"  # a referent type (referents/<type>.yaml)
    profile: str = "native"  # the exam's profile: native | libero
    policies: list[str] = field(default_factory=lambda: ["oracle", "random"])  # policies to time (see eval/policies/__init__.py)
    workers: list[int] = field(default_factory=lambda: [1, 2])  # worker counts to time each policy at


def bench(options: BenchOptions) -> None:
    if min(options.workers, default=1) < 1:
        raise UserError(f"workers must be at least 1, got {options.workers}")
    try:
        policies = {name: make(name) for name in options.policies}
    except PolicyError as exc:
        raise UserError(str(exc)) from None
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "exam"
        argv = [f"referent={options.referent}", f"n={options.trials}", "split=exam", f"out={root}", f"profile={options.profile}"]
        generate(parse(argv), progress=False)
        exam = read(root)
        print(f"{options.referent} exam ({options.profile}): {options.trials} trials, {len(exam.trials)} rollouts")
        print(
            f"{'policy':<10}{'workers':>8}{'seconds':>9}{'rollouts/min':>14}{'task':>7}{'obeyed':>8}"
            f"{'95% CI':>10}{'chance':>8}{'max face':>10}"
        )
        for name, policy in policies.items():
            for workers in options.workers:
                report, seconds = take(exam, exam.trials, policy, Path(tmp) / f"{name}-{workers}", workers, name)
                f = report["faces"]
                print(
                    f"{name:<10}{workers:>8}{seconds:>9.1f}{60 * len(exam.trials) / seconds:>14.1f}"
                    f"{f['task']['rate']:>7.0%}{f['obeyed_name']['rate']:>8.0%}"
                    f"{'{:.0%}-{:.0%}'.format(*f['obeyed_name']['ci']):>10}{f['obeyed_name']['chance']:>8.0%}"
                    f"{max(face['rate'] for face in f.values()):>10.0%}"
                )


if __name__ == "__main__":
    sys.exit(main("python bench/battery.py", BenchOptions, bench, doc=__doc__))
