"""LIBERO-Goal's goal axis: what the instruction asks is done where it says (see goal.yaml beside it).

The target of an episode is the place it names (a place on the stove or the cabinet, the wine
rack's shelf, the plate, the bowl, a drawer, the stove's knob, the table in front of the stove) and `task.params.object` is
what is moved there, where something is; the program is the task's: `place` carries the object
there, and the motions (`motions` in the spec) open a drawer, turn the knob on, push the plate, put
the bowl in a drawer it opens. The four objects stand in the table's places, each in every place
it may stand (`keep_off`) equally often, and the places on furniture are in every scene; every
task LIBERO-Goal asks that our skills can do is asked equally often. The swap keeps the program and the object and names another
of its places.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import numpy as np

from core import libero, programs, worlds
from core.furniture import Spot
from core.spec import Counterfactual, EpisodeSpec, SceneObject, TaskSpec
from referents import scenery
from referents.balance import Balance
from referents.compose import slug
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig
from referents.variables import IDENTITY, POSITION, Alternative, Variable, object_alternatives

CONFOUNDS = ("position", "layout")


def _goals(cfg: ReferentConfig) -> dict[str, list[str]]:
    """Where each carried object may go, less what `holdout=` keeps out of the scenes."""
    kept = {str(k): [str(d) for d in v if str(d) not in cfg.holdout] for k, v in cfg.need("goals", dict).items()}
    return {k: v for k, v in kept.items() if k not in cfg.holdout}


def _motions(cfg: ReferentConfig) -> dict[str, dict]:
    """The motions (program -> places, object moved, words), less what `holdout=` keeps out."""
    kept = {}
    for program, motion in cfg.extra.get("motions", {}).items():
        places = [str(p) for p in motion["places"] if str(p) not in cfg.holdout]
        if places and motion.get("object") not in cfg.holdout:
            kept[str(program)] = {**motion, "places": places}
    return kept


def _tasks(cfg: ReferentConfig, displaced: bool = True) -> list[tuple[str, str, str]]:
    """Every (program, object moved or "", place) an instruction may ask: each carried object to each
    of its aims, and each motion at each of its targetable places (`displaced`: only the motions
    asked in displaced scenes too, not those asked on LIBERO's own layout alone)."""
    carry = [(cfg.task.program, c, d) for c in _goals(cfg) for d in _aims(cfg, c)]
    return carry + [
        (p, str(m.get("object", "")), d)
        for p, m in _motions(cfg).items()
        for d in m["places"]
        if _named(cfg, d).targetable and (m.get("displaced", True) or not displaced)
    ]


def _others(cfg: ReferentConfig, program: str, carried: str, place: str) -> list[str]:
    """The places a swap of the task may name: the object's other places, or the motion's."""
    places = _motions(cfg)[program]["places"] if program in _motions(cfg) else _goals(cfg)[carried]
    return [d for d in places if d != place]


def _say(cfg: ReferentConfig, template: str, program: str, carried: str, place: str) -> str:
    """The instruction asking for a task: the template's words for carrying, a motion's own."""
    if program in _motions(cfg):
        return str(_motions(cfg)[program]["say"]).format(object=carried, place=place)
    return template.format(object=carried, destination=_phrase(cfg, place))


def _changed(cfg: ReferentConfig, program: str, place: str) -> str:
    """The words of an instruction that name its place."""
    return place if program in _motions(cfg) else _phrase(cfg, place)


def _aims(cfg: ReferentConfig, carried: str) -> list[str]:
    """The places `carried` may be asked to go: its goals that `targets=`/`distractor_only=` leave targetable."""
    return [d for d in _goals(cfg)[carried] if _named(cfg, d).targetable]


def _phrase(cfg: ReferentConfig, destination: str) -> str:
    return str(cfg.need("phrases", dict)[destination])


def _named(cfg: ReferentConfig, name: str) -> Candidate:
    return next(c for c in cfg.objects if c.name == name)


def _sites(cfg: ReferentConfig) -> dict[str, int]:
    """The places on furniture (site kinds) and their layout slots: `sites` in the spec."""
    return {str(k): int(v) for k, v in cfg.need("sites", dict).items()}


def _fixed(cfg: ReferentConfig) -> list[Placement]:
    """The places on furniture in every scene, each in its own slot (one `holdout=` keeps out is absent)."""
    return [Placement(slug(c.key), c, _sites(cfg)[c.name]) for c in cfg.objects if c.name in _sites(cfg)]


def _stands(cfg: ReferentConfig, name: str) -> list[int]:
    """The table's slots an object may stand in: all but those `keep_off` keeps it off."""
    off = {int(s) for s in cfg.extra.get("keep_off", {}).get(name, [])}
    return [s for s in _table_slots(cfg) if s not in off]


def _table_slots(cfg: ReferentConfig) -> list[int]:
    return [s for s in range(len(cfg.layout.slots)) if s not in _sites(cfg).values()]


def validate(cfg: ReferentConfig) -> None:
    names = {c.name for c in cfg.objects}
    if not all(isinstance(v, list) for v in cfg.need("goals", dict).values()):
        raise cfg.fail("goals", "maps each carried object's name to a list of the places it may go")
    goals = _goals(cfg)
    if not goals or any(k not in names or not v or any(d not in names for d in v) for k, v in goals.items()):
        raise cfg.fail("goals", "maps each carried object's name to the names of two or more places it may go")
    if any(len(v) < 2 for v in goals.values()):
        raise cfg.fail("goals", "each carried object needs two or more places: the swap names another")
    if any(d not in cfg.need("phrases", dict) for v in goals.values() for d in v):
        raise cfg.fail("phrases", "needs the words for every place in goals")
    motions = cfg.extra.get("motions", {})
    if not isinstance(motions, dict) or any(
        p not in programs.PROGRAMS
        or not isinstance(m, dict)
        or not isinstance(m.get("say"), str)
        or not isinstance(m.get("places"), list)
        or not {str(d) for d in m["places"]} <= names
        for p, m in motions.items()
    ):
        known = ", ".join(programs.PROGRAMS)
        raise cfg.fail("motions", f"maps programs ({known}) to their places (names of objects) and words (say)")
    if not _tasks(cfg):
        raise cfg.fail("targets" if cfg.targets else "distractor_only", "leaves no place any object may be asked to go")
    world = worlds.world(cfg.world)
    sited = {c.name for c in cfg.role("destination") if world.kind(c.kind).is_site}
    if set(_sites(cfg)) - set(cfg.holdout) != sited or not set(_sites(cfg).values()) <= set(range(len(cfg.layout.slots))):
        raise cfg.fail("sites", "maps each place on furniture (a destination of a site kind) to its slot of layout.slots")
    if len([c for c in cfg.objects if c.name not in sited]) > len(_table_slots(cfg)):
        raise cfg.fail("layout.slots", "needs a table slot per object besides the places on furniture")
    keep_off = cfg.extra.get("keep_off", {})
    if (
        not isinstance(keep_off, dict)
        or not set(keep_off) <= names
        or not all(isinstance(v, list) and all(isinstance(s, int) for s in v) for v in keep_off.values())
    ):
        raise cfg.fail("keep_off", "maps objects' names to the lists of table slots they never stand in")
    table = [c.name for c in cfg.objects if c.name not in sited]
    crowded = next(
        (
            group
            for k in range(1, len(table) + 1)
            for group in combinations(table, k)
            if len(set().union(*(_stands(cfg, n) for n in group))) < k
        ),
        None,
    )
    if crowded:
        raise cfg.fail("keep_off", f"leaves {', '.join(crowded)} fewer table slots than they are objects")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    if cfg.confound == "layout":
        return _as_liberos_task(cfg, balance)
    program, carried, goal = balance.pick("task", _tasks(cfg))
    others = _others(cfg, program, carried, goal)
    other = balance.pick(("other", program, carried, goal), others) if others else None
    placements: list[Placement] = []
    table = [c for c in cfg.objects if c.name not in _sites(cfg)]
    for cand in sorted(table, key=lambda c: len(_stands(cfg, c.name))):  # the most restricted first: each finds a place
        free = [s for s in _stands(cfg, cand.name) if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(cand.key), cand, balance.pick(("slot", cand.key), free, also="slot")))
    placements = sorted(placements, key=lambda p: table.index(p.candidate)) + _fixed(cfg)
    ids = {p.candidate.name: p.id for p in placements}
    template = balance.pick("template", cfg.templates)

    def say(place: str) -> str:
        return _say(cfg, template, program, carried, place)

    swaps = (
        []
        if other is None
        else [Counterfactual(say(other), ids[other], (_changed(cfg, program, goal), _changed(cfg, program, other)))]
    )
    return Design(
        placements=tuple(placements),
        target=ids[goal],
        template=template,
        instruction=say(goal),
        counterfactuals=tuple(swaps),
        task=TaskSpec(program=program, params={"object": ids[carried]} if carried else {}),
    )


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    moved = spec.task.params.get("object")
    carried = spec.object(moved) if moved else None
    named = spec.object(spec.target).name
    places = {named, *_others(cfg, spec.task.program, carried.name if carried else "", named)}
    destinations = [o.id for o in spec.objects if o.name in places]

    def extra(o: SceneObject) -> dict[str, Variable]:
        if carried is None:
            return {}
        return {
            "carried object and destination": Variable((carried.name, o.name), IDENTITY),
            "carried object slot and destination slot": Variable((carried.slot, o.slot), POSITION | IDENTITY),
        }

    return object_alternatives(cfg, spec, destinations, extra)


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    return [(c.kind, 1) for c in cfg.objects]


