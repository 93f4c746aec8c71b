"""LIBERO-Spatial's relation axis: the black bowl named by where it stands goes on the plate (see
relation.yaml beside it).

A scene is a pair of places (any two whose words mention nothing in common and that stand
`min_gap` apart) with an identical bowl in each: every place is the named one equally often, and
the other place is drawn evenly among those it can share a scene with; the plate, the cookie box
and the ramekin stand in their LIBERO places in every scene. The swap names the other bowl by its
own place. Only the two bowls are alternatives.
"""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import replace as replaced
from itertools import combinations

import numpy as np

from core import libero, worlds
from core.spec import Counterfactual, EpisodeSpec, SceneObject, TaskSpec
from referents import scenery
from referents.balance import Balance
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig
from referents.variables import POSITION, Alternative, Variable, object_alternatives

CONFOUNDS = ("position", "layout")


@dataclass(frozen=True)
class _Place:
    """Where a bowl may stand: its layout slot (None: only LIBERO's initial states use it), the
    words that say so, what they mention, and the BDDL region LIBERO's tasks put a bowl in there."""

    slot: int | None
    says: str
    mentions: frozenset[str]
    region: str


def _places(cfg: ReferentConfig, elsewhere: bool = False) -> list[_Place]:
    fields = cfg.need("places", list) + (cfg.extra.get("elsewhere", []) if elsewhere else [])
    return [_Place(f.get("slot"), str(f["says"]), frozenset(f.get("mentions", [])), str(f["region"])) for f in fields]


def _slot(place: _Place) -> int:
    assert place.slot is not None, f"{place.says!r} has no layout slot"
    return place.slot


def _pairs(cfg: ReferentConfig) -> list[tuple[_Place, _Place]]:
    """The pairs of places two bowls can stand in: apart, said without a word in common, and
    neither held out (`holdout=` may name places)."""
    gap = float(cfg.extra.get("min_gap", 0.12))
    slots = cfg.layout.slots
    kept = [p for p in _places(cfg) if p.says not in cfg.holdout]
    return [
        (a, b)
        for a, b in combinations(kept, 2)
        if not a.mentions & b.mentions and np.hypot(*np.subtract(slots[_slot(a)][:2], slots[_slot(b)][:2])) >= gap
    ]


def _nameable(cfg: ReferentConfig, place: _Place) -> bool:
    """Whether the bowl there may be the named one: `targets=` and `distractor_only=` may name places."""
    said = [v for v in cfg.targets if v in words(cfg)]
    return place.says not in cfg.distractor_only and (not said or place.says in said)


def words(cfg: ReferentConfig) -> tuple[str, ...]:
    """The places bowls stand in, as the instruction says them (what the card lists as values)."""
    return tuple(p.says for p in _places(cfg))


def _bowl(cfg: ReferentConfig) -> Candidate:
    return cfg.role("referent")[0]


def _others(cfg: ReferentConfig) -> list[Placement]:
    """The plate, the cookie box and the ramekin, in the layout's slots after the bowls' places."""
    first = len(_places(cfg))
    stands = [*cfg.role("destination"), *cfg.role("fixed")]
    return [Placement(c.name.replace(" ", "_"), c, first + i) for i, c in enumerate(stands)]


