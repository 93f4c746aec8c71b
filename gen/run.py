"""Generation: plan -> confound audit -> verified oracle demos -> LeRobot dataset.

Everything is built beside `out` (datasets in a resumable partial folder, see gen/partial.py;
exams and plans in a throwaway one) and moved into place in one rename once complete, so a
failed or interrupted run never leaves a half-written dataset at `out` and never destroys the
one that was there.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import time
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path

import referents
from core import __version__
from core.layout import NATIVE, STATE_KEY, TASK_KEY
from core.spec import EpisodeSpec, SimSettings
from gen import card, faults, scenes
from gen.audit import agree, audit
from gen.cli import UserError
from gen.config import GenConfig
from gen.partial import GENERATION_PATH, Partial, completed, publish
from gen.plan import designs, realize
from referents import Referent, UnknownReferent
from referents.base import ReferentSpecError

AUDIT_PATH = "meta/audit.json"


@dataclass
class Summary:
    out: Path
    episodes: int
    frames: int
    failed_attempts: int
    seconds: float
    verdict: str
    plan_only: bool = False
    exam: bool = False
    already_complete: bool = False

    def __str__(self) -> str:
        if self.already_complete:
            return f"{self.out} is already complete ({self.episodes} episodes, same options); nothing to do"
        if self.exam:
            return (
                f"wrote an exam of {self.episodes} oracle-solvable trials to {self.out} in {self.seconds:.1f} s\n"
                f"confound audit of its plan: {self.verdict}\n"
                f"take it with: python -m eval policy=<policy> exam={self.out}"
            )
        if self.plan_only:
            return (
                f"planned {self.episodes} episodes to {self.out} (nothing simulated) in {self.seconds:.1f} s\n"
                f"confound audit: {self.verdict}"
            )
        attempts = self.episodes + self.failed_attempts
        return (
            f"wrote {self.episodes} episodes ({self.frames} frames) to {self.out}\n"
            f"oracle: {self.failed_attempts} failed demos resampled; success before retries "
            f"{self.episodes}/{attempts} = {self.episodes / attempts:.1%}\n"
            f"confound audit: {self.verdict}\n"
            f"wall time {self.seconds:.1f} s, {self.frames / self.seconds:.1f} frames/s, "
            f"{self.seconds / self.episodes:.2f} s/episode"
        )


def overrides(cfg: GenConfig) -> dict:
    """Options that edit the referent spec."""
    return {
        "objects_per_scene": cfg.objects_per_scene,
        "holdout": cfg.holdout,
        "distractor_only": cfg.distractor_only,
        "targets": cfg.targets,
        "confound": cfg.confound,
    }


def load_referent(cfg: GenConfig) -> Referent:
    try:
        return referents.load(cfg.referent, cfg.spec, overrides(cfg))
    except (UnknownReferent, ReferentSpecError) as exc:
        raise UserError(str(exc)) from None


def sim_settings(cfg: GenConfig) -> SimSettings:
    return SimSettings(image_size=cfg.image_size, fps=cfg.fps)


def check_audit(report: dict) -> None:
    """A plan whose audit finds a leak nobody asked for is refused, naming the variable."""
    if report["unexpected_leaks"]:
        worst = {v["variable"]: v for v in report["variables"]}
        detail = ", ".join(
            f"{name} (held-out accuracy {worst[name]['rate']:.0%} vs chance {report['chance']:.0%})"
            for name in report["unexpected_leaks"]
        )
        raise UserError(f"the {report['referent']} plan fails its confound audit: {detail} predicts the target")


def run_record(cfg: GenConfig) -> dict:
    """The options that determine a dataset's bytes: a resumed run must match them."""
    keep = ("referent", "n", "seed", "image_size", "fps", "codec", "max_attempts", "spec", "objects_per_scene", "plan_only")
    record = {k: getattr(cfg, k) for k in keep} | overrides(cfg) | {"generator_version": __version__}
    if cfg.spec:
        record["spec_text"] = Path(cfg.spec).read_text()
    return record


