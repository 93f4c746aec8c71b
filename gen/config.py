"""The generator's options (`python -m gen key=value ...`) and their validation.

Every problem with the input becomes a `UserError` (gen/cli.py) whose message is one line
naming it; the CLI prints that line and exits non-zero before anything is written.
"""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional

import referents
from core import worlds
from core.layout import layout
from core.worlds import MAX_IMAGE_SIZE, PHYSICS_DT
from gen.cli import UserError, compose_config
from gen.partial import completed
from gen.video import CODECS


@dataclass
class GenConfig:
    referent: str = "object"  # a referent type (referents/<type>.yaml)
    n: int = 20  # episodes
    seed: int = 0
    out: Optional[str] = None  # output folder; default datasets/<referent>
    overwrite: bool = False  # replace a non-empty `out`
    resume: bool = False  # continue a killed run of the same options (see gen/partial.py)
    image_size: Optional[int] = None  # square camera frames, pixels; default: the profile's (native 128, libero 256)
    fps: int = 20  # control and recording rate
    codec: str = "h264"  # h264 | av1
    max_attempts: int = 10  # oracle attempts per episode before generation stops
    spec: Optional[str] = None  # a referent spec file instead of referents/<referent>.yaml
    objects_per_scene: Optional[int] = None  # override the referent spec's objects_per_scene
    plan_only: bool = False  # write the plan (meta/scenes.parquet) and its audit, simulate nothing
    holdout: Optional[List[str]] = None  # values kept out of the dataset entirely
    distractor_only: Optional[List[str]] = None  # values that appear but are never the target
    targets: Optional[List[str]] = None  # the only values that may be the target (e.g. held-out ones in an exam)
    split: str = "train"  # train: a LeRobot dataset; exam: an exam (held-out random stream, no video)
    workers: Optional[int] = None  # processes producing episodes; default: this machine's cores
    backend: str = "process"  # process (this machine) | ray (Ray tasks; RAY_ADDRESS selects a cluster)
    confound: Optional[str] = None  # "position": put the target in the canonical slot (for comparisons)
    push_to_hub: bool = False  # push the finished dataset (or exam) with gen/push.py
    repo_id: Optional[str] = None  # <user or org>/<name> to push to
    # native (joint targets, 16-d state) | libero (OSC end-effector deltas, LIBERO's features); default: the world's
    profile: Optional[str] = None
    world: Optional[str] = None  # native | libero_object (LIBERO-Object's scenes); default: the referent's

    def spec_overrides(self) -> dict:
        """The options that edit the referent spec."""
        return {
            "objects_per_scene": self.objects_per_scene,
            "holdout": self.holdout,
            "distractor_only": self.distractor_only,
            "targets": self.targets,
            "confound": self.confound,
        }


def parse(argv: list[str]) -> GenConfig:
    """Overrides -> validated config."""
    config: GenConfig = compose_config("gen", GenConfig, argv)
    validate(config)
    return config


def validate(cfg: GenConfig) -> None:
    world = resolve_world(cfg)
    try:
        profile = layout(cfg.profile or world.profiles[0])
    except ValueError as exc:
        raise UserError(str(exc)) from None
    if profile.name not in world.profiles:
        only = " or ".join(world.profiles)
        raise UserError(f"world {world.name} is recorded in profile {only} only, not profile={profile.name}")
    cfg.profile = profile.name
    if cfg.image_size is None:
        cfg.image_size = profile.image_size
    if cfg.n <= 0:
        raise UserError(f"n must be a positive number of episodes, got {cfg.n}")
    if not 16 <= cfg.image_size <= MAX_IMAGE_SIZE or cfg.image_size % 2:
        raise UserError(f"image_size must be an even number of pixels in [16, {MAX_IMAGE_SIZE}], got {cfg.image_size}")
    physics_hz = round(1 / PHYSICS_DT)
    if cfg.fps <= 0 or physics_hz % cfg.fps:
        raise UserError(f"fps must divide the physics rate of {physics_hz} Hz (e.g. 10, 20, 25, 50), got {cfg.fps}")
    if cfg.codec not in CODECS:
        raise UserError(f"codec must be one of {', '.join(CODECS)}, got {cfg.codec!r}")
    if cfg.push_to_hub and not cfg.repo_id:
        raise UserError("push_to_hub=true needs repo_id=<user or org>/<name>")
    if cfg.split not in ("train", "exam"):
        raise UserError(f"split must be train or exam, got {cfg.split!r}")
    if cfg.split == "exam" and cfg.plan_only:
        raise UserError("plan_only=true and split=exam do not combine: an exam is already simulation-free to read")
    if cfg.workers is None:
        cfg.workers = os.cpu_count() or 1
    if cfg.workers < 1:
        raise UserError(f"workers must be at least 1, got {cfg.workers}")
    if cfg.backend not in ("process", "ray"):
        raise UserError(f"backend must be process or ray, got {cfg.backend!r}")
    if cfg.max_attempts < 1:
        raise UserError(f"max_attempts must be at least 1, got {cfg.max_attempts}")
    if cfg.objects_per_scene is not None and cfg.objects_per_scene < 1:
        raise UserError(f"objects_per_scene must be at least 1, got {cfg.objects_per_scene}")
    if cfg.out is None:
        cfg.out = str(Path("datasets") / (cfg.referent if cfg.split == "train" else f"{cfg.referent}-exam"))
    try:
        check_output(Path(cfg.out), cfg.overwrite or cfg.resume and completed(Path(cfg.out)) is not None)
    except (OSError, ValueError) as exc:  # e.g. a NUL byte or an over-long name in the path
        raise UserError(f"out={cfg.out!r} is not a usable path ({exc})") from None


def resolve_world(cfg: GenConfig) -> worlds.World:
    """The world a run's scenes happen in: the referent's, which `world=` may only confirm;
    its files must be installed."""
    home = referents.world_of(cfg.referent, cfg.spec)
    try:
        world = worlds.world(cfg.world or home)
    except worlds.UnknownWorld as exc:
        raise UserError(str(exc)) from None
    if world.name != home:
        others = ", ".join(referents.of_world(world.name)) or "none yet"
        raise UserError(
            f"referent {cfg.referent}'s scenes are in world {home}, not {world.name}; referents of world {world.name}: {others}"
        )
    try:
        world.requires()
    except worlds.WorldUnavailable as exc:
        raise UserError(f"world={world.name}: {exc}") from None
    cfg.world = world.name
    return world


def check_output(out: Path, overwrite: bool) -> None:
    """`out` must be creatable and writable, and empty unless `overwrite`.

    Writability is tested by creating (and removing) a folder where the dataset will be staged:
    permission bits alone say nothing for root or on read-only mounts.
    """
    if out.exists() and not out.is_dir():
        raise UserError(f"out={out} exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        raise UserError(f"out={out} is not empty; pass overwrite=true to replace it")
    parent = out.resolve().parent
    while not parent.exists():
        parent = parent.parent
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".deconfound-write-test-", dir=parent))
    except OSError as exc:
        raise UserError(f"out={out} is not writable ({exc.strerror or exc} in {parent})") from None
