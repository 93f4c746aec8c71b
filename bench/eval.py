"""Battery throughput: rollouts per minute for the reference policies.

    python bench/eval.py [trials=40] [referent=object] [policies=oracle,random] [workers=1,2]

Builds an exam (trials x (task + swaps + occ + nonsense) rollouts), takes it with each policy
at each worker count, and prints rollouts/min. Reference policies read no cameras, so this is
physics and planning; a camera policy adds two renders per step (see bench/generate.py).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from core.exam import read
from eval.__main__ import take
from eval.policies import make
from gen.config import parse
from gen.run import generate


def main(argv: list[str]) -> None:
    opts = dict(a.split("=", 1) for a in argv)
    trials = int(opts.get("trials", 40))
    referent = opts.get("referent", "object")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "exam"
        generate(parse([f"referent={referent}", f"n={trials}", "split=exam", f"out={root}"]), progress=False)
        exam = read(root)
        print(f"{referent} exam: {trials} trials, {len(exam.trials)} rollouts")
        print(f"{'policy':<10}{'workers':>8}{'seconds':>9}{'rollouts/min':>14}{'task':>7}{'obeyed':>8}")
        for name in opts.get("policies", "oracle,random").split(","):
            for workers in (int(w) for w in opts.get("workers", "1,2").split(",")):
                report, seconds = take(exam, exam.trials, make(name), Path(tmp) / f"{name}-{workers}", workers, name)
                f = report["faces"]
                print(
                    f"{name:<10}{workers:>8}{seconds:>9.1f}{60 * len(exam.trials) / seconds:>14.1f}"
                    f"{f['task']['rate']:>7.0%}{f['obeyed_name']['rate']:>8.0%}"
                )


if __name__ == "__main__":
    main(sys.argv[1:])