def _already_complete(cfg: GenConfig, out: Path, generation: dict) -> Summary:
    """`resume=true` on a finished run (a requeued job that had in fact completed): a no-op when
    the options match, refused naming the first option that differs otherwise."""
    recorded, wanted = generation.get("run") or {}, run_record(cfg)
    changed = [k for k in wanted if recorded.get(k) != wanted[k]]
    if changed:
        name = "spec" if changed[0] == "spec_text" else changed[0]
        raise UserError(
            f"resume=true, but the complete dataset at out={out} was made with another {name} "
            f"({recorded.get(changed[0], 'unrecorded')!r}, not {wanted[changed[0]]!r}); pass overwrite=true to replace it"
        )
    return Summary(out, generation["episodes"], 0, 0, 0.0, "", already_complete=True)


def generate(cfg: GenConfig, progress: bool = True) -> Summary:
    start = time.perf_counter()
    out = Path(cfg.out or f"datasets/{cfg.referent}")
    if cfg.resume and not cfg.overwrite and cfg.split == "train" and (generation := completed(out)) is not None:
        return _already_complete(cfg, out, generation)
    referent = load_referent(cfg)
    sim = sim_settings(cfg)
    try:
        plan = designs(referent, cfg.n, cfg.seed, cfg.split)
    except ReferentSpecError as exc:
        raise UserError(str(exc)) from None
    planned = [realize(referent, d, i, cfg.seed, sim, split=cfg.split) for i, d in enumerate(plan)]
    audits: dict = {"planned": audit(referent, planned)}
    check_audit(audits["planned"])
    if cfg.split == "exam" or cfg.plan_only:
        return _quick(cfg, referent, sim, plan, planned, audits, out, start, progress)
    partial = Partial(out)
    if partial.exists and cfg.overwrite and not cfg.resume:
        shutil.rmtree(partial.root)
    try:
        done = partial.start(run_record(cfg), cfg.resume)
    except (FileExistsError, ValueError) as exc:
        raise UserError(str(exc)) from None
    failed = _simulate(cfg, referent, sim, plan, partial, done, progress)
    root = partial.fresh_dataset()
    rows, frames, written = _assemble(cfg, sim, partial, root)
    audits["written"] = audit(referent, written)
    audits["agree"] = agree(audits["planned"], audits["written"])
    if not audits["agree"]:
        raise RuntimeError("the audit of the written episodes disagrees with the plan's: resampling changed roles")
    scenes.write(root, rows)
    (root / AUDIT_PATH).write_text(json.dumps(audits, indent=2))
    summary = Summary(out, len(rows), frames, failed, time.perf_counter() - start, audits["written"]["verdict"])
    card.write(root, referent, cfg, summary, audits["written"])
    faults.point("finalize")
    _write_generation(root, cfg, referent, summary)  # last: it marks the dataset complete
    partial.publish()
    return summary


def _quick(
    cfg: GenConfig,
    referent: Referent,
    sim: SimSettings,
    plan: list,
    planned: list,
    audits: dict,
    out: Path,
    start: float,
    progress: bool,
) -> Summary:
    """Exams and plans: no video, cheap to redo, so built in a throwaway folder."""
    staging = out.parent / f".{out.name}.staging-{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    try:
        if cfg.split == "exam":
            staging.mkdir(parents=True)
            n_trials = _examine(cfg, referent, sim, plan, staging, audits["planned"], progress)
            summary = Summary(out, n_trials, 0, 0, time.perf_counter() - start, audits["planned"]["verdict"], exam=True)
            card.write_exam(staging, referent, cfg, summary, audits["planned"])
        else:
            (staging / "meta").mkdir(parents=True)
            scenes.write(staging, [scenes.row(i, spec) for i, spec in enumerate(planned)])
            (staging / AUDIT_PATH).write_text(json.dumps(audits, indent=2))
            summary = Summary(out, len(planned), 0, 0, time.perf_counter() - start, audits["planned"]["verdict"], plan_only=True)
            card.write(staging, referent, cfg, summary, audits["planned"])
            _write_generation(staging, cfg, referent, summary)
        publish(staging, out)
        return summary
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _simulate(
    cfg: GenConfig, referent: Referent, sim: SimSettings, plan: list, partial: Partial, done: int, progress: bool
) -> int:
    """Produce every episode not yet in the partial run; returns the failed oracle attempts."""
    from tqdm import tqdm

    from gen.produce import DemoFailed
    from gen.workers import Job, WorkerCrash, produce

    job = Job(cfg.referent, cfg.spec, overrides(cfg), sim, cfg.codec, cfg.seed, cfg.max_attempts)
    bar = tqdm(total=len(plan), initial=done, desc=referent.name, unit="ep", disable=not progress, dynamic_ncols=True)
    failed = 0
    try:
        for index, produced in enumerate(produce(job, plan, cfg.workers or 1, cfg.backend, start=done), start=done):
            faults.point(f"episode:{index}")
            partial.save(index, produced)
            failed += len(produced.failures)
            bar.update()
            bar.set_postfix(retries=failed)
    except DemoFailed as exc:
        raise UserError(f"{exc}; the referent spec may place objects out of reach") from None
    except WorkerCrash as exc:
        raise UserError(str(exc)) from None
    finally:
        bar.close()
    return failed


