"""Negation referent: "the <shape> that is not <color>" over a 2 shapes x 2 colors scene.

Counterfactuals: flip the negated color (the same shape's other object becomes the target) and
swap the shape word (the other shape's object of the target's color becomes the target).
"""

from __future__ import annotations

from core.spec import Counterfactual
from referents.balance import Balance
from referents.compose import crossed_scene
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    scene = crossed_scene(cfg, balance, "name")
    (shape, other_shape), (color, other_color) = scene.axis, scene.color
    template = balance.pick("template", cfg.templates)

    def say(name: str, negated: str) -> str:
        return template.format(name=name, negated=negated)

    return Design(
        placements=scene.placements,
        target=scene.target.id,
        template=template,
        instruction=say(shape, other_color),
        counterfactuals=(
            Counterfactual(say(shape, color), scene.objects[(shape, other_color)].id, (other_color, color)),
            Counterfactual(say(other_shape, other_color), scene.objects[(other_shape, color)].id, (shape, other_shape)),
        ),
    )


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    return [(kind, 2) for kind in dict.fromkeys(c.kind for c in cfg.objects)]