def _spot_names(spot: Spot | None) -> tuple[str, ...]:
    """The names LIBERO's goals may give a place on the furniture: its site's, its `goal_name`."""
    return tuple(n for n in (spot.site, spot.goal_name) if n) if spot else ()


def _destination(cfg: ReferentConfig, problem: libero.Problem, name: str) -> Candidate | None:
    """The place a BDDL name means: an object of the problem, or a place on the furniture (a fixture's
    site, or the name LIBERO's goals give a point of it: `goal_name`)."""
    world = worlds.world(cfg.world)
    kind = problem.objects.get(name)
    base = scenery.base_kind(cfg, kind) if kind is not None else None
    return next(
        (
            c
            for c in cfg.role("destination") + cfg.role("object")
            if c.kind == base or name in _spot_names(world.kind(c.kind).spot)
        ),
        None,
    )


def _task(cfg: ReferentConfig, problem: libero.Problem) -> tuple[str, str, str] | None:
    """A LIBERO-Goal problem's (program, object moved or "", place) among the tasks we ask, or None."""
    if len(problem.goal) != 1:
        return None
    predicate, *args = problem.goal[0]
    place = _destination(cfg, problem, args[-1])
    moved = problem.objects.get(args[0]) if len(args) == 2 else None
    carried = scenery.candidate(cfg, moved).name if moved is not None else ""
    if place is None or (len(args) == 2 and not carried):
        return None
    task = (_program(cfg, predicate, place.name), carried, place.name)
    return task if task in _tasks(cfg, displaced=False) else None


