"""`python -m eval policy=<name> exam=<dir> [out=<dir>] [rows=<N>] [workers=<N>]`: take an exam.

Runs every rollout of the exam in our simulator with the policy (oracle, position, nothing,
random, remote:HOST:PORT, ckpt:PATH), logs them to `rollouts.parquet`, scores the logs with
eval/score.py and writes report.json, report.md and report.html to `out`
(default: runs/<exam folder>/<policy>). `rows` takes only the first N rollouts; `workers`
runs rollouts in that many processes (default 1; the logs are the same either way).
"""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)

USAGE = (
    "usage: python -m eval policy=<oracle|position|nothing|random|remote:HOST:PORT|ckpt:PATH> exam=<dir> "
    "[out=<dir>] [rows=<N>] [workers=<N>]"
)
OPTIONS = {"policy", "exam", "out", "rows", "workers"}


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help", "help"):
        print(USAGE)
        return 0 if argv else 2
    from core.exam import ExamError, read

    try:
        opts = dict(a.split("=", 1) for a in argv)
    except ValueError:
        print(f"error: options are key=value; {USAGE}", file=sys.stderr)
        return 2
    unknown = set(opts) - OPTIONS
    if unknown or not {"policy", "exam"} <= set(opts):
        problem = f"unknown option {sorted(unknown)[0]!r}" if unknown else "policy= and exam= are required"
        print(f"error: {problem}; {USAGE}", file=sys.stderr)
        return 2
    from eval.policies import PolicyError, make

    try:
        exam = read(opts["exam"])
        policy = make(opts["policy"])
        rows = exam.trials if "rows" not in opts else exam.trials.head(int(opts["rows"]))
        workers = int(opts.get("workers", 1))
    except (ExamError, PolicyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except ValueError:
        print("error: rows and workers must be whole numbers", file=sys.stderr)
        return 2
    out = Path(opts.get("out") or Path("runs") / exam.root.name / re.sub(r"[^A-Za-z0-9_.-]+", "_", opts["policy"]))
    report, seconds = take(exam, rows, policy, out, workers=max(1, workers), policy_name=opts["policy"])
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
    return 0


def take(exam, rows, policy, out: Path, workers: int = 1, policy_name: str | None = None) -> tuple[dict, float]:  # noqa: ANN001
    """Run, log, and score: the report is computed from the written logs, exactly as the
    offline scorer would. With workers > 1 the rollouts are split into contiguous chunks run
    by processes that rebuild the policy from `policy_name`."""
    import multiprocessing

    import numpy as np
    import pyarrow as pa
    import pyarrow.parquet as pq
    from tqdm import tqdm

    from eval.report import write_reports
    from eval.rollout import Runner, run_chunk
    from eval.score import POLICY_KEY, read_logs, score

    start = time.perf_counter()
    if workers > 1 and policy_name is not None:
        chunks = [rows.iloc[idx] for idx in np.array_split(np.arange(len(rows)), workers) if len(idx)]
        with multiprocessing.get_context("spawn").Pool(len(chunks)) as pool:
            logs = [log for part in pool.starmap(run_chunk, [(policy_name, c) for c in chunks]) for log in part]
    else:
        runner = Runner(policy)
        it = tqdm(rows.iterrows(), total=len(rows), desc=policy.name, unit="rollout")
        logs = [runner.run(row).to_row() for _, row in it]
        runner.close()
    seconds = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pylist(logs)
    pq.write_table(table.replace_schema_metadata({POLICY_KEY: policy.name.encode()}), out / "rollouts.parquet")
    logged, _ = read_logs(out / "rollouts.parquet")
    subset = type(exam)(exam.root, exam.meta, rows.reset_index(drop=True))
    report = score(subset, logged, policy.name)
    write_reports(out, report)
    return report, seconds


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
