"""Goal referent: carry an object to the destination the instruction names.

The target of a goal episode is the destination; `task.params.object` is what to carry. The
swap counterfactual names the other destination (its whole phrase, e.g. "on the plate" ->
"in the basket"); only destinations are alternatives.
"""

from __future__ import annotations

from core.spec import Counterfactual, EpisodeSpec, SceneObject, TaskSpec
from referents.balance import Balance
from referents.compose import slug
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig
from referents.variables import IDENTITY, POSITION, Alternative, Variable, object_alternatives


def validate(cfg: ReferentConfig) -> None:
    if len(cfg.role("destination")) < 2 or len(cfg.role("object")) < 2:
        raise cfg.fail("objects", "needs two or more objects with role: destination and with role: object")
    if cfg.objects_per_scene != 4:
        raise cfg.fail("objects_per_scene", "goal scenes hold exactly 4 objects: carried, other, two destinations")
    prepositions = cfg.extra.get("prepositions", {})
    if not isinstance(prepositions, dict) or not all(isinstance(v, str) for v in prepositions.values()):
        raise cfg.fail("prepositions", f"must map destination names to words, got {prepositions!r}")


def _phrase(cfg: ReferentConfig, destination: Candidate) -> str:
    return f"{cfg.extra.get('prepositions', {}).get(destination.name, 'on')} the {destination.name}"


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    destinations = cfg.role("destination")
    goal = balance.pick("target", [d for d in destinations if d.targetable])
    other = balance.pick(("other destination", goal.key), [d for d in destinations if d is not goal])
    carried = balance.pick(("carried", goal.key), cfg.role("object"), also="carried")
    extra = balance.pick("distractor", [o for o in cfg.role("object") if o is not carried])
    slots = list(range(len(cfg.layout.slots)))
    placements: list[Placement] = []
    for key, cand in (("target_slot", goal), ("other_slot", other), ("object_slot", carried), ("object_slot", extra)):
        free = [s for s in slots if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(cand.key), cand, balance.pick((key, cand.key), free, also="slot")))
    template = balance.pick("template", cfg.templates)

    def say(destination: Candidate) -> str:
        return template.format(object=carried.name, destination=_phrase(cfg, destination))

    return Design(
        placements=tuple(sorted(placements, key=lambda p: p.slot)),
        target=placements[0].id,
        template=template,
        instruction=say(goal),
        counterfactuals=(Counterfactual(say(other), placements[1].id, (_phrase(cfg, goal), _phrase(cfg, other))),),
        task=TaskSpec(program="place", params={"object": placements[2].id}),
    )


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    carried = spec.object(spec.task.params["object"])
    destinations = [o.id for o in spec.objects if o.kind in {c.kind for c in cfg.role("destination")}]

    def extra(o: SceneObject) -> dict[str, Variable]:
        return {
            "carried object and destination": Variable((carried.name, o.name), IDENTITY),
            "carried object slot and slot": Variable((carried.slot, o.slot), POSITION | IDENTITY),
        }

    return object_alternatives(cfg, spec, destinations, extra)
