"""Planning: a referent and a seed -> balanced, realised episode specs, and their audit.

Pure data: no simulator runs here, so a 10,000-episode plan takes seconds. Designs (the roles:
which objects, where, which is the target) are drawn in sequence by one balancer; poses are
realised per episode from (seed, index, attempt), so re-realising a failed demo changes its
poses but never its roles. `plan_and_audit` is the step every product (dataset, plan, exam)
starts from: a plan whose confound audit finds a leak nobody asked for goes no further. A plan
of several referent types (gen/planning/mix.py) plans and audits each type on its own and interleaves them.
"""

from __future__ import annotations

import sys
import zlib
from dataclasses import dataclass

import numpy as np

from core import profiles, worlds
from core.spec import FAST, EpisodeSpec, SceneObject, Setup
from gen.config import GenConfig, load_referent
from gen.planning import mix, switches
from gen.planning.audit import audit
from jobs.cli import UserError
from referents.balance import Balance
from referents.design import Design
from referents.registry import Referent
from referents.schema import ReferentSpecError

# Extra entropy of each split's random streams: an exam never re-draws a training scene.
SPLITS = {"train": (), "exam": (0xE7A3,)}


PROGRESS_FROM = 2_000  # plans of this many episodes or more (about 2 s) show a progress bar while they are drawn


def designs(referent: Referent, n: int, seed: int, split: str = "train", stream: str | None = None) -> list[Design]:
    """The plan's roles. A spec whose values cannot fill a scene fails here, naming the file. A
    mix's types each draw from a `stream` of their own (their label, gen/planning/mix.py), so two types of
    alike scenes (negation and composition) never share one; a single type draws from the seed's."""
    from tqdm import tqdm

    own = [zlib.crc32(stream.encode())] if stream is not None else []
    entropy = [seed, *SPLITS[split], *own]
    balance = Balance(np.random.default_rng(entropy if len(entropy) > 1 else seed))
    try:
        return [referent.design(balance) for _ in tqdm(range(n), desc="planning", unit="ep", disable=n < PROGRESS_FROM)]
    except ReferentSpecError:
        raise
    except (ValueError, KeyError, IndexError, TypeError) as exc:
        problem = f"{type(exc).__name__}: {exc}"
        raise ReferentSpecError(f"{referent.config.path}: cannot lay out a scene from this spec ({problem})") from None


def realize(
    referent: Referent, design: Design, index: int, seed: int, setup: Setup, attempt: int = 0, split: str = "train"
) -> EpisodeSpec:
    if setup.world != referent.config.world:
        raise ValueError(f"referent {referent.name}'s scenes are in world {referent.config.world}, not {setup.world}")
    layout, world = referent.config.layout, worlds.world(setup.world)
    rng = np.random.default_rng([seed, index, attempt, *SPLITS[split]])
    objects = []
    for p in design.placements:
        kind = world.kind(p.candidate.kind)
        jitter = layout.jitter_at(p.slot)
        x, y = np.asarray(layout.slots[p.slot][:2]) + rng.uniform(-jitter, jitter, 2)
        yaw = rng.uniform(*layout.yaw)
        pos = (round(float(x), 5), round(float(y), 5), round(kind.rest_z(layout.surface(p.slot, world.surface_z)), 5))
        objects.append(
            SceneObject(p.id, p.candidate.kind, p.candidate.name, p.slot, pos, round(float(yaw), 5), dict(p.candidate.attributes))
        )
    return EpisodeSpec(
        referent=referent.name,
        index=index,
        seed=seed,
        objects=tuple(objects),
        target=design.target,
        instruction=design.instruction,
        template=design.template,
        counterfactuals=design.counterfactuals,
        assets=referent.assets(),
        task=design.task or referent.config.task,
        setup=setup,
        attempt=attempt,
        split=split,
        switch=design.switch,
    )


def plan(referent: Referent, n: int, seed: int, setup: Setup, split: str = "train") -> list[EpisodeSpec]:
    return [realize(referent, d, i, seed, setup, split=split) for i, d in enumerate(designs(referent, n, seed, split))]