def validate(cfg: ReferentConfig) -> None:
    gap = cfg.extra.get("min_gap", 0.12)
    if isinstance(gap, bool) or not isinstance(gap, (int, float)) or not gap >= 0:
        raise cfg.fail("min_gap", f"must be a distance in metres (>= 0), got {gap!r}")
    try:
        found = _places(cfg, elsewhere=True)
    except (KeyError, TypeError, AttributeError):
        raise cfg.fail("places", "each place needs says and region (and slot, mentions)") from None
    if any(p.slot is None or not 0 <= p.slot < len(cfg.layout.slots) for p in found[: len(_places(cfg))]):
        raise cfg.fail("places", "each place needs a slot of layout.slots")
    if len(cfg.layout.slots) != len(_places(cfg)) + len(cfg.role("destination")) + len(cfg.role("fixed")):
        raise cfg.fail("layout.slots", "needs one slot per place, then the destination's and each fixed object's")
    if len(cfg.role("referent")) != 1 or len(cfg.role("destination")) != 1:
        raise cfg.fail("objects", "needs one object with role: referent (the bowl) and one with role: destination")
    if not _pairs(cfg):
        raise cfg.fail("places", "no two places can hold the two bowls together")
    if cfg.confound == "layout" and not _liberos_pairs(cfg):
        raise cfg.fail("confound", "no LIBERO-Spatial task stands both its bowls in places of ours")
    if not any(_nameable(cfg, p) for pair in _pairs(cfg) for p in pair):
        raise cfg.fail("targets" if cfg.targets else "distractor_only", "leaves no place whose bowl can be named")


def _standing(cfg: ReferentConfig, place: _Place) -> Candidate:
    """The bowl, with where it stands as its `relation` (what the instruction names it by)."""
    bowl = _bowl(cfg)
    return replaced(bowl, attributes={**bowl.attributes, cfg.naming: place.says})


def _say(template: str, place: _Place) -> str:
    return template.format(relation=place.says)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    at = {p.region: p for p in _places(cfg)}
    if cfg.confound == "layout":
        named, other = (at[region] for region in balance.pick("task", _liberos_pairs(cfg)))
        return _scene(cfg, balance, named, other)
    partners: dict[str, list[str]] = {}
    for a, b in _pairs(cfg):
        partners.setdefault(a.region, []).append(b.region)
        partners.setdefault(b.region, []).append(a.region)
    named = at[balance.pick("named", [region for region in partners if _nameable(cfg, at[region])])]
    other = at[balance.pick(("other", named.region), partners[named.region], also="present")]
    return _scene(cfg, balance, named, other)


def _liberos_pairs(cfg: ReferentConfig) -> list[tuple[str, str]]:
    """`confound=layout`: (named bowl's region, other bowl's region) of each LIBERO-Spatial task whose
    two bowls both stand in places of ours, as LIBERO's demonstrations lay them out: each place named
    is always beside the same other place, so the layout says which bowl is meant."""
    at = {p.region for p in _places(cfg)}
    suite, pairs = worlds.world(cfg.world).suite, []
    for task in libero.tasks(suite):
        problem = libero.problem(suite, task)
        where = problem.placed()
        target = problem.goal[0][1]  # (On <bowl> plate_1)
        other = [i for i, k in problem.objects.items() if k == _bowl(cfg).kind and i != target]
        if where.get(target) in at and len(other) == 1 and where.get(other[0]) in at:
            pairs.append((where[target], where[other[0]]))
    return pairs


def _scene(cfg: ReferentConfig, balance: Balance, named: _Place, other: _Place) -> Design:
    """The two bowls in their places (the named one and the other), the rest in LIBERO's places."""
    first, second = sorted((named, other), key=_slot)  # ids by place, not by role
    template = balance.pick("template", cfg.templates)
    ids = {first.region: "bowl_a", second.region: "bowl_b"}
    bowls = tuple(Placement(ids[p.region], _standing(cfg, p), _slot(p)) for p in (first, second))
    destination = _others(cfg)[0]
    return Design(
        placements=(*bowls, *_others(cfg)),
        target=ids[named.region],
        template=template,
        instruction=_say(template, named),
        counterfactuals=(Counterfactual(_say(template, other), ids[other.region], (named.says, other.says)),),
        task=replaced(cfg.task, params={**cfg.task.params, "destination": destination.id}),
    )


