"""The confound audit's view of an episode: the alternatives an instruction chooses among, and
the non-instruction variables of each.

Every variable declares its shortcut families where it is made: `POSITION` (it depends on where
the alternative stands) and `IDENTITY` (on which object it is). `confound=position` makes a
POSITION variable's leak expected; a vocabulary restriction (`distractor_only`, `targets`) an
IDENTITY variable's. A variable that crosses both (an attribute at a slot) declares both.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass

import numpy as np

from core.spec import EpisodeSpec, SceneObject
from referents.schema import ReferentConfig, object_key


class Family(enum.Flag):
    NONE = 0
    POSITION = enum.auto()
    IDENTITY = enum.auto()


POSITION, IDENTITY = Family.POSITION, Family.IDENTITY


@dataclass(frozen=True)
class Variable:
    """One variable's value for one alternative, and the families the variable belongs to."""

    value: Hashable
    family: Family = Family.NONE


@dataclass(frozen=True)
class Alternative:
    """One of the things an instruction could ask for in a scene, as the confound audit sees it:
    `value` is what the instruction would call it, `variables` its non-instruction variables."""

    id: str
    value: str
    slot: int
    variables: dict[str, Variable]


def object_variables(spec: EpisodeSpec, obj: SceneObject) -> dict[str, Variable]:
    """Non-instruction variables of one object, for the confound audit."""
    key = object_key(obj.name, obj.attributes)
    variables = {
        "slot": Variable(obj.slot, POSITION),
        "x bin (5 cm)": Variable(int(np.floor(obj.pos[0] / 0.05)), POSITION),
        "y bin (5 cm)": Variable(int(np.floor(obj.pos[1] / 0.05)), POSITION),
        "identity": Variable(key, IDENTITY),
        "kind": Variable(obj.kind, IDENTITY),
        "composition": Variable((tuple(sorted(object_key(o.name, o.attributes) for o in spec.objects)), key), IDENTITY),
    }
    for attr, value in obj.attributes.items():
        variables[f"{attr} at slot"] = Variable((value, obj.slot), POSITION | IDENTITY)
    return variables


def object_alternatives(
    cfg: ReferentConfig,
    spec: EpisodeSpec,
    ids: Sequence[str] | None = None,
    extra: Callable[[SceneObject], dict[str, Variable]] | None = None,
) -> list[Alternative]:
    """Objects as alternatives (all of the scene's, or `ids`), valued by the naming variable."""
    chosen = [spec.object(i) for i in ids] if ids is not None else list(spec.objects)
    out = []
    for o in chosen:
        key = object_key(o.name, o.attributes)
        value = {"name": o.name, "key": key}.get(cfg.naming) or o.attributes.get(cfg.naming, key)
        variables = object_variables(spec, o) | (extra(o) if extra else {})
        out.append(Alternative(o.id, value, o.slot, variables))
    return out
