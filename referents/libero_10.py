"""LIBERO-10's "put both" axis: two named groceries into the basket, one after the other (see
libero_10.yaml beside it).

An episode is a task of two goals (core/spec.py THEN): both named groceries into the basket, the
shorter first (the words leave the order free), side by side as the basket's kind says
(`Kind.beside`). The first named, the second named and
the distractors are balanced apart (each grocery first, second and a distractor equally often, each
in every slot), and the audit reads both goals (gen/planning/audit.py), so neither name is
predicted by where things stand. A swap changes one of the two names to a distractor's
(`Counterfactual.goal`: which one), the other goal as asked; each distractor is named by one swap,
so an exam row's ask says which goal it renames. What is LIBERO-10's own is here too: its tasks'
scenes (`canonical`) and what a policy that learnt its layouts does (`shortcut`).

LIBERO-10's other tasks are laid out as LIBERO sets them, with no swap: what stands beside the
thing a kitchen task carries is nothing the hand could take in its stead (the frying pan, the wine
bottle, the other moka pot; the red mug beside the living room's two), and where it could (the white
mug beside KITCHEN_SCENE6's), it is what the goal carries to its place, which a swap, naming a
goal's target, does not change. In the kitchens the type lays out those tasks and nothing else (a
spec there says `canonical_only`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import libero, libero_goals, worlds
from core.libero_goals import Goal
from core.spec import THEN, Counterfactual, EpisodeSpec, TaskSpec
from referents import scenery
from referents.balance import Balance
from referents.compose import slug
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig
from referents.variables import Alternative, object_alternatives

_DESTINATION = "destination"  # the role of the basket in the spec


def _basket(cfg: ReferentConfig) -> Candidate:
    return cfg.role(_DESTINATION)[0]


def _groceries(cfg: ReferentConfig) -> list[Candidate]:
    return [c for c in cfg.objects if c.role != _DESTINATION]


def _tasks_only(cfg: ReferentConfig) -> bool:
    """A spec that lays out its world's LIBERO-10 tasks on LIBERO's states only (registry.tasks_only)."""
    return cfg.extra.get("canonical_only") is True


def _sites(cfg: ReferentConfig) -> dict[str, int]:
    """The places on furniture LIBERO-10's tasks of the world name -> their layout slots (`sites`)."""
    return {str(k): int(v) for k, v in cfg.extra.get("sites", {}).items()}


def _table_slots(cfg: ReferentConfig) -> list[int]:
    """The layout's slots where things stand (the groceries', the basket's last), not the `sites`."""
    return [s for s in range(len(cfg.layout.slots)) if s not in _sites(cfg).values()]


def validate(cfg: ReferentConfig) -> None:
    world = worlds.world(cfg.world)
    if any(
        k not in world.kinds or not world.kind(k).is_site or not 0 <= v < len(cfg.layout.slots) for k, v in _sites(cfg).items()
    ):
        raise cfg.fail("sites", "maps places on the world's furniture or table (site kinds) to slots of layout.slots")
    if _tasks_only(cfg):
        return
    baskets = cfg.role(_DESTINATION)
    if len(baskets) != 1 or world.kind(baskets[0].kind).contain is None:
        raise cfg.fail("objects", f"needs one object with role: destination, a container of world {cfg.world}")
    if world.kind(baskets[0].kind).side_by_side is None:
        raise cfg.fail("objects", f"{baskets[0].kind} has no side_by_side: where two things brought to it stand")
    if cfg.objects_per_scene < 3 or cfg.objects_per_scene > len(_groceries(cfg)):
        raise cfg.fail("objects_per_scene", "needs two named groceries and one or more to swap to, from the objects")
    if len(_table_slots(cfg)) < cfg.objects_per_scene + 1:
        raise cfg.fail("layout.slots", f"needs a slot per grocery ({cfg.objects_per_scene}) and the basket's, before the `sites`")
    if len([c for c in _groceries(cfg) if c.targetable]) < 2:
        raise cfg.fail("targets", "leaves fewer than two groceries to name")
    if any("{first}" not in t or "{second}" not in t for t in cfg.templates):
        raise cfg.fail("templates", "each names both groceries: {first} and {second}")