@dataclass(frozen=True)
class Share:
    """One referent type's part of a plan: the type, where its scenes happen, the audit of its episodes."""

    referent: Referent
    setup: Setup
    audit: dict


@dataclass
class Planned:
    """A product's plan: its referent types' shares (one, or a mix's taking turns, gen/planning/mix.py),
    and the roles and realised specs of every episode in episode order."""

    shares: tuple[Share, ...]
    designs: list[Design]
    specs: list[EpisodeSpec]

    @property
    def only(self) -> Share:
        """The share of a plan of one type (an exam's: exams are made one type at a time)."""
        (share,) = self.shares
        return share

    @property
    def switched(self) -> bool:
        """Whether any episode's instruction changes mid-course (gen/planning/switches.py)."""
        return any(spec.switch is not None for spec in self.specs)

    @property
    def recording(self) -> Setup:
        """The setup with what every share records (profile, frame size, rate, cameras; one
        dataset records one set, gen/config.py checks): the first share's."""
        return self.shares[0].setup


def world_setup(
    world: worlds.World, profile: str | None = None, image_size: int | None = None, fps: int = 20, look: str = FAST
) -> Setup:
    """A world's setup: its robot's home, a profile it is recorded in (default its own)."""
    features = profiles.named(profile or world.profiles[0])
    return Setup(
        image_size=image_size or features.image_size,
        fps=fps,
        cameras=features.camera_names,
        robot_home=world.robot_home,
        profile=features.name,
        world=world.name,
        look=look,
    )


def configured_setup(cfg: GenConfig, world: worlds.World) -> Setup:
    return world_setup(world, cfg.profile, cfg.image_size, cfg.fps, cfg.look)


def default_setup(referent: Referent) -> Setup:
    """The setup of a referent's world in its default profile (what tests plan with)."""
    return world_setup(worlds.world(referent.config.world))


def check_audit(report: dict, answer: str = "the target") -> None:
    """A plan whose audit finds a leak nobody asked for is refused, naming the variable."""
    if report["unexpected_leaks"]:
        worst = {v["variable"]: v for v in report["variables"]}
        detail = ", ".join(
            f"{name} (held-out accuracy {worst[name]['rate']:.0%} vs chance {report['chance']:.0%})"
            for name in report["unexpected_leaks"]
        )
        raise UserError(f"the {report['referent']} plan fails its confound audit: {detail} predicts {answer}")


def plan_and_audit(cfg: GenConfig) -> Planned:
    """The options -> the audited plan every product is built from (bad input: `UserError`)."""
    types, roles, mixed = [], [], len(cfg.shares()) > 1
    for one in cfg.shares():
        referent = load_referent(one)
        types.append((referent, configured_setup(one, worlds.world(referent.config.world))))
        try:
            roles.append(designs(referent, one.n, one.seed, one.split, stream=referent.label if mixed else None))
        except ReferentSpecError as exc:
            raise UserError(str(exc)) from None
    episodes, k = switches.switched(mix.interleave(roles), cfg.switched, cfg.seed), len(types)
    specs = []
    for i, design in enumerate(episodes):
        referent, setup = types[mix.turn(i, k)]
        specs.append(realize(referent, design, i, cfg.seed, setup, split=cfg.split))
    if cfg.n >= PROGRESS_FROM:
        print(f"auditing the plan of {cfg.n} episodes ...", file=sys.stderr)
    shares = []
    for place, (referent, setup) in enumerate(types):
        own = mix.share(specs, place, k)
        report = audit(referent, own)
        check_audit(report)
        second = [spec.after_switch() for spec in own if spec.switch is not None]
        if second:  # the targets after a switch are audited as the first ones are
            report["switched"] = audit(referent, second)
            check_audit(report["switched"], "the target after a switch")
        shares.append(Share(referent, setup, report))
    return Planned(tuple(shares), episodes, specs)
