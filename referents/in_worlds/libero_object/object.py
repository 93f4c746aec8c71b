"""LIBERO-Object's object axis: the named grocery goes into the basket (see object.yaml beside it).

The groceries are chosen, placed and named as in the object referent (every grocery the target
and a distractor in every region equally often); the basket, the spec's `container`, stands in
the last slot of every scene and every target is carried into it (referents/destination.py:
alternatives, assets and the oracle's plan are the defaults). What is LIBERO-Object's own is here:
its tasks' scenes (`canonical`) and what a policy that learnt its layouts does (`shortcut`: the
scene says where; `named_place`: the name says where).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import libero, worlds
from core.spec import Counterfactual, EpisodeSpec, TaskSpec
from referents import destination, scenery
from referents.balance import Balance
from referents.compose import fill, naming_design
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig

CONFOUNDS = ("position", "layout")


def _container(cfg: ReferentConfig) -> Candidate:
    held = destination.container(cfg)
    if held is None:
        raise cfg.fail(destination.FIELD, "missing field (where every grocery goes)")
    return held


def validate(cfg: ReferentConfig) -> None:
    container = worlds.world(cfg.world).kinds.get(_container(cfg).kind)
    if container is None or container.contain is None:
        raise cfg.fail("container", f"{_container(cfg).kind!r} is not a container of world {cfg.world}")
    if len(cfg.layout.slots) != cfg.objects_per_scene + 1:
        raise cfg.fail("layout.slots", f"needs one slot per grocery ({cfg.objects_per_scene}) and the container's last")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    if cfg.confound == "layout":
        return _as_liberos_task(cfg, balance)
    return naming_design(cfg, balance)


def _as_liberos_task(cfg: ReferentConfig, balance: Balance) -> Design:
    """`confound=layout`: the scene of the LIBERO-Object task whose target is the balanced choice,
    as LIBERO's demonstrations lay it out (its groceries, each in its task's region), named with
    any template; the container is added by the world (referents/destination.py)."""
    target = balance.pick("target", [c for c in cfg.objects if c.targetable])
    suite = worlds.world(cfg.world).suite
    for task in libero.tasks(suite):
        problem = libero.problem(suite, task)
        if problem.objects[problem.goal[0][1]] == target.kind:
            break
    else:
        raise cfg.fail("confound", f"no {suite} task's target is {target.name}: its layout is LIBERO's to give")
    scene = canonical(cfg, problem)
    template = balance.pick("template", cfg.templates)
    placements = tuple(p for p in scene.placements if p.candidate.role != destination.FIELD)
    return replace(
        scene,
        placements=placements,
        template=template,
        instruction=fill(template, target),
        counterfactuals=tuple(
            Counterfactual(fill(template, p.candidate), p.id, (target.name, p.candidate.name))
            for p in placements
            if p.id != scene.target
        ),
        task=None,
    )


def canonical(cfg: ReferentConfig, problem: libero.Problem) -> Design:
    """A LIBERO-Object task's scene: its objects (each in the slot nearest its region), LIBERO's
    instruction, and a swap to every other grocery (LIBERO-PRO's one rename per task,
    `libero_object_task`, is one of them), said as LIBERO says it."""
    container = _container(cfg)
    placements = []
    for instance, kind in problem.objects.items():
        slot = scenery.nearest_slot(cfg, problem, instance)
        known = scenery.base_kind(cfg, kind) == container.kind
        placements.append(Placement(kind, replace(container, kind=kind) if known else scenery.candidate(cfg, kind), slot))
    target = problem.objects[problem.goal[0][1]]  # (In <target> <container>_contain_region)
    destination = problem.objects[problem.goal[0][2].removesuffix("_contain_region")]
    template = cfg.templates[0]
    say = template.format
    named = scenery.candidate(cfg, target).name
    others = [p for p in placements if p.id not in (target, destination) and p.candidate.role != scenery.SCENERY]
    return Design(
        placements=tuple(placements),
        target=target,
        template=template,
        instruction=libero.language(problem.name),
        counterfactuals=tuple(Counterfactual(say(name=p.candidate.name), p.id, (named, p.candidate.name)) for p in others),
        task=TaskSpec(program=cfg.task.program, params={"destination": destination}),
    )


def shortcut(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """What a policy that learnt LIBERO-Object's layouts instead of its words does: it knows
    the scene by its groceries and fetches whatever stands in that task's target region (a
    scene of no LIBERO task: region 0, the target region of half of them)."""
    destination = spec.task.params["destination"]
    known = {c.kind for c in cfg.objects}  # it knows LIBERO's groceries (a recoloured one as itself), not what was added
    groceries = {scenery.base_kind(cfg, o.kind) for o in spec.objects if o.id != destination} & known
    suite, slot = worlds.world(cfg.world).suite, 0
    for task in libero.tasks(suite):
        problem = libero.problem(suite, task)
        target = problem.objects[problem.goal[0][1]]  # (In <target> basket_1_contain_region)
        if groceries == {c for c in problem.objects.values() if c != _container(cfg).kind}:
            slot = _home(cfg, target)
    return _fetch(cfg, spec, slot)


def named_place(cfg: ReferentConfig, spec: EpisodeSpec, named: str) -> EpisodeSpec:
    """What a policy that learnt where each name's grocery stands in LIBERO's layouts does: every
    grocery is the target of one task and always stands in that task's target region (one of
    two), so the name alone says where to reach; it fetches whatever stands there. A name LIBERO
    never gave (a new grocery): region 0, as `shortcut`."""
    return _fetch(cfg, spec, _home(cfg, scenery.base_kind(cfg, spec.object(named).kind)))


def _home(cfg: ReferentConfig, kind: str) -> int:
    """The target region (slot) of the LIBERO task whose target is `kind`; 0 for a kind LIBERO never targets."""
    keys = [c.key for c in cfg.objects if c.kind == kind]
    return cfg.layout.canonical(keys[0]) if keys else 0


def _fetch(cfg: ReferentConfig, spec: EpisodeSpec, slot: int) -> EpisodeSpec:
    """The scene's episode with whatever grocery stands nearest `slot` as its target."""
    destination = spec.task.params["destination"]
    x, y = cfg.layout.slots[slot]
    chosen = min((o for o in spec.objects if o.id != destination), key=lambda o: np.hypot(o.pos[0] - x, o.pos[1] - y))
    return replace(spec, target=chosen.id)
