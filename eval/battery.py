"""Taking an exam: run its rollouts with a policy, log them, and score the logs.

The report is computed from the written `rollouts.parquet`, exactly as the offline scorer
(`python -m eval.score`) would, so a report never depends on how the rollouts were run. Every
report carries the measured shortcut beside it: the `position` reference policy's faces on the
same rollouts, run once per exam and kept in the cache (`shortcut_baseline`).
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from tqdm import tqdm

from core.exam import Exam
from eval.baseline import SHORTCUT, cached_baseline, store_baseline
from eval.policies import Policy
from eval.registry import make
from eval.report import write_reports
from eval.rollout import Runner, run_chunk
from eval.score import POLICY_KEY, read_logs, score


def shortcut_baseline(exam: Exam, rows: pd.DataFrame, workers: int = 1) -> dict:
    """The `position` policy's faces on `rows` of the exam: measured once, then cached."""
    known = cached_baseline(exam, list(rows["row"]))
    if known is not None:
        return known
    with tempfile.TemporaryDirectory() as tmp:
        report, _ = take(exam, rows, make(SHORTCUT), Path(tmp), workers, SHORTCUT, baseline=False)
    store_baseline(exam, list(rows["row"]), report["faces"])
    return report["faces"]


def take(
    exam: Exam,
    rows: pd.DataFrame,
    policy: Policy,
    out: Path,
    workers: int = 1,
    policy_name: str | None = None,
    baseline: bool = True,
    policy_options: dict | None = None,
) -> tuple[dict, float]:
    """Run `rows` (some or all of `exam.trials`) with `policy`, write rollouts.parquet and the
    reports to `out`; returns the report and the seconds the rollouts took (the shortcut
    baseline's, measured on first use with `baseline`, not included). With workers > 1
    and a `policy_name`, contiguous chunks of rows run in processes that each rebuild the policy
    from its name and `policy_options` (eval/registry.py); the logs are the same either way."""
    check = getattr(policy, "check", None)
    if check is not None:  # a checkpoint that cannot read this exam stops here, before any rollout
        check(exam.features)
    start = time.perf_counter()
    if workers > 1 and policy_name is not None:
        chunks = [rows.iloc[idx] for idx in np.array_split(np.arange(len(rows)), workers) if len(idx)]
        with multiprocessing.get_context("spawn").Pool(len(chunks)) as pool:
            logs = [log for part in pool.starmap(run_chunk, [(policy_name, c, policy_options) for c in chunks]) for log in part]
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
    report = score(dataclasses.replace(exam, trials=rows.reset_index(drop=True)), logged, policy.name)
    if baseline and policy.name == SHORTCUT:
        store_baseline(exam, list(rows["row"]), report["faces"])
        report["baseline"] = report["faces"]
    elif baseline:
        report["baseline"] = shortcut_baseline(exam, rows, workers)
    write_reports(out, report)
    return report, seconds