def _program(cfg: ReferentConfig, predicate: str, place: str) -> str:
    """The program doing LIBERO's goal `predicate` at `place`: the motion whose LIBERO predicate it
    is, at one of its places (`Open` a drawer, `On` the table before the stove is pushing there),
    else carrying (the spec's program)."""
    said = predicate.lower()
    doing = [p for p, m in _motions(cfg).items() if (programs.named(p).libero or "").lower() == said and place in m["places"]]
    return doing[0] if doing else cfg.task.program


def _as_liberos_task(cfg: ReferentConfig, balance: Balance) -> Design:
    """`confound=layout`: a LIBERO-Goal task (each our skills can do equally often) in LIBERO's one
    layout, as its demonstrations have it, asked with any template: where each thing stands never
    changes, so a policy can learn each task's motion without looking."""
    suite = worlds.world(cfg.world).suite
    doable = [task for task in libero.tasks(suite) if _task(cfg, libero.problem(suite, task)) is not None]
    problem = libero.problem(suite, balance.pick("task", doable))
    scene = canonical(cfg, problem, balance.pick("template", cfg.templates))
    assert scene is not None  # only doable tasks are picked
    return replace(scene, placements=_apart(cfg, problem, scene.placements))


def _apart(cfg: ReferentConfig, problem: libero.Problem, placements: tuple[Placement, ...]) -> tuple[Placement, ...]:
    """LIBERO's layout on our table's slots, each object in a slot of its own (the canonical exam
    may share one: LIBERO's initial states place its objects there): the nearest free one it may
    stand in (`keep_off`), the objects nearest a slot first. The wine bottle, whose place no slot
    is near, takes a free one; it is the same in every scene, as LIBERO's layout is."""
    slots, taken, placed = cfg.layout.slots, set(), {}

    def distance(p: Placement, slot: int) -> float:
        x, y = problem.centre(problem.region_of(p.id))
        return float(np.hypot(x - slots[slot][0], y - slots[slot][1]))

    table = [p for p in placements if p.slot in _table_slots(cfg)]
    for p in sorted(table, key=lambda p: min(distance(p, s) for s in _stands(cfg, p.candidate.name))):
        slot = min((s for s in _stands(cfg, p.candidate.name) if s not in taken), key=lambda s: distance(p, s))
        taken.add(slot)
        placed[p.id] = replace(p, slot=slot)
    return tuple(placed.get(p.id, p) for p in placements)


