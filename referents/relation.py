"""Relation referent: identical blocks left and right of an anchor; the side names the target.

Balanced: the anchor, the block color, the anchor's place (row and inner column) and the side
asked for. The swap counterfactual asks for the other side. Only the two blocks are
alternatives: the anchor is never what is asked for.
"""

from __future__ import annotations

from core.spec import Counterfactual, EpisodeSpec, SceneObject
from referents.balance import Balance
from referents.design import Design, Placement
from referents.schema import ReferentConfig
from referents.variables import POSITION, Alternative, Variable, object_alternatives

_SIDES = ("left", "right")


def validate(cfg: ReferentConfig) -> None:
    columns = cfg.need("columns", int)
    if columns < 3 or len(cfg.layout.slots) % columns:
        raise cfg.fail("columns", f"layout.slots must hold whole rows of {columns} (>= 3) places")
    if not cfg.role("anchor") or not cfg.role("referent"):
        raise cfg.fail("objects", "needs objects with role: referent and role: anchor")


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    columns = int(cfg.extra["columns"])
    anchor = balance.pick("anchor", cfg.role("anchor"))
    block = balance.pick("instance", [c for c in cfg.role("referent") if c.targetable])
    row = balance.pick("row", list(range(len(cfg.layout.slots) // columns)))
    column = balance.pick("anchor column", list(range(1, columns - 1)))
    side = balance.pick(("side", anchor.key), list(_SIDES), also="side")
    anchor_slot = row * columns + column
    ids = {s: f"{block.key.replace(' ', '_')}_{s}" for s in _SIDES}
    placements = (
        Placement(ids["left"], block, anchor_slot - 1),  # columns run from the robot's left
        Placement(anchor.key.replace(" ", "_"), anchor, anchor_slot),
        Placement(ids["right"], block, anchor_slot + 1),
    )
    template = balance.pick("template", cfg.templates)

    def say(s: str) -> str:
        return template.format(name=block.name, side=s, anchor=anchor.name, **block.attributes)

    other = _SIDES[1 - _SIDES.index(side)]
    return Design(
        placements=placements,
        target=ids[side],
        template=template,
        instruction=say(side),
        counterfactuals=(Counterfactual(say(other), ids[other], (side, other)),),
    )


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    anchor = next(o for o in spec.objects if o.kind != spec.object(spec.target).kind)
    blocks = [o for o in spec.objects if o is not anchor]

    def side(o: SceneObject) -> str:
        return "left" if o.pos[1] > anchor.pos[1] else "right"

    def extra(o: SceneObject) -> dict[str, Variable]:
        return {
            "side": Variable(side(o), POSITION),
            "anchor and side": Variable((anchor.name, side(o)), POSITION),
            "anchor slot and side": Variable((anchor.slot, side(o)), POSITION),
        }

    alts = object_alternatives(cfg, spec, [o.id for o in blocks], extra)
    return [Alternative(a.id, side(spec.object(a.id)), a.slot, a.variables) for a in alts]


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    """Two identical referents and one of each anchor."""
    kinds = dict.fromkeys(c.kind for c in cfg.objects)
    return [(k, 2 if any(c.kind == k for c in cfg.role("referent")) else 1) for k in kinds]
