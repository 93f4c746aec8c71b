"""Generation: plan -> verified oracle demos -> LeRobot dataset.

Everything is written into a staging folder beside `out` and moved into place in one rename
once complete, so a failed or interrupted run never leaves a half-written dataset at `out` and
never destroys the one that was there.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import mujoco
from tqdm import tqdm

import referents
from gen import __version__, card, scenes
from gen.config import GenConfig, UserError
from gen.lerobot_writer import Layout, LeRobotWriter
from gen.plan import designs
from gen.produce import DemoFailed, Producer
from gen.spec import SimSettings
from oracle.scene import ACTION_NAMES, STATE_NAMES
from referents import Referent, UnknownReferent
from referents.base import ReferentSpecError

GENERATION_PATH = "meta/generation.json"


@dataclass
class Summary:
    out: Path
    episodes: int
    frames: int
    failed_attempts: int
    seconds: float

    def __str__(self) -> str:
        attempts = self.episodes + self.failed_attempts
        return (
            f"wrote {self.episodes} episodes ({self.frames} frames) to {self.out}\n"
            f"oracle: {self.failed_attempts} failed demos resampled; success before retries "
            f"{self.episodes}/{attempts} = {self.episodes / attempts:.1%}\n"
            f"wall time {self.seconds:.1f} s, {self.frames / self.seconds:.1f} frames/s, "
            f"{self.seconds / self.episodes:.2f} s/episode"
        )


def load_referent(cfg: GenConfig) -> Referent:
    overrides = {"objects_per_scene": cfg.objects_per_scene} if cfg.objects_per_scene is not None else None
    try:
        return referents.load(cfg.referent, cfg.spec, overrides)
    except (UnknownReferent, ReferentSpecError) as exc:
        raise UserError(str(exc)) from None


def sim_settings(cfg: GenConfig) -> SimSettings:
    return SimSettings(image_size=cfg.image_size, fps=cfg.fps)


def generate(cfg: GenConfig, progress: bool = True) -> Summary:
    start = time.perf_counter()
    referent = load_referent(cfg)
    sim = sim_settings(cfg)
    plan = designs(referent, cfg.n, cfg.seed)
    out = Path(cfg.out or f"datasets/{referent.name}")
    staging = out.parent / f".{out.name}.staging-{os.getpid()}"
    shutil.rmtree(staging, ignore_errors=True)
    try:
        writer = LeRobotWriter(staging, Layout(sim.fps, sim.image_size, sim.cameras, STATE_NAMES, ACTION_NAMES, cfg.codec))
        producer = Producer(referent, sim, cfg.codec)
        rows, failed = [], 0
        bar = tqdm(plan, desc=f"{referent.name}", unit="ep", disable=not progress, dynamic_ncols=True)
        for i, design in enumerate(bar):
            try:
                produced = producer.produce(design, i, cfg.seed, cfg.max_attempts)
            except DemoFailed as exc:
                raise UserError(f"{exc}; the referent spec may place objects out of reach") from None
            failed += len(produced.failures)
            rows.append(scenes.row(writer.add(produced.episode), produced))
            bar.set_postfix(retries=failed)
        writer.finalize()
        scenes.write(staging, rows)
        summary = Summary(out, len(rows), writer.frames, failed, time.perf_counter() - start)
        _write_generation(staging, cfg, referent, summary)
        card.write(staging, referent, cfg, summary)
        _publish(staging, out)
        return summary
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _write_generation(root: Path, cfg: GenConfig, referent: Referent, summary: Summary) -> None:
    """What regenerates this dataset: generator and simulator versions, config, referent spec."""
    record = {
        "generator": "deconfound",
        "generator_version": __version__,
        "mujoco": mujoco.__version__,
        "python": platform.python_version(),
        "config": asdict(cfg),
        "referent_spec": asdict(referent.config),
        "episodes": summary.episodes,
        "failed_attempts": summary.failed_attempts,
        "seconds": round(summary.seconds, 2),
    }
    (root / GENERATION_PATH).write_text(json.dumps(record, indent=2, default=str))


def _publish(staging: Path, out: Path) -> None:
    """Move the finished dataset to `out`; an old one is removed only after the swap."""
    out.parent.mkdir(parents=True, exist_ok=True)
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        out.rename(old)
    staging.rename(out)
    if old is not None:
        shutil.rmtree(old)
