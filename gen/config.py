"""The generator's options (`python -m gen key=value ...`) and their validation.

Every problem with the input becomes a `UserError` (jobs/cli.py) whose message is one line
naming it; the CLI prints that line and exits non-zero before anything is written.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, List, Optional

from core import profiles, worlds
from core.profiles import Profile
from core.spec import FAST, LOOKS
from core.worlds import MAX_IMAGE_SIZE, PHYSICS_DT
from gen.lerobot.video import CODECS
from gen.planning import mix
from jobs.cli import UserError, compose_config
from jobs.output import check_output
from jobs.partial import completed
from referents import registry
from referents.registry import Referent, UnknownReferent
from referents.schema import ReferentSpecError


@dataclass
class GenConfig:
    referent: Any = "object"  # a referent type (referents/<type>.yaml), or a list that shares one dataset ([type@world,...])
    n: int = 20  # episodes
    seed: int = 0  # non-negative; the same seed and options give byte-identical output
    out: Optional[str] = None  # default datasets/<referent>, or datasets/<referent>-<world> in another world (exam: ...-exam)
    overwrite: bool = False  # replace a non-empty `out`
    resume: bool = False  # continue a killed run of the same options (see jobs/partial.py)
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
    confound: Any = None  # position: target in its canonical slot; layout: a benchmark task's own scene; a mix: one each ([..])
    push_to_hub: bool = False  # push the finished dataset (or exam) with gen/push.py
    repo_id: Optional[str] = None  # <user or org>/<name> to push to
    profile: Optional[str] = None  # native (joint targets) | libero (LIBERO's features, OSC deltas); default: the world's
    world: Optional[str] = None  # native, libero_goal, libero_object, libero_spatial: one carrying the type; default its own
    look: str = FAST  # fast | full: every mesh whole and reflections, as the world's own simulator draws (core/spec.py)
    switches: Optional[int] = None  # split=exam: switch rows per trial (the instruction changed mid-course); default 1, 0 none
    switched: float = 0.0  # split=train: the share of episodes whose instruction changes mid-course, the oracle changing course

    def spec_overrides(self) -> dict:
        """The options that edit the referent spec."""
        return {
            "objects_per_scene": self.objects_per_scene,
            "holdout": self.holdout,
            "distractor_only": self.distractor_only,
            "targets": self.targets,
            "confound": self.confound,
        }

    def shares(self) -> list[GenConfig]:
        """The options of each referent type the run plans: this run's own for one type; for a list
        (one dataset mixing them, gen/planning/mix.py), each type with its equal share of `n`."""
        if isinstance(self.referent, str):
            return [self]
        shares = []
        confounds = self.confound if isinstance(self.confound, list) else [self.confound] * len(self.referent)
        for item, confound in zip(self.referent, confounds, strict=True):
            name, world = registry.own_name(*mix.split(item))  # `object@libero_object` is libero_object
            n = self.n // len(self.referent)
            shares.append(replace(self, referent=name, world=world or self.world, n=n, confound=confound))
        return shares


def parse(argv: list[str]) -> GenConfig:
    """Overrides -> validated config."""
    config: GenConfig = compose_config("gen", GenConfig, argv)
    validate(config)
    return config


RESTRICTING = ("holdout", "distractor_only", "targets")  # list options that restrict what a plan may do


def validate(cfg: GenConfig) -> None:
    for name in RESTRICTING:
        if getattr(cfg, name) == []:
            raise UserError(f"{name}=[] names no value; leave {name} out, or name the values ({name}=[a,b])")
    if not isinstance(cfg.referent, str):
        _validate_mix(cfg)
        return
    if mix.WORLD_SEPARATOR in cfg.referent:  # `color@libero_spatial`, as a list names it: `world=` said another way
        name, world = mix.split(cfg.referent)
        if cfg.world not in (None, world):
            raise UserError(f"referent={cfg.referent} names world {world} and world={cfg.world} another: give one")
        cfg.referent, cfg.world = name, world
    if cfg.confound is not None and not isinstance(cfg.confound, (str, list)):
        raise UserError(f"confound must name a shortcut (position, layout), or one per type of a list, got {cfg.confound!r}")
    if cfg.confound is not None and not isinstance(cfg.confound, str):
        listed = mix.listed(cfg.confound, "confound")
        raise UserError(f"{listed} is one per type of a referent list; {cfg.referent} is one type: give one")
    world = resolve_world(cfg)
    try:
        profile = profiles.named(cfg.profile or world.profiles[0])
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
    check_seed(cfg.seed)
    if not 16 <= cfg.image_size <= MAX_IMAGE_SIZE or cfg.image_size % 2:
        raise UserError(f"image_size must be an even number of pixels in [16, {MAX_IMAGE_SIZE}], got {cfg.image_size}")
    physics_hz = round(1 / PHYSICS_DT)
    if cfg.fps <= 0 or physics_hz % cfg.fps:
        raise UserError(f"fps must divide the physics rate of {physics_hz} Hz (e.g. 10, 20, 25, 50), got {cfg.fps}")
    if cfg.codec not in CODECS:
        raise UserError(f"codec must be one of {', '.join(CODECS)}, got {cfg.codec!r}")
    if cfg.look not in LOOKS:
        raise UserError(f"look must be one of {', '.join(LOOKS)}, got {cfg.look!r}")
    if cfg.push_to_hub and not cfg.repo_id:
        raise UserError("push_to_hub=true needs repo_id=<user or org>/<name>")
    if cfg.split not in ("train", "exam"):
        raise UserError(f"split must be train or exam, got {cfg.split!r}")
    if cfg.switches is not None and (cfg.split != "exam" or cfg.switches < 0):
        got = f"switches={cfg.switches} with split={cfg.split}"
        raise UserError(f"switches= sizes an exam's switch rows (split=exam, 0 or more), got {got}")
    if isinstance(cfg.switched, bool) or not isinstance(cfg.switched, (int, float)) or not 0 <= cfg.switched <= 1:
        raise UserError(f"switched= is the share of episodes that change course, in [0, 1], got {cfg.switched!r}")
    if cfg.switched and cfg.split != "train":
        raise UserError(f"switched={cfg.switched} changes a training set's episodes; an exam's switches are switches= rows")
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
    if cfg.objects_per_scene is not None and cfg.objects_per_scene < 2:
        raise UserError(f"objects_per_scene must be at least 2 (a swap needs another object), got {cfg.objects_per_scene}")
    load_referent(cfg)  # the spec's own problems come before any about out=
    if cfg.out is None:
        name = cfg.referent if cfg.world == registry.world_of(cfg.referent, cfg.spec) else f"{cfg.referent}-{cfg.world}"
        cfg.out = str(Path("datasets") / (name if cfg.split == "train" else f"{name}-exam"))
    try:
        if finished(cfg) is None:  # resume=true on a finished run replaces nothing (gen/products/run.py)
            check_output(Path(cfg.out), cfg.overwrite)
    except (OSError, ValueError) as exc:  # e.g. a NUL byte or an over-long name in the path
        raise UserError(f"out={cfg.out!r} is not a usable path ({exc})") from None
    check_size(cfg, profile)


def _validate_mix(cfg: GenConfig) -> None:
    """A list of referent types (gen/planning/mix.py): each type is validated as its own run would be (its
    share of `n`, into the same `out`), then they must record the same features and be different
    types where they are laid out."""
    names = mix.types(cfg.referent)
    if len(names) == 1:  # a list of one is that type
        cfg.referent = names[0]
        if isinstance(cfg.confound, list) and len(cfg.confound) == 1:
            cfg.confound = cfg.confound[0]
        validate(cfg)
        return
    listed_types = mix.listed(names)
    if cfg.spec is not None:
        raise UserError(f"spec= is one type's spec file and {listed_types} mixes built-in types: leave spec= out")
    if cfg.split == "exam":
        raise UserError(
            f"split=exam makes one exam per referent type, not of {listed_types}: make each type's (referent=<type> split=exam)"
        )
    if cfg.n <= 0:
        raise UserError(f"n must be a positive number of episodes, got {cfg.n}")
    mix.check_share(cfg.n, names)
    if isinstance(cfg.confound, list) and len(cfg.confound) != len(names):
        raise UserError(
            f"{mix.listed(cfg.confound, 'confound')} names {len(cfg.confound)} confounds for the "
            f"{len(names)} types of {listed_types}: "
            "give one for all of them, or one each (null: that type deconfounded)"
        )
    shares = cfg.shares()
    if cfg.out is None:  # named as the progress bar names the types (`object@libero_object` is libero_object)
        own = [s.world in (None, registry.world_of(s.referent)) for s in shares]
        cfg.out = str(Path("datasets") / mix.name([s.referent if o else f"{s.referent}@{s.world}" for s, o in zip(shares, own)]))
        shares = cfg.shares()
    for item, share in zip(names, shares):
        try:
            validate(share)
        except UserError as exc:
            raise UserError(f"{listed_types}: {item}: {exc}") from None
    recorded = [
        (item, f"profile {s.profile} ({', '.join(profiles.named(str(s.profile)).image_keys)} at {s.image_size} px)")
        for item, s in zip(names, shares)
    ]
    common = set.intersection(*(set(worlds.world(str(s.world)).profiles) for s in shares))
    mix.check_features(recorded, f"all of them take profile={sorted(common)[0]}" if common else "no profile is taken by all")
    laid_out = [load_referent(s).label for s in shares]  # a world may make one type another's axis there
    for i, label in enumerate(laid_out):
        if label in laid_out[:i]:
            other = names[laid_out.index(label)]
            raise UserError(f"{listed_types}: {other} and {names[i]} are both {label}: name it once")
    first = shares[0]
    cfg.profile, cfg.image_size, cfg.workers = first.profile, first.image_size, first.workers
    check_size(cfg, profiles.named(str(cfg.profile)))


def finished(cfg: GenConfig) -> dict | None:
    """The generation record of the finished dataset or plan that `resume=true` finds at `out`:
    the run is then a no-op (or refused, when its options differ), so `out` is left as it is."""
    if not cfg.resume or cfg.overwrite or cfg.split != "train" or cfg.out is None:
        return None
    return completed(Path(cfg.out))


# What a run needs, measured: planning holds ~11.7 KB of memory per episode (a 20,000-episode
# object plan peaked 210 MB above a 2,000-episode one); a plan's scene records take ~0.43 KB of
# disk per episode, and a dataset's videos about half a byte per recorded pixel (~150 frames at most).
PLAN_MEMORY, PLAN_DISK, VIDEO_BYTES_PER_PIXEL, MAX_FRAMES = 12_000, 500, 0.5, 150


def check_size(cfg: GenConfig, profile: Profile) -> None:
    """Refuse an `n` whose plan could not fit in this machine's memory, or whose product could
    not fit on the disk under `out`, with the estimate."""
    memory = _available_memory()
    need = cfg.n * PLAN_MEMORY
    if memory is not None and need > memory:
        raise UserError(
            f"n={cfg.n} needs about {_size(need)} of memory to plan ({_size(PLAN_MEMORY)} per episode), "
            f"more than the {_size(memory)} available; plan fewer episodes"
        )
    pixels = MAX_FRAMES * len(profile.cameras) * (cfg.image_size or profile.image_size) ** 2
    per_episode = PLAN_DISK if cfg.plan_only or cfg.split == "exam" else PLAN_DISK + VIDEO_BYTES_PER_PIXEL * pixels
    existing = Path(str(cfg.out)).resolve()
    while not existing.exists():
        existing = existing.parent
    free = shutil.disk_usage(existing).free
    if cfg.n * per_episode > free:
        raise UserError(
            f"n={cfg.n} would write about {_size(cfg.n * per_episode)} ({_size(per_episode)} per episode), "
            f"more than the {_size(free)} free under {existing}"
        )


def _available_memory() -> int | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _size(n: float) -> str:
    for unit in ("B", "KB", "MB", "GB", "TB", "PB"):
        if n < 1000:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} EB"


def check_seed(seed: int) -> None:
    """Random streams are seeded from non-negative integers only (numpy's SeedSequence)."""
    if seed < 0:
        raise UserError(f"seed must be a non-negative integer, got {seed}")


def load_referent(cfg: GenConfig) -> Referent:
    """The run's referent, its spec validated with the run's overrides."""
    try:
        return registry.load(cfg.referent, cfg.spec, cfg.spec_overrides(), cfg.world)
    except UnknownReferent as exc:
        raise UserError(str(exc)) from None
    except ReferentSpecError as exc:
        raise UserError(_blame_objects_per_scene(cfg, exc) or str(exc)) from None


def _blame_objects_per_scene(cfg: GenConfig, exc: ReferentSpecError) -> str | None:
    """When the spec loads with its own objects per scene but not with `objects_per_scene=`, the
    option is the problem, not whichever spec field the referent's check names: say so, with the
    values that load."""
    if cfg.objects_per_scene is None:
        return None
    overrides = {**cfg.spec_overrides(), "objects_per_scene": None}
    try:
        own = registry.load(cfg.referent, cfg.spec, overrides, cfg.world)
    except (UnknownReferent, ReferentSpecError):
        return None
    accepted = []
    for k in range(2, len(own.config.layout.slots) + 1):
        try:
            registry.load(cfg.referent, cfg.spec, {**overrides, "objects_per_scene": k}, cfg.world)
            accepted.append(k)
        except ReferentSpecError:
            pass
    own_field = f"{own.config.path}: objects_per_scene: "
    reason = f" ({str(exc).removeprefix(own_field)})" if str(exc).startswith(own_field) else ""
    named = f"spec={cfg.spec}" if cfg.spec else f"referent {cfg.referent}"
    span = len(accepted) > 2 and accepted == list(range(accepted[0], accepted[-1] + 1))
    takes = f"{accepted[0]} to {accepted[-1]}" if span else ", ".join(map(str, accepted))
    return f"objects_per_scene={cfg.objects_per_scene} does not fit {named}{reason}; accepted: objects_per_scene={takes}"


def resolve_world(cfg: GenConfig) -> worlds.World:
    """The world a run's scenes happen in: the referent's own, or one `world=` names that carries
    it (registry.worlds_of); its files must be installed."""
    if cfg.spec is None and cfg.referent not in registry.available():
        raise UserError(f"unknown referent {cfg.referent!r}; available: {', '.join(registry.available())}")
    if cfg.spec is not None and not Path(cfg.spec).is_file():
        raise UserError(f"spec={cfg.spec}: no such file")
    home = registry.world_of(cfg.referent, cfg.spec)
    try:
        world = worlds.world(cfg.world or home)
    except worlds.UnknownWorld as exc:
        raise UserError(str(exc)) from None
    if world.name != home:
        others = ", ".join(registry.carried_by(world.name)) or "none yet"
        if cfg.spec:
            raise UserError(
                f"spec={cfg.spec} lays out scenes in world {home}, not {world.name}: leave world= out (or world={home}); "
                f"types world {world.name} carries: {others}"
            )
        carriers = registry.worlds_of(cfg.referent)
        if any(path.stem == cfg.referent for path in registry.tasks_only(world.name)):
            raise UserError(
                f"referent {cfg.referent} lays out only LIBERO's own tasks in world {world.name} (no scenes of its own): "
                f"python -m gen.canonical world={world.name}; worlds where it generates: {', '.join(carriers)}"
            )
        if world.name not in carriers:
            raise UserError(
                f"referent {cfg.referent} has no design in world {world.name}; worlds that carry {cfg.referent}: "
                f"{', '.join(carriers)} (types world {world.name} carries: {others})"
            )
    try:
        world.requires()
    except worlds.WorldUnavailable as exc:
        raise UserError(f"world={world.name}: {exc}") from None
    cfg.world = world.name
    return world
