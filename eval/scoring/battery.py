"""Taking an exam: run its rollouts with a policy, log them, and score the logs.

The report is computed from the written `rollouts.parquet`, exactly as the offline scorer
(`python -m eval.score`) would, so a report never depends on how the rollouts were run. Every
report carries the measured shortcut beside it: the `position` reference policy's faces on the
same rollouts, run once per exam and kept in the cache (`shortcut_baseline`).

A take runs for hours on a canonical exam, so every finished rollout is kept at once, one file
each, in a partial run beside `out` (jobs/partial.py, locked while a take works on it): an
interrupted take loses only the rollouts in flight, and `resume` runs only the missing ones, to
the same report. The reports reach `out` only when every rollout is done; a take that fails
before any rollout is finished leaves no partial run behind.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import os
import signal
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
from tqdm import tqdm

from core.exam import Exam, read
from core.products import REPORTS, ROLLOUTS
from core.spec import EpisodeSpec
from eval.policies import Policy
from eval.policies.registry import make
from eval.scoring.baseline import SHORTCUT, cached_baseline, exam_digest, store_baseline
from eval.scoring.report import write_reports
from eval.scoring.score import BASELINE_MEASURED, score
from eval.sims.libero import versions
from eval.sims.log import EXAM_KEY, POLICY_KEY, PREDICTION_KEY, SIM_KEY, VERSIONS_KEY, read_logs
from eval.sims.rollout import OurSim, Runner, Simulator
from jobs import faults
from jobs.cli import Failed
from jobs.partial import Partial
from jobs.processes import die_with

REPORT_FILES = (*REPORTS, ROLLOUTS)  # what a take writes to `out`, all it ever replaces there
WATCH_S = 1.0  # seconds between looks at a take's worker processes


def _worker(parent: int) -> None:
    """A rollout worker: Ctrl-C is for the parent to handle, and it dies with the parent (gen/products/workers.py)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with(parent)


class WorkerDied(Failed):
    """A rollout worker process died mid-take; the message says what is kept and how to go on."""


class BaselineInterrupted(KeyboardInterrupt):
    """Ctrl-C while the shortcut baseline was measured; the message says what its take kept."""


def shortcut_baseline(exam: Exam, rows: pd.DataFrame, workers: int = 1, keep: Path | None = None) -> dict:
    """The `position` policy's faces on `rows` of the exam: measured once, then cached. Its rollouts
    are kept in `keep` as they finish (a take's partial run, so an interrupted take resumes them too)."""
    known = cached_baseline(exam, list(rows["row"]))
    if known is not None:
        return known
    with tempfile.TemporaryDirectory() as tmp:
        out = (keep or Path(tmp)) / SHORTCUT
        try:
            report, _ = take(exam, rows, make(SHORTCUT), out, workers, SHORTCUT, baseline=False, resume=True, discard=False)
        except KeyboardInterrupt as exc:
            raise BaselineInterrupted(str(exc)) from None
    store_baseline(exam, list(rows["row"]), report["faces"])
    return report["faces"]


def kept_rollouts(out: Path) -> Partial:
    """Where a take to `out` keeps its finished rollouts: a partial run beside `out`."""
    return Partial(out, "rollouts")


def take(
    exam: Exam,
    rows: pd.DataFrame,
    policy: Policy,
    out: Path,
    workers: int = 1,
    policy_name: str | None = None,
    baseline: bool = True,
    policy_options: dict | None = None,
    resume: bool = False,
    discard: bool = True,
    sim: str = OurSim.name,
) -> tuple[dict, float]:
    """Run `rows` (some or all of `exam.trials`) with `policy`, write rollouts.parquet and the
    reports to `out`; returns the report and the seconds the rollouts run now took (the shortcut
    baseline's, measured on first use with `baseline`, not included). With workers > 1
    and a `policy_name`, contiguous chunks of rows run in processes that each rebuild the policy
    from its name and `policy_options` (eval/policies/registry.py); the logs are the same either way.
    An interrupted take's rollouts are continued with `resume`, discarded with `discard`, and
    refused with neither; interrupting this one raises KeyboardInterrupt saying what was kept.
    `sim` is where the rollouts run: our simulator, or LIBERO's own (`libero`, eval/sims/libero.py)."""
    check = getattr(policy, "check", None)
    if check is not None:  # a checkpoint that cannot read this exam stops here, before any rollout
        check(exam.features)
    ids = [int(r) for r in rows["row"]]
    run = {"exam": exam_digest(exam), "rows": ids, "policy": policy.name, "policy_name": policy_name, "options": policy_options}
    if sim != OurSim.name:  # a take in another simulator resumes only there
        run["sim"] = sim
    with kept_rollouts(out) as partial:
        partial.start(run, resume, discard)
        try:
            start = time.perf_counter()
            _run(exam, rows[~rows["row"].isin(partial.saved())], policy, partial, workers, policy_name, policy_options, sim)
            seconds = time.perf_counter() - start
            logs = [partial.load(i) for i in ids]
            report = _report(exam, rows, policy, logs, partial.root, workers, baseline, sim)
        except KeyboardInterrupt as exc:
            kept = len(partial.saved() & set(ids))
            during = (
                f" (while the `{SHORTCUT}` baseline was measured: {str(exc).removeprefix('interrupted: ').split(';')[0]})"
                if isinstance(exc, BaselineInterrupted)
                else ""
            )
            raise KeyboardInterrupt(
                f"interrupted: {kept} of {len(ids)} rollouts kept in {partial.root}{during}; rerun with resume=true to continue"
            ) from None
        except Exception:
            if not partial.saved():  # nothing to resume: an empty partial run would only block the rerun
                partial.finish()
            raise
        out.mkdir(parents=True, exist_ok=True)
        for name in REPORT_FILES:  # each file replaced in one rename; anything else in `out` stays
            (partial.root / "report" / name).replace(out / name)
        partial.finish()
    return report, seconds


