"""Composition referent: size and color together name the target, over a 2 sizes x 2 colors
scene. Counterfactuals change one attribute: the size word, or the color word."""

from __future__ import annotations

from core.spec import Counterfactual
from referents.balance import Balance
from referents.compose import crossed_scene, fill
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    scene = crossed_scene(cfg, balance, "size")
    (size, other_size), (color, other_color) = scene.axis, scene.color
    template = balance.pick("template", cfg.templates)
    by_size = scene.objects[(other_size, color)]
    by_color = scene.objects[(size, other_color)]
    return Design(
        placements=scene.placements,
        target=scene.target.id,
        template=template,
        instruction=fill(template, scene.target.candidate),
        counterfactuals=(
            Counterfactual(fill(template, by_size.candidate), by_size.id, (size, other_size)),
            Counterfactual(fill(template, by_color.candidate), by_color.id, (color, other_color)),
        ),
    )


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    return [(kind, 2) for kind in dict.fromkeys(c.kind for c in cfg.objects)]
