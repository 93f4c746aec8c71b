"""Ordinal referent: a row of identical blocks; the target is named by its rank counted from
one side ("the second block from the left"; the final one may be called "last").

Balanced: row length, row (x), start column, the target's place in the row (per length) and the
counted side. The swap counterfactual names each other block by its rank from the same side.
"""

from __future__ import annotations

from core.spec import Counterfactual, EpisodeSpec, SceneObject
from referents import destination
from referents.balance import Balance
from referents.design import Design, Placement
from referents.schema import ReferentConfig
from referents.variables import POSITION, Alternative, Variable, object_alternatives

_LAST = "last"


def validate(cfg: ReferentConfig) -> None:
    lengths = cfg.need("row_lengths", list)
    ordinals = cfg.need("ordinals", list)
    columns = _columns(cfg)
    if columns < 2:
        raise cfg.fail("columns", f"a row needs two or more places, got {columns}")
    if len(destination.inner(cfg).layout.slots) % columns:
        held = " besides the container's last slot" if destination.container(cfg) else ""
        raise cfg.fail("layout.slots", f"must hold whole rows of {columns} places{held}")
    if not lengths or min(lengths) < 2 or max(lengths) > min(columns, len(ordinals), cfg.objects_per_scene):
        raise cfg.fail(
            "row_lengths",
            f"each must be 2..{min(columns, len(ordinals), cfg.objects_per_scene)} (columns, ordinals, objects_per_scene)",
        )


def _columns(cfg: ReferentConfig) -> int:
    return int(cfg.need("columns", int))


def _rank(pos: int, length: int, side: str) -> int:
    """1-based rank of place `pos` (0 = leftmost) counted from `side`."""
    return pos + 1 if side == "left" else length - pos


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    columns = _columns(cfg)
    rows = len(cfg.layout.slots) // columns
    length = balance.pick("row length", list(cfg.extra["row_lengths"]))
    row = balance.pick("row", list(range(rows)))
    start = balance.pick(("start", length), list(range(columns - length + 1)))
    target_pos = balance.pick(("place in row", length), list(range(length)))
    side = balance.pick("side", ["left", "right"])
    block = balance.pick("instance", [c for c in cfg.objects if c.targetable])
    ordinals = list(cfg.extra["ordinals"])
    rank = _rank(target_pos, length, side)
    word = _LAST if rank == length and balance.pick(("say last", length), [True, False]) else ordinals[rank - 1]
    template = balance.pick("template", cfg.templates)
    ids = [f"{block.key.replace(' ', '_')}_{p + 1}" for p in range(length)]
    placements = tuple(Placement(ids[p], block, row * columns + start + p) for p in range(length))

    def say(ordinal: str) -> str:
        return template.format(ordinal=ordinal, side=side, name=block.name, **block.attributes)

    return Design(
        placements=placements,
        target=ids[target_pos],
        template=template,
        instruction=say(word),
        counterfactuals=tuple(
            Counterfactual(say(ordinals[_rank(p, length, side) - 1]), ids[p], (word, ordinals[_rank(p, length, side) - 1]))
            for p in range(length)
            if p != target_pos
        ),
    )


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    columns = _columns(cfg)
    row = sorted(spec.objects, key=lambda o: o.slot)
    place = {o.id: i for i, o in enumerate(row)}
    length = len(row)

    def extra(o: SceneObject) -> dict[str, Variable]:
        p = place[o.id]
        return {
            "rank from left": Variable(p, POSITION),
            "rank from right": Variable(length - 1 - p, POSITION),
            "row length and rank": Variable((length, p), POSITION),
            "column": Variable(o.slot % columns, POSITION),
        }

    alts = object_alternatives(cfg, spec, extra=extra)
    return [Alternative(a.id, f"place {place[a.id] + 1} of {length}", a.slot, a.variables) for a in alts]


def assets(cfg: ReferentConfig) -> list[tuple[str, int]]:
    """A whole row of identical blocks."""
    return [(kind, cfg.objects_per_scene) for kind in dict.fromkeys(c.kind for c in cfg.objects)]
