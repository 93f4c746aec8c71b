"""Object referent: the instruction names the target by its noun.

Roles are balanced greedily: the target is the least-used object, at its least-used slot;
distractors are the least-used as distractors, each at its least-used free slot. The swap
counterfactual names each distractor instead.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gen.spec import Counterfactual, EpisodeSpec
from referents.base import Balance, Design, Placement, ReferentConfig, fill

if TYPE_CHECKING:
    from oracle.skills import Skills


def object_id(name: str) -> str:
    return name.replace(" ", "_")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    slots = list(range(len(cfg.layout.slots)))
    target = balance.pick("target", cfg.objects)
    target_slot = balance.pick(("target_slot", target.key), slots, also="slot")
    placements = [Placement(object_id(target.name), target, target_slot)]
    others = [c for c in cfg.objects if c is not target]
    for _ in range(cfg.objects_per_scene - 1):
        d = balance.pick("distractor", others)
        others.remove(d)
        free = [s for s in slots if s not in {p.slot for p in placements}]
        placements.append(Placement(object_id(d.name), d, balance.pick(("distractor_slot", d.key), free, also="slot")))
    template = balance.pick("template", cfg.templates)
    return Design(
        placements=tuple(sorted(placements, key=lambda p: p.slot)),
        target=placements[0].id,
        template=template,
        instruction=fill(template, name=target.name),
        counterfactuals=tuple(
            Counterfactual(fill(template, name=p.candidate.name), p.id, (target.name, p.candidate.name))
            for p in placements[1:]
        ),
    )


def demo(skills: Skills, spec: EpisodeSpec) -> None:
    skills.grasp(spec.target)
    skills.lift()
