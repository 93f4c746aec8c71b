"""LIBERO-Goal's goal axis: the named object goes where the instruction says (see goal.yaml beside it).

The target of an episode is the destination (a place on the stove or the cabinet, the plate, the
bowl) and `task.params.object` is what to carry, as in the goal referent; the four objects stand
in the table's places, each in every place equally often, and the stove's burner and the
cabinet's top are in every scene. The swap keeps the object and names another of its places.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import libero, worlds
from core.spec import Counterfactual, EpisodeSpec, SceneObject, TaskSpec
from referents import scenery
from referents.balance import Balance
from referents.compose import slug
from referents.design import Design, Placement
from referents.features import IDENTITY, POSITION, Alternative, Feature, object_alternatives
from referents.schema import Candidate, ReferentConfig

CONFOUNDS = ("position",)


def _goals(cfg: ReferentConfig) -> dict[str, list[str]]:
    """Where each carried object may go, less what `holdout=` keeps out of the scenes."""
    kept = {str(k): [str(d) for d in v if str(d) not in cfg.holdout] for k, v in cfg.need("goals", dict).items()}
    return {k: v for k, v in kept.items() if k not in cfg.holdout}


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


def _table_slots(cfg: ReferentConfig) -> list[int]:
    return [s for s in range(len(cfg.layout.slots)) if s not in _sites(cfg).values()]


def validate(cfg: ReferentConfig) -> None:
    names = {c.name for c in cfg.objects}
    goals = _goals(cfg)
    if not goals or any(k not in names or not v or any(d not in names for d in v) for k, v in goals.items()):
        raise cfg.fail("goals", "maps each carried object's name to the names of two or more places it may go")
    if any(len(v) < 2 for v in goals.values()):
        raise cfg.fail("goals", "each carried object needs two or more places: the swap names another")
    if any(d not in cfg.need("phrases", dict) for v in goals.values() for d in v):
        raise cfg.fail("phrases", "needs the words for every place in goals")
    if not any(_aims(cfg, carried) for carried in goals):
        raise cfg.fail("targets" if cfg.targets else "distractor_only", "leaves no place any object may be asked to go")
    world = worlds.world(cfg.world)
    sited = {c.name for c in cfg.role("destination") if world.kind(c.kind).is_site}
    if set(_sites(cfg)) - set(cfg.holdout) != sited or not set(_sites(cfg).values()) <= set(range(len(cfg.layout.slots))):
        raise cfg.fail("sites", "maps each place on furniture (a destination of a site kind) to its slot of layout.slots")
    if len([c for c in cfg.objects if c.name not in sited]) > len(_table_slots(cfg)):
        raise cfg.fail("layout.slots", "needs a table slot per object besides the places on furniture")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    goals = _goals(cfg)
    carried = _named(cfg, balance.pick("carried", [c for c in goals if _aims(cfg, c)]))
    goal = balance.pick(("goal", carried.name), _aims(cfg, carried.name))
    other = balance.pick(("other", carried.name, goal), [d for d in goals[carried.name] if d != goal])
    placements: list[Placement] = []
    for cand in (c for c in cfg.objects if c.name not in _sites(cfg)):
        free = [s for s in _table_slots(cfg) if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(cand.key), cand, balance.pick(("slot", cand.key), free, also="slot")))
    placements += _fixed(cfg)
    ids = {p.candidate.name: p.id for p in placements}
    template = balance.pick("template", cfg.templates)

    def say(destination: str) -> str:
        return template.format(object=carried.name, destination=_phrase(cfg, destination))

    return Design(
        placements=tuple(placements),
        target=ids[goal],
        template=template,
        instruction=say(goal),
        counterfactuals=(Counterfactual(say(other), ids[other], (_phrase(cfg, goal), _phrase(cfg, other))),),
        task=TaskSpec(program=cfg.task.program, params={"object": ids[carried.name]}),
    )


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    carried = spec.object(spec.task.params["object"])
    places = set(_goals(cfg)[carried.name])
    destinations = [o.id for o in spec.objects if o.name in places]

    def extra(o: SceneObject) -> dict[str, Feature]:
        return {
            "carried object and destination": Feature((carried.name, o.name), IDENTITY),
            "carried object slot and destination slot": Feature((carried.slot, o.slot), POSITION | IDENTITY),
        }

    return object_alternatives(cfg, spec, destinations, extra)


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    return [(c.kind, 1) for c in cfg.objects]


def _destination(cfg: ReferentConfig, problem: libero.Problem, name: str) -> Candidate | None:
    """The place a BDDL name means: an object of the problem, or a fixture's site."""
    world = worlds.world(cfg.world)
    kind = problem.objects.get(name)
    base = scenery.base_kind(cfg, kind) if kind is not None else None
    return next(
        (
            c
            for c in cfg.role("destination") + cfg.role("object")
            if c.kind == base or world.kind(c.kind).params.get("site") == name
        ),
        None,
    )