def _task(cfg: ReferentConfig, first: str, second: str, basket: str, basket_kind: str) -> TaskSpec:
    """Both into the basket, the first then the second, side by side."""
    kind = worlds.world(cfg.world).kind(basket_kind)
    return libero_goals.task(
        tuple(Goal(cfg.task.program, t, {"destination": basket, "at": kind.beside(i)}) for i, t in enumerate((first, second)))
    )


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    if _tasks_only(cfg):
        raise cfg.fail("canonical_only", f"lays out LIBERO-10's own tasks only: python -m gen.canonical world={cfg.world}")
    groceries = _groceries(cfg)
    first = balance.pick("target", [c for c in groceries if c.targetable])
    second = balance.pick(("second", first.key), [c for c in groceries if c.targetable and c is not first], also="second")
    chosen = [first, second]
    while len(chosen) < cfg.objects_per_scene:
        chosen.append(balance.pick("distractor", [c for c in groceries if c not in chosen]))
    placements: list[Placement] = []
    for role, cand in zip(("target", "second", *["distractor"] * (len(chosen) - 2)), chosen):
        free = [s for s in _table_slots(cfg)[:-1] if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(cand.key), cand, balance.pick((role, "slot", cand.key), free, also="slot")))
    basket = Placement(slug(_basket(cfg).key), _basket(cfg), _table_slots(cfg)[-1])
    template = balance.pick("template", cfg.templates)
    others = placements[2:]
    renamed = balance.pick(("renamed first", first.key), [p.candidate for p in others])  # the first name's swap names it

    def say(a: Candidate, b: Candidate) -> str:
        return template.format(first=a.name, second=b.name)

    swaps = []
    for p in others:
        goal = 0 if p.candidate is renamed else 1
        a, b = (p.candidate, second) if goal == 0 else (first, p.candidate)
        swaps.append(Counterfactual(say(a, b), p.id, (chosen[goal].name, p.candidate.name), goal=goal))
    order = _shorter_first(cfg, placements[:2])
    return Design(
        placements=tuple(sorted([*placements, basket], key=lambda p: p.slot)),
        target=order[0].id,
        template=template,
        instruction=say(first, second),
        counterfactuals=tuple(replace(cf, goal=order.index(placements[cf.goal])) for cf in swaps),
        task=_task(cfg, order[0].id, order[1].id, basket.id, basket.candidate.kind),
    )


def _shorter_first(cfg: ReferentConfig, named: list[Placement]) -> list[Placement]:
    """The two named in the order the oracle brings them (the instruction leaves it free, as LIBERO
    does): the shorter first. A thing let down beside a taller one in the basket comes down with a
    finger on it (the tomato sauce beside the orange juice rested on the rim)."""
    world = worlds.world(cfg.world)
    return sorted(named, key=lambda p: world.kind(p.candidate.kind).height)


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    """The groceries (the basket is no answer); in a kitchen, its things (its places are none)."""
    world = worlds.world(cfg.world)
    return object_alternatives(
        cfg, spec, [o.id for o in spec.objects if not world.kind(o.kind).is_site and o.kind not in _destinations(cfg)]
    )


def _destinations(cfg: ReferentConfig) -> set[str]:
    return {c.kind for c in cfg.role(_DESTINATION)}


def canonical(cfg: ReferentConfig, problem: libero.Problem) -> Design | None:
    """A LIBERO-10 task of the world's scenes. One that puts two of the groceries in the basket: its
    objects (each in the slot nearest its region), LIBERO's instruction, and a swap from each other
    grocery, the first name's and the second's in turn. Another: as `_own_task` lays it out. None
    for a task our programs do not do."""
    goals = libero_goals.goals(problem, worlds.world(cfg.world))
    if goals is None:
        return None
    if not _puts_both(cfg, problem, goals):
        return _own_task(cfg, problem, goals)
    named = {c.kind for c in _groceries(cfg)}
    placements = _as_libero_sets(cfg, problem)
    ids = [g.target for g in goals]
    words = [scenery.candidate(cfg, problem.objects[i]).name for i in ids]
    instruction = libero.language(problem.name)
    others = [p for p in placements if p.id not in ids and p.candidate.kind in named]
    swaps = tuple(
        Counterfactual(instruction.replace(words[k % 2], p.candidate.name, 1), p.id, (words[k % 2], p.candidate.name), goal=k % 2)
        for k, p in enumerate(others)
    )
    return Design(tuple(placements), goals[0].target, cfg.templates[0], instruction, swaps, libero_goals.task(goals))


