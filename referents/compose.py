"""Scene composers most referent types are built from: a target and distractors that differ in
the naming variable (`naming_design` is a whole type named by one word), and the two-axis
crossed scene in which no single word picks the target. Every choice goes through `Balance`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from core.spec import Counterfactual
from referents.balance import Balance
from referents.design import Design, Placement
from referents.schema import Candidate, ReferentConfig


def fill(template: str, candidate: Candidate, **words: str) -> str:
    """A template filled with the candidate's name and attributes (and any extra words)."""
    return template.format(name=candidate.name, **candidate.attributes, **words)


def slug(text: str) -> str:
    return text.replace(" ", "_")


def target_slot(cfg: ReferentConfig, balance: Balance, key: str, options: Sequence[int]) -> int:
    """The target's slot: least used for `key`, or always the canonical one under confound=position."""
    if cfg.confound == "position":
        canonical = cfg.layout.canonical(key)
        if canonical not in options:
            raise ValueError("the canonical slot is not free")
        return canonical
    return balance.pick(("target_slot", key), list(options), also="slot")


def choose_scene(
    cfg: ReferentConfig, balance: Balance, pool: Sequence[Candidate], naming: str, slots: Sequence[int] | None = None
) -> list[Placement]:
    """A target and `objects_per_scene - 1` distractors that each differ from every other in
    the naming variable, in `slots` (default: all of the layout's); the target comes first.

    The target value is the least-used one, its instance the least-used of that value, at its
    least-used slot; distractor values are the least-used as distractors, each instance at its
    least-used free slot.
    """
    for c in pool:
        if naming not in ("name", "key") and naming not in c.attributes:
            raise cfg.fail("objects", f"{c.key!r} has no {naming!r} attribute, which names targets (naming: {naming})")
    targets = [c for c in pool if c.targetable]
    value = balance.pick("target", list(dict.fromkeys(c.word(naming) for c in targets)))
    target = balance.pick(("instance", value), [c for c in targets if c.word(naming) == value])
    slots = list(range(len(cfg.layout.slots))) if slots is None else list(slots)
    placements = [Placement(slug(target.key), target, target_slot(cfg, balance, target.key, slots))]
    others = list(dict.fromkeys(c.word(naming) for c in pool if c.word(naming) != value))
    if len(others) < cfg.objects_per_scene - 1:
        raise cfg.fail("objects", f"needs {cfg.objects_per_scene} different {naming} values per scene, has {len(others) + 1}")
    for _ in range(cfg.objects_per_scene - 1):
        other = balance.pick("distractor", others)
        others.remove(other)
        d = balance.pick(("distractor_instance", other), [c for c in pool if c.word(naming) == other])
        free = [s for s in slots if s not in {p.slot for p in placements}]
        placements.append(Placement(slug(d.key), d, balance.pick(("distractor_slot", d.key), free, also="slot")))
    return placements


def naming_design(
    cfg: ReferentConfig, balance: Balance, pool: Sequence[Candidate] | None = None, slots: Sequence[int] | None = None
) -> Design:
    """One target named by a single word (its name, or an attribute) among distractors that
    each have another value of it (in `slots`, default all); the swap counterfactual names each
    distractor instead."""
    placements = choose_scene(cfg, balance, cfg.objects if pool is None else pool, cfg.naming, slots)
    target = placements[0].candidate
    template = balance.pick("template", cfg.templates)
    return Design(
        placements=tuple(sorted(placements, key=lambda p: p.slot)),
        target=placements[0].id,
        template=template,
        instruction=fill(template, target),
        counterfactuals=tuple(
            Counterfactual(fill(template, p.candidate), p.id, (target.word(cfg.naming), p.candidate.word(cfg.naming)))
            for p in placements[1:]
        ),
    )


@dataclass(frozen=True)
class Crossed:
    """Four objects crossing two values of an axis with two colors; `objects[(axis, color)]`."""

    placements: tuple[Placement, ...]
    objects: dict[tuple[str, str], Placement]
    axis: tuple[str, str]  # (target's value, the other)
    color: tuple[str, str]  # (target's color, the other)

    @property
    def target(self) -> Placement:
        return self.objects[(self.axis[0], self.color[0])]


def crossed_scene(cfg: ReferentConfig, balance: Balance, axis: str) -> Crossed:
    """Two values of `axis` (e.g. shape or size) x two colors: every object shares one attribute
    with two others, so no single word picks the target. The target is the least-used object;
    the other axis value and the other color are the least used alongside it; slots as usual."""
    table = {(c.word(axis), c.attributes.get("color", "")): c for c in cfg.objects}
    axis_values = list(dict.fromkeys(a for a, _ in table))
    colors = list(dict.fromkeys(col for _, col in table))
    if len(axis_values) < 2 or len(colors) < 2 or len(table) != len(axis_values) * len(colors):
        raise cfg.fail("objects", f"needs every {axis} in the same two or more colors")
    target = balance.pick("target", [c for c in cfg.objects if c.targetable])
    a_target, c_target = target.word(axis), target.attributes["color"]
    a_other = balance.pick(("other", axis, a_target), [a for a in axis_values if a != a_target])
    c_other = balance.pick(("other color", c_target), [col for col in colors if col != c_target])
    slots = list(range(len(cfg.layout.slots)))
    cells = [(a_target, c_target), (a_other, c_target), (a_target, c_other), (a_other, c_other)]
    objects: dict[tuple[str, str], Placement] = {}
    for i, cell in enumerate(cells):
        cand = table[cell]
        free = [s for s in slots if s not in {p.slot for p in objects.values()}]
        slot = (
            target_slot(cfg, balance, cand.key, free)
            if i == 0
            else balance.pick(("distractor_slot", cand.key), free, also="slot")
        )
        objects[cell] = Placement(slug(cand.key), cand, slot)
    return Crossed(tuple(sorted(objects.values(), key=lambda p: p.slot)), objects, (a_target, a_other), (c_target, c_other))
