"""What the experiments (train/experiment.py, train/axes.py) are built from: stages that are done
once and reused, so a killed experiment continues where it stopped and its parts can run in
different sittings.

* a dataset or exam is generated only if its folder holds none, and refused if it holds one made
  with other options (the next invocation's options are the ones a reader believes);
* a training run continues from its last matching state (`resume=true`, train/fit.py) and is
  skipped when finished on the same recipe (`recipe`);
* an exam report is taken once, and read back while the weights it was taken with (their
  digest, kept beside it) are still the ones there (a reference policy's: while the exam is);
* each stage's wall time is summed over every invocation that did its work (`timings.json`).
"""

from __future__ import annotations

import hashlib
import json
import shlex
import shutil
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd

from core.exam import Exam
from gen.config import GenConfig, parse
from jobs.cli import UserError
from jobs.lock import held

if TYPE_CHECKING:
    from train.fit import TrainConfig

WEIGHTS_DIGEST = "weights.sha256"  # beside a report: the weights (or, of a reference policy, the exam) it was taken with
TIMINGS = "timings.json"  # in an experiment's `out`: each stage's wall time
FLUSH_S = 60.0  # a running stage's time is added this often: a killed process loses at most this much


class Ledger:
    """Wall time per stage, summed over every invocation that did the stage's work (two
    experiment processes on one `out`, e.g. the arms trained side by side, add to the same file)."""

    def __init__(self, root: Path) -> None:
        self.path = root / TIMINGS
        self.spent: dict[str, float] = self._read()

    def _read(self) -> dict[str, float]:
        return json.loads(self.path.read_text()) if self.path.is_file() else {}

    @contextmanager
    def timing(self, stage: str) -> Iterator[None]:
        """Time the work inside as `stage`'s, added as it goes (every `FLUSH_S`) and when it ends: a
        stage stopped part way, by Ctrl-C, an error or a killed process (a sitting's end), did that
        much of its work, which its rerun does not redo."""
        since, done = time.perf_counter(), threading.Event()

        def flush() -> None:  # by the beat, then (once it has stopped) at the end: never both at once
            nonlocal since
            now = time.perf_counter()
            self.add(stage, now - since)
            since = now

        def beat() -> None:
            while not done.wait(FLUSH_S):
                flush()

        beating = threading.Thread(target=beat, name=f"ledger {stage}", daemon=True)
        beating.start()
        try:
            yield
        finally:
            done.set()
            beating.join()
            flush()

    def add(self, stage: str, seconds: float) -> None:
        """Add `seconds` of `stage`'s work to the file as it is now."""
        with held(self.path.with_name(f".{self.path.name}.lock")):
            self.spent = self._read()
            self.spent[stage] = round(self.spent.get(stage, 0.0) + seconds, 1)
            tmp = self.path.with_suffix(".tmp")
            tmp.write_text(json.dumps(self.spent, indent=2))
            tmp.replace(self.path)


class Commands:
    """The command line of every stage run so far, kept in `out` as each comes (a stopped run's
    docs list them; two processes on one `out` add to the same file)."""

    def __init__(self, root: Path) -> None:
        self.path = root / "commands.json"

    def read(self) -> list[str]:
        return json.loads(self.path.read_text()) if self.path.is_file() else []

    def append(self, line: str) -> None:
        with held(self.path.with_name(f".{self.path.name}.lock")):
            lines = self.read()
            if line not in lines:
                tmp = self.path.with_suffix(".tmp")
                tmp.write_text(json.dumps([*lines, line], indent=2))
                tmp.replace(self.path)


def begun_with(root: Path, wanted: dict, record: str, what: str, command: str, begin: bool) -> dict:
    """The determining options the `what` run in `root` was begun with: recorded in `record` by the
    first invocation (`begin`), and every later one must ask for the same (a folder `command` did
    not begin is refused, never written into, and its docs state what ran, not what a later
    invocation was given)."""
    path = root / record
    with held(root.parent / f".{root.name}.lock") if root.parent.is_dir() else nullcontext():
        if path.is_file():
            begun = json.loads(path.read_text())
            changed = [k for k in wanted if begun.get(k) != wanted[k]]
            if changed:
                k = changed[0]
                raise UserError(f"out={root} was begun with {k}={value(begun.get(k))}, not {value(wanted[k])}; "
                                "choose another out= for another recipe")  # fmt: skip
            return begun
        if root.exists() and any(root.iterdir()):
            raise UserError(f"out={root} is not empty and holds no {record}: not a {what} run's folder; choose another out=")
        if not begin:
            raise UserError(f"out={root} holds no {what} run yet; run {command} first")
        root.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(wanted, indent=2))
        tmp.replace(path)
        return wanted