def _assemble(cfg: GenConfig, sim: SimSettings, partial: Partial, root: Path) -> tuple[list[dict], int, list[EpisodeSpec]]:
    """The LeRobot files, from the episode files, in order."""
    from gen.lerobot_writer import Layout, LeRobotWriter

    writer = LeRobotWriter(root, Layout(sim.fps, sim.image_size, sim.cameras, NATIVE.state_names, NATIVE.action_names, cfg.codec))
    rows, written = [], []
    for produced in partial.episodes(cfg.n):
        rows.append(scenes.row(writer.add(produced.episode), produced.spec, produced))
        written.append(produced.spec)
        faults.point(f"assemble:{len(rows) - 1}")
    writer.finalize()
    return rows, writer.frames, written


def _examine(cfg: GenConfig, referent: Referent, sim: SimSettings, plan: list, root: Path, report: dict, progress: bool) -> int:
    """Check every exam trial is solvable by the oracle (resampling poses as for datasets) and
    write the exam with each trial's initial state and rollout horizon."""
    import numpy as np
    from tqdm import tqdm

    from core import exam
    from gen.produce import DemoFailed, Producer

    producer = Producer(referent, sim)
    rows: list[dict] = []
    for i, design in enumerate(tqdm(plan, desc=f"{referent.name} exam", unit="trial", disable=not progress)):
        try:
            demo, _ = producer.demonstrate(design, i, cfg.seed, cfg.max_attempts, split="exam")
        except DemoFailed as exc:
            raise UserError(f"{exc}; the referent spec may place objects out of reach") from None
        producer.scene.reset(demo.spec)
        state = producer.scene.physics_state().astype(np.float64).tolist()
        horizon = int(np.ceil(1.5 * len(demo.actions))) + 20
        values = {a.id: a.value for a in referent.alternatives(demo.spec)}
        rows += exam.trial_rows(i, demo.spec, values, state, horizon)
    exam.write(
        root,
        rows,
        {
            "referent": referent.name,
            "seed": cfg.seed,
            "split": "exam",
            "command": card.command(cfg),
            "observation": {
                "keys": [NATIVE.image_key(c) for c in sim.cameras] + [STATE_KEY, TASK_KEY],
                "image_size": sim.image_size,
                "fps": sim.fps,
                "state_names": list(NATIVE.state_names),
                "action_names": list(NATIVE.action_names),
                "action": NATIVE.action_meaning,
            },
            "referent_spec": asdict(referent.config),
            "audit": report,
        },
    )
    return len(plan)


def _write_generation(root: Path, cfg: GenConfig, referent: Referent, summary: Summary) -> None:
    """What regenerates this dataset: generator and simulator versions, config, referent spec."""
    record = {
        "generator": "deconfound",
        "generator_version": __version__,
        "mujoco": metadata.version("mujoco"),
        "robosuite": metadata.version("robosuite"),
        "python": platform.python_version(),
        "config": asdict(cfg),
        "referent_spec": asdict(referent.config),
        "plan_only": cfg.plan_only,
        "run": run_record(cfg),
        "complete": True,
        "referent_spec_hash": card.spec_hash(referent),
        "episodes": summary.episodes,
        "failed_attempts": summary.failed_attempts,
        "seconds": round(summary.seconds, 2),
    }
    (root / GENERATION_PATH).write_text(json.dumps(record, indent=2, default=str))