def _place_of(cfg: ReferentConfig, obj: SceneObject) -> _Place:
    """The place a bowl of a scene stands in (its `relation`; a region no place names, where
    LIBERO-PRO's `_swap` moved it, is its own place)."""
    said = obj.attributes[cfg.naming]
    return next((p for p in _places(cfg, elsewhere=True) if p.says == said), _Place(None, said, frozenset(), said))


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    bowls = [o.id for o in spec.objects if o.kind == _bowl(cfg).kind]

    def extra(o: SceneObject) -> dict[str, Variable]:
        return {"place": Variable(_place_of(cfg, o).region, POSITION)}

    return object_alternatives(cfg, spec, bowls, extra)


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    """Two identical bowls, one of everything else."""
    return [(c.kind, 2 if c.role == "referent" else 1) for c in cfg.objects]


def canonical(cfg: ReferentConfig, problem: libero.Problem) -> Design | None:
    """A LIBERO-Spatial task's scene (LIBERO-PRO's too: referents/scenery.py): its objects under
    LIBERO's instance names (each in the slot of its place), LIBERO's instruction, and the swap to
    the other bowl, named by its own place."""
    at = {p.region: p for p in _places(cfg, elsewhere=True)}
    copies = {kind: scenery.base_kind(cfg, kind) for kind in problem.objects.values()}

    def plain(region: str) -> str:  # LIBERO-PRO names a region after a recoloured copy: `between_yellow_plate_...`
        if region in at:
            return region
        for kind, base in copies.items():
            region = region.replace(f"_{kind}_", f"_{base}_")
        return region

    where = {instance: plain(on) for instance, on in problem.placed().items()}
    target = problem.goal[0][1]  # (On <bowl> plate_1)
    bowl = _bowl(cfg).kind
    placements = []
    for instance, kind in problem.objects.items():
        region = where.get(instance, "")
        place = at.get(region, _Place(None, region, frozenset(), region)) if scenery.base_kind(cfg, kind) == bowl else None
        fixed = next((p.slot for p in _others(cfg) if p.candidate.kind == scenery.base_kind(cfg, kind)), None)
        slot = fixed if fixed is not None else (place.slot if place is not None and place.slot is not None else 0)
        named = replaced(_standing(cfg, place), kind=kind) if place is not None else scenery.candidate(cfg, kind)
        placements.append(Placement(instance, named, slot))
    if problem.objects.get(target) is None or scenery.base_kind(cfg, problem.objects[target]) != bowl:
        return None  # LIBERO-PRO's `_task` asks for another bowl than LIBERO's places name
    other = next(p.id for p in placements if scenery.base_kind(cfg, p.candidate.kind) == bowl and p.id != target)
    template = cfg.templates[0]
    said = at.get(where[target])
    # the swap names the other bowl by its place, where a place's words say where it stands
    swap = (
        (Counterfactual(_say(template, at[where[other]]), other, (said.says if said else where[target], at[where[other]].says)),)
        if where[other] in at
        else ()
    )
    return Design(
        placements=tuple(placements),
        target=target,
        template=template,
        instruction=libero.language(problem.name),
        counterfactuals=swap,
        task=TaskSpec(program=cfg.task.program, params={"destination": problem.goal[0][2]}),
    )


def shortcut(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """What a policy that learnt LIBERO-Spatial's layouts instead of its words does: it fetches
    the bowl standing where LIBERO's first task whose bowls stand as these do puts its named bowl
    (a pair of places no task uses: where the first task naming either place puts it)."""
    bowl = _bowl(cfg).kind
    bowls = {_place_of(cfg, o).region: o.id for o in spec.objects if scenery.base_kind(cfg, o.kind) == bowl}
    suite = worlds.world(cfg.world).suite
    layouts = []
    for task in libero.tasks(suite):
        problem = libero.problem(suite, task)
        where = problem.placed()
        named = where[problem.goal[0][1]]
        layouts.append(({where[i] for i, k in problem.objects.items() if k == bowl}, named))
    remembered = next((named for regions, named in layouts if regions == set(bowls)), None)
    remembered = remembered or next((named for _, named in layouts if named in bowls), next(iter(bowls)))
    return replaced(spec, target=bowls[remembered])
