"""Composition referent: two attributes together name the target, over a 2 x 2 scene: color and
the spec's `crossed` attribute (default size; `name` crosses color with what the object is).
Counterfactuals change one attribute: the crossed word, or the color word."""

from __future__ import annotations

from core.spec import Counterfactual
from referents.balance import Balance
from referents.compose import crossed_scene, fill
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def validate(cfg: ReferentConfig) -> None:
    crossed = cfg.extra.get("crossed", "size")
    if not isinstance(crossed, str) or not all(crossed in ("name", "key") or crossed in c.attributes for c in cfg.objects):
        raise cfg.fail("crossed", f"names the attribute crossed with color, which every object has (or name); got {crossed!r}")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    scene = crossed_scene(cfg, balance, str(cfg.extra.get("crossed", "size")))
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