def gen_command(args: Sequence[str], out: Path, image_size: int, workers: int | None = None) -> tuple[str, GenConfig]:
    """A `python -m gen` command line and its validated config (resume=true: a generation killed
    with the experiment continues; a finished one is not asked again)."""
    line = [*args, f"image_size={image_size}", *([f"workers={workers}"] if workers is not None else []), f"out={out}"]
    return "python -m gen " + " ".join(map(shlex.quote, line)), parse([*line, "overwrite=true", "resume=true"])


def canonical_once(
    world: str, states: int, seed: int, image_size: int, out: Path, ledger: Ledger, stage: str, commands: Commands | list[str]
) -> Path:
    """LIBERO's canonical exam of `world` (gen.canonical) in `out`, built unless it is there; its
    command line added to `commands`."""
    import torch._dynamo  # noqa: F401  before the exam's GL context (generate_once: why)

    from gen.products.canonical import CanonicalOptions, build

    chosen = CanonicalOptions(world, states, seed, image_size, str(out))
    commands.append(f"python -m gen.canonical world={world} states={states} seed={seed} image_size={image_size} out={out}")
    if not (out / "exam.json").is_file():
        with ledger.timing(stage):
            build(chosen)
    return out


def generate_once(cfg: GenConfig, ledger: Ledger, stage: str) -> None:
    """Generate `cfg`'s dataset or exam unless its folder already holds it (two experiment
    processes on one `out` that both need it: one makes it while the other waits)."""
    # Before generation makes a GL context in this process (workers=1): triton, which torch's
    # compiler loads (transformers imports it with the text tower), crashes (SIGSEGV) after one.
    import torch._dynamo  # noqa: F401

    from gen.products.run import generate

    out = Path(str(cfg.out))
    with held(out.parent / f".{out.name}.lock"):
        if made(cfg, out):
            return
        with ledger.timing(stage):
            generate(cfg)


def made(cfg: GenConfig, out: Path) -> bool:
    """Whether `out` holds the finished product `cfg` describes; one made with other options is
    refused (one line naming both), never silently reused."""
    from gen.products.dataset import already_complete
    from gen.products.provenance import Provenance
    from jobs.partial import completed

    if (out / "exam.json").is_file():
        there, wanted = json.loads((out / "exam.json").read_text()).get("command"), Provenance(cfg, {}).command()
        if there != wanted:
            raise UserError(f"{out} holds the exam `{there}`, not `{wanted}`; choose another out= or remove it")
        return True
    if (generation := completed(out)) is not None:
        already_complete(cfg, out, generation)
        return True
    return False


def train_once(cfg: TrainConfig, ledger: Ledger, stage: str, allowed: bool = True) -> dict | None:
    """The log of the run `cfg` describes: trained (or continued from its last matching state) unless
    one finished on the same recipe is there; None when it is not finished and not `allowed`."""
    from jobs.cli import Failed
    from train.fit import fit

    ckpt = Path(cfg.out)
    log = train_log(ckpt)
    if log is not None and log["steps"] > cfg.steps:
        raise UserError(f"{ckpt} holds a {log['steps']}-step run, more than the {cfg.steps} asked for; choose another out=")
    if log is None or recipe(log["config"]) != recipe(asdict(cfg)):
        if not allowed:
            return None
        try:
            with ledger.timing(stage):
                fit(cfg)
        except ValueError as exc:
            raise Failed(f"training {ckpt}: {exc}") from None
        log = train_log(ckpt)
    return log


def train_log(ckpt: Path) -> dict | None:
    """The log of the finished training run in `ckpt` (train/fit.py), or None if none finished there."""
    try:
        log = json.loads((ckpt / "train.json").read_text())
        return log if isinstance(log.get("steps"), int) else None
    except (OSError, ValueError, AttributeError):
        return None


def restore(ckpt: Path, committed: Path) -> dict | None:
    """The log of a finished run rebuilt from its committed checkpoint when `ckpt` holds none: the
    final weights carry the config and loss history they were trained with (train/fit.py), so a
    run outlives the machine that trained it. None when there is nothing to restore."""
    import torch

    from train.policy import MODEL_FILE

    if (log := train_log(ckpt)) is not None or not (committed / MODEL_FILE).is_file():
        return log
    record = torch.load(committed / MODEL_FILE, map_location="cpu", weights_only=False)
    if not record.get("history"):
        return None
    ckpt.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(committed / MODEL_FILE, ckpt / MODEL_FILE)
    history = record["history"]
    log = {"steps": history[-1]["step"], "final_loss": history[-1]["loss"], "config": record["train"],
           "history": history, "restored_from": str(committed)}  # fmt: skip
    (ckpt / "train.json").write_text(json.dumps(log, indent=2))
    return log