def make_sim(name: str, exam: Exam) -> Simulator:
    """The simulator `name` (eval/sims/libero.py SIMS) for rollouts of `exam`."""
    if name == OurSim.name:
        return OurSim()
    from eval.sims.libero import LiberoSim

    specs = [EpisodeSpec.from_json(s) for s in exam.trials.drop_duplicates("trial")["spec"]]
    return LiberoSim(exam.meta, specs)


def run_chunk(policy_name: str, rows: pd.DataFrame, options: dict | None, partial: Partial, sim: str, exam_root: Path) -> None:
    """A worker process's share of an exam: its own policy, simulator and renderers; each rollout is
    saved to the partial run as soon as it ends, so an interrupted take keeps it."""
    runner = Runner(make(policy_name, **(options or {})), make_sim(sim, read(exam_root)))
    try:
        for _, row in rows.iterrows():
            faults.point(f"rollout:{int(row['row'])}")
            partial.save(int(row["row"]), runner.run(row).to_row())
    finally:
        runner.close()


def _run(
    exam: Exam,
    rows: pd.DataFrame,
    policy: Policy,
    partial: Partial,
    workers: int,
    policy_name: str | None,
    policy_options: dict | None,
    sim: str,
) -> None:
    """Run `rows`, each rollout saved to `partial` as it ends."""
    if rows.empty:
        return
    if workers > 1 and policy_name is not None:
        chunks = [rows.iloc[idx] for idx in np.array_split(np.arange(len(rows)), workers) if len(idx)]
        # Ctrl-C reaches the whole process group: the workers ignore it, this process stops the pool
        with multiprocessing.get_context("spawn").Pool(len(chunks), initializer=_worker, initargs=(os.getpid(),)) as pool:
            # a worker that dies (a native crash, the OOM killer) is replaced by the pool but its chunk is
            # lost, and the take would wait for it forever: watch the workers the chunks went to
            workers_started = list(pool._pool)
            taking = pool.starmap_async(run_chunk, [(policy_name, c, policy_options, partial, sim, exam.root) for c in chunks])
            while not taking.ready():
                taking.wait(WATCH_S)
                dead = [w.exitcode for w in workers_started if w.exitcode is not None]
                if dead and not taking.ready():
                    how = signal.Signals(-dead[0]).name if dead[0] < 0 else f"exit code {dead[0]}"
                    raise WorkerDied(
                        f"a rollout worker died ({how}); the {len(partial.saved())} rollouts finished are kept in "
                        f"{partial.root}: rerun with resume=true to continue"
                    )
            taking.get()
    else:
        runner = Runner(policy, make_sim(sim, exam))
        try:
            for _, row in tqdm(rows.iterrows(), total=len(rows), desc=policy.name, unit="rollout"):
                partial.save(int(row["row"]), runner.run(row).to_row())
        finally:
            runner.close()


def _report(
    exam: Exam, rows: pd.DataFrame, policy: Policy, logs: list[dict], kept: Path, workers: int, baseline: bool, sim: str
) -> dict:
    """Score `logs` from the written rollouts.parquet, as the offline scorer would, and write every
    report file to `kept`/report (the shortcut baseline's rollouts, when it is measured now, are kept
    in `kept`/baseline)."""
    staged = kept / "report"
    staged.mkdir(parents=True, exist_ok=True)
    table = pa.Table.from_pylist(logs)
    # who acted, where, on which exam (its digest: eval.agreement refuses takes of another), and whether
    # the policy's predictions come from a trained head, where it says (train/policy.py CheckpointPolicy)
    meta = {
        POLICY_KEY: policy.name.encode(),
        SIM_KEY: sim.encode(),
        VERSIONS_KEY: json.dumps(versions(sim)).encode(),
        EXAM_KEY: exam_digest(exam).encode(),
    }
    trained = getattr(policy, "prediction_trained", None)
    if trained is not None:
        meta[PREDICTION_KEY] = b"true" if trained else b"false"
    pq.write_table(table.replace_schema_metadata(meta), staged / ROLLOUTS)
    logged, _ = read_logs(staged / ROLLOUTS)
    report = score(dataclasses.replace(exam, trials=rows.reset_index(drop=True)), logged, policy.name, len(exam.trials))
    if baseline and policy.name == SHORTCUT:
        store_baseline(exam, list(rows["row"]), report["faces"])
        report["baseline"] = report["faces"]
    elif baseline:
        report["baseline"] = shortcut_baseline(exam, rows, workers, kept / "baseline")
    if baseline:
        report["baseline_source"] = BASELINE_MEASURED
    write_reports(staged, report)
    return report