def _as_libero_sets(cfg: ReferentConfig, problem: libero.Problem) -> list[Placement]:
    """A LIBERO problem's objects under its names, each in the table slot nearest its region (where it
    stands until LIBERO's state poses it)."""
    among = _table_slots(cfg)
    return [
        Placement(i, scenery.candidate(cfg, k), scenery.nearest_slot(cfg, problem, i, among)) for i, k in problem.objects.items()
    ]


def _puts_both(cfg: ReferentConfig, problem: libero.Problem, goals: tuple[Goal, ...]) -> bool:
    """Whether a task's goals are the type's: two of its groceries into its basket."""
    named = {c.kind for c in _groceries(cfg)}
    return (
        not _tasks_only(cfg)
        and len(goals) == 2
        and all(g.program == cfg.task.program and problem.objects.get(g.target) in named for g in goals)
        and all(problem.objects.get(g.params["destination"]) == _basket(cfg).kind for g in goals)
    )


def _own_task(cfg: ReferentConfig, problem: libero.Problem, goals: tuple[Goal, ...]) -> Design | None:
    """Another LIBERO-10 task (a kitchen's; the mugs onto the plates): its objects (each in the
    object slot nearest its region) and the places its goals name (in their `sites` slots),
    LIBERO's instruction, no swap (the module's docstring says why); None where a place it names
    has no slot (the table's region right of the plate, in the living room's layout)."""
    sites = _sites(cfg)
    if any(g.target not in problem.objects and g.target not in sites for g in goals):
        return None
    placements = _as_libero_sets(cfg, problem)
    named = dict.fromkeys(g.target for g in goals if g.target not in problem.objects)
    placements += [Placement(place, scenery.candidate(cfg, place), sites[place]) for place in named]
    return Design(
        tuple(placements), goals[0].target, cfg.templates[0], libero.language(problem.name), (), libero_goals.task(goals)
    )


def _layouts(cfg: ReferentConfig) -> list[tuple[frozenset[str], tuple[tuple[float, float], ...]]]:
    """Each "put both" task of LIBERO-10's in the world's scenes, by name: its groceries, and the
    centres of the regions its first and second stand in."""
    world, found = worlds.world(cfg.world), []
    for task in sorted(t for t in libero.tasks(world.suite) if world.stands(t)):
        problem = libero.problem(world.suite, task)
        goals = libero_goals.goals(problem, world)
        if goals is not None and _puts_both(cfg, problem, goals):
            design = canonical(cfg, problem)
            assert design is not None and design.task is not None
            named = (design.target, design.task.params[THEN][0]["target"])
            groceries = frozenset(problem.objects.values()) - {_basket(cfg).kind}
            found.append((groceries, tuple(problem.centre(problem.region_of(i)) for i in named)))
    return found


def shortcut(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """What a policy that learnt LIBERO-10's living room instead of its words does: it knows a scene
    by its groceries and puts in the basket whatever stands where that scene's task had its two (the
    first task by name, where two share a scene: only their words tell them apart); in a scene of
    no LIBERO-10 task, where the first task had them."""
    if not any(o.kind in _destinations(cfg) for o in spec.objects):  # a scene of one task (a kitchen's, the mugs'):
        return spec  # its layout asks what its words ask
    groceries = [o for o in spec.objects if o.kind != _basket(cfg).kind]
    layouts = _layouts(cfg)
    kinds = frozenset(o.kind for o in groceries)
    regions = next((where for known, where in layouts if known == kinds), layouts[0][1])

    def nearest(at: tuple[float, float], besides: str = "") -> str:
        return min((o for o in groceries if o.id != besides), key=lambda o: np.hypot(o.pos[0] - at[0], o.pos[1] - at[1])).id

    first = nearest(regions[0])
    then = [{**spec.task.params[THEN][0], "target": nearest(regions[1], besides=first)}]
    return replace(spec, target=first, task=replace(spec.task, params={**spec.task.params, THEN: then}))