def recipe(config: dict) -> tuple:
    """What decides a run's weights besides its data and seed: the learning rate at every step, and
    the pointer loss's weight (runs logged before `decay` or `point_weight` existed had none), the
    types a run favours with their share (none before `favour` existed), and the share of switched
    frames and which (none before `switched_share` existed)."""
    favoured = (tuple(config["favour"]), config["favour_share"]) if config.get("favour") else ()
    switched = (("switched", config["switched_share"]),) if config.get("switched_share") else ()
    switched += tuple((k, config[k]) for k in ("switched_first", "switched_before", "switched_stay") if config.get(k))
    return tuple(config.get(k, 0) for k in ("steps", "lr", "warmup", "lr_floor", "decay", "point_weight")) + favoured + switched


def exam_report(
    exam: Exam,
    weights: Path,
    rows: pd.DataFrame,
    out: Path,
    replan: int,
    ledger: Ledger,
    stage: str,
    baseline: bool = True,
    sim: str = "ours",
) -> dict:
    """The report of the checkpoint `weights` on `rows` of `exam`, taken once (in our simulator or,
    `sim=libero`, in LIBERO's own) and read back on later runs while the weights it was taken with
    are still the ones there."""
    from eval.scoring.battery import take
    from train.policy import CheckpointPolicy

    def run() -> None:
        policy = CheckpointPolicy(str(weights), replan)
        options = {"replan": replan}
        take(exam, rows, policy, out, 2, f"ckpt:{weights}", baseline=baseline, policy_options=options, resume=True, sim=sim)

    return _once(out, weights_digest(weights), run, ledger, stage)


def weights_digest(weights: Path) -> str:
    """What a checkpoint's reports are stamped with (`WEIGHTS_DIGEST`): its final weights' sha256."""
    from train.policy import MODEL_FILE

    return hashlib.sha256((weights / MODEL_FILE if weights.is_dir() else weights).read_bytes()).hexdigest()


def finished_report(report_dir: Path, digest: str | None) -> dict | None:
    """The report in `report_dir` if it was taken with the weights `digest` names (`weights_digest`;
    None: a reference policy's, kept while its exam is)."""
    path, stamp = report_dir / "report.json", report_dir / WEIGHTS_DIGEST
    if not path.is_file() or not stamp.is_file() or (digest is not None and stamp.read_text() != digest):
        return None
    return json.loads(path.read_text())


def reference_report(exam: Exam, policy: str, out: Path, ledger: Ledger, stage: str) -> dict:
    """The report of the reference policy `policy` (eval/policies/__init__.py) on the whole of `exam`,
    taken once and read back while the exam is the same."""
    from eval.policies.registry import make
    from eval.scoring.battery import take

    def run() -> None:
        take(exam, exam.trials, make(policy), out, 2, policy, baseline=False)

    return _once(out, reference_digest(exam, policy), run, ledger, stage)


def reference_digest(exam: Exam, policy: str) -> str:
    """What a reference policy's report is stamped with (`WEIGHTS_DIGEST`): the exam it took."""
    from eval.scoring.baseline import exam_digest

    return exam_digest(exam, policy)


def _once(out: Path, digest: str, run: Callable[[], None], ledger: Ledger, stage: str) -> dict:
    """`out`'s report, taken by `run` unless the one there was taken from what `digest` names (two
    processes that both need it: one takes it while the other waits)."""
    stamp = out / WEIGHTS_DIGEST
    with held(out.parent / f".{out.name}.lock"):
        if not (out / "report.json").is_file() or not stamp.is_file() or stamp.read_text() != digest:
            with ledger.timing(stage):
                run()
            stamp.write_text(digest)
    return json.loads((out / "report.json").read_text())


def brief(face: dict) -> dict:
    """A face's headline numbers: k, n, rate and its intervals."""
    return {k: face[k] for k in ("k", "n", "rate", "ci", "ci_trials") if k in face}


def commit(model: Path, folder: Path, limit_mb: float) -> str | None:
    """Copy a final checkpoint into the docs when it is small enough to commit; its path, or
    None when it is not (a full fine-tune carries the whole text tower)."""
    if model.stat().st_size > limit_mb * 1e6:
        return None
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / model.name
    shutil.copyfile(model, target)
    return str(target)


def value(v: object) -> str:
    """An option's value as it is written on the command line."""
    if isinstance(v, list):
        return f"[{','.join(map(str, v))}]"
    return str(v).lower() if isinstance(v, bool) else str(v)


def cell(face: dict) -> str:
    """Rate (k/n; the trial-resampled 95% interval, else Wilson's)."""
    if not face.get("n"):
        return "— (n=0)"
    lo, hi = face.get("ci_trials") or face["ci"]
    return f"{face['rate']:.1%} ({face['k']}/{face['n']}; {lo:.0%}–{hi:.0%})"