def canonical(cfg: ReferentConfig, problem: libero.Problem, template: str | None = None) -> Design | None:
    """A LIBERO-Goal task's own scene, if its goal is one of ours: its objects under LIBERO's instance
    names, LIBERO's instruction (or `template`'s), and a swap to each other place the task may name
    (the object's other places; the other drawer); None for a task our skills cannot do."""
    task = _task(cfg, problem)
    if task is None:
        return None
    program, carried, place = task
    placements = []
    for instance, kind in problem.objects.items():
        slot = scenery.nearest_slot(cfg, problem, instance, _table_slots(cfg))
        placements.append(Placement(instance, scenery.candidate(cfg, kind), slot))
    placements += _fixed(cfg)
    ids = {p.candidate.name: p.id for p in placements}

    def say(other: str) -> str:
        return _say(cfg, template or cfg.templates[0], program, carried, other)

    moved = {"object": ids[carried]} if carried else {}
    return Design(
        placements=tuple(placements),
        target=ids[place],
        template=template or cfg.templates[0],
        instruction=say(place) if template else libero.language(problem.name),
        counterfactuals=tuple(
            Counterfactual(say(d), ids[d], (_changed(cfg, program, place), _changed(cfg, program, d)))
            for d in _others(cfg, program, carried, place)
        ),
        task=TaskSpec(program=program, params=moved),
    )


def shortcut(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """What a policy that learnt LIBERO-Goal's one layout instead of looking does with the trial's
    task: it carries (or pushes) whatever stands where LIBERO stands that object to whatever stands
    where LIBERO stands that place (the furniture's places, and its motions, never move). Like every shortcut it does not
    read the instruction, so on LIBERO's own states it does the task and no swap."""
    suite = worlds.world(cfg.world).suite
    problem = libero.problem(suite, libero.tasks(suite)[0])
    remembered = {problem.objects[i]: problem.centre(problem.region_of(i)) for i in problem.objects}
    table = [o for o in spec.objects if scenery.base_kind(cfg, o.kind) in remembered]

    def nearest(kind: str, besides: str = "") -> str:
        x, y = remembered[scenery.base_kind(cfg, kind)]
        return min((o for o in table if o.id != besides), key=lambda o: np.hypot(o.pos[0] - x, o.pos[1] - y)).id

    if "object" not in spec.task.params:  # a motion of the furniture: where it always is
        return spec
    named = spec.object(spec.target)
    destination = nearest(named.kind) if scenery.base_kind(cfg, named.kind) in remembered else named.id
    carried = nearest(spec.object(spec.task.params["object"]).kind, besides=destination)
    return replace(spec, target=destination, task=replace(spec.task, params={**spec.task.params, "object": carried}))