def canonical(cfg: ReferentConfig, problem: libero.Problem) -> Design | None:
    """A LIBERO-Goal task's own scene, if its goal is one of ours (`On <object> <place>`): its
    objects under LIBERO's instance names, LIBERO's instruction, and a swap to each other place
    the object may go; None for the tasks our skills cannot do (drawers, the knob, pushing)."""
    predicate, *args = problem.goal[0]
    if predicate.lower() != "on" or len(problem.goal) != 1:
        return None
    carried, destination = problem.objects.get(args[0]), _destination(cfg, problem, args[1])
    carried_name = scenery.candidate(cfg, carried).name if carried is not None else None
    if carried_name is None or destination is None or destination.name not in _goals(cfg).get(carried_name, []):
        return None
    slots = cfg.layout.slots
    placements = []
    for instance, kind in problem.objects.items():
        x, y = problem.centre(problem.region_of(instance))
        table = _table_slots(cfg)
        slot = table[int(np.argmin([np.hypot(x - sx, y - sy) for sx, sy, *_ in (slots[s] for s in table)]))]
        placements.append(Placement(instance, scenery.candidate(cfg, kind), slot))
    placements += _fixed(cfg)
    ids = {p.candidate.name: p.id for p in placements}
    template = cfg.templates[0]

    def say(place: str) -> str:
        return template.format(object=carried_name, destination=_phrase(cfg, place))

    others = [d for d in _goals(cfg)[carried_name] if d != destination.name]
    return Design(
        placements=tuple(placements),
        target=ids[destination.name],
        template=template,
        instruction=libero.language(problem.name),
        counterfactuals=tuple(Counterfactual(say(d), ids[d], (_phrase(cfg, destination.name), _phrase(cfg, d))) for d in others),
        task=TaskSpec(program=cfg.task.program, params={"object": args[0]}),
    )


def shortcut(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """What a policy that learnt LIBERO-Goal's one layout instead of looking does with the trial's
    task: it carries whatever stands where LIBERO stands that object to whatever stands where
    LIBERO stands that place (the furniture's places never move). Like every shortcut it does not
    read the instruction, so on LIBERO's own states it does the task and no swap."""
    suite = worlds.world(cfg.world).suite
    problem = libero.problem(suite, libero.tasks(suite)[0])
    remembered = {problem.objects[i]: problem.centre(problem.region_of(i)) for i in problem.objects}
    table = [o for o in spec.objects if scenery.base_kind(cfg, o.kind) in remembered]

    def nearest(kind: str, besides: str = "") -> str:
        x, y = remembered[scenery.base_kind(cfg, kind)]
        return min((o for o in table if o.id != besides), key=lambda o: np.hypot(o.pos[0] - x, o.pos[1] - y)).id

    named = spec.object(spec.target)
    destination = nearest(named.kind) if scenery.base_kind(cfg, named.kind) in remembered else named.id
    carried = nearest(spec.object(spec.task.params["object"]).kind, besides=destination)
    return replace(spec, target=destination, task=replace(spec.task, params={**spec.task.params, "object": carried}))
