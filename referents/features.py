"""The confound audit's view of an episode: the alternatives an instruction chooses among, and
the non-instruction variables (features) of each.

Every feature declares its shortcut families where it is made: `POSITION` (it depends on where
the alternative stands) and `IDENTITY` (on which object it is). `confound=position` makes a
POSITION feature's leak expected; a vocabulary restriction (`distractor_only`, `targets`) an
IDENTITY feature's. A feature that crosses both (an attribute at a slot) declares both.
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
class Feature:
    """One variable's value for one alternative, and the families the variable belongs to."""

    value: Hashable
    family: Family = Family.NONE


@dataclass(frozen=True)
class Alternative:
    """One of the things an instruction could ask for in a scene, as the confound audit sees it:
    `value` is what the instruction would call it, `features` are non-instruction variables."""

    id: str
    value: str
    slot: int
    features: dict[str, Feature]


def object_features(spec: EpisodeSpec, obj: SceneObject) -> dict[str, Feature]:
    """Non-instruction variables of one object, for the confound audit."""
    key = object_key(obj.name, obj.attributes)
    features = {
        "slot": Feature(obj.slot, POSITION),
        "x bin (5 cm)": Feature(int(np.floor(obj.pos[0] / 0.05)), POSITION),
        "y bin (5 cm)": Feature(int(np.floor(obj.pos[1] / 0.05)), POSITION),
        "identity": Feature(key, IDENTITY),
        "kind": Feature(obj.kind, IDENTITY),
        "composition": Feature((tuple(sorted(object_key(o.name, o.attributes) for o in spec.objects)), key), IDENTITY),
    }
    for attr, value in obj.attributes.items():
        features[f"{attr} at slot"] = Feature((value, obj.slot), POSITION | IDENTITY)
    return features


def object_alternatives(
    cfg: ReferentConfig,
    spec: EpisodeSpec,
    ids: Sequence[str] | None = None,
    extra: Callable[[SceneObject], dict[str, Feature]] | None = None,
) -> list[Alternative]:
    """Objects as alternatives (all of the scene's, or `ids`), valued by the naming variable."""
    chosen = [spec.object(i) for i in ids] if ids is not None else list(spec.objects)
    out = []
    for o in chosen:
        key = object_key(o.name, o.attributes)
        value = {"name": o.name, "key": key}.get(cfg.naming) or o.attributes.get(cfg.naming, key)
        features = object_features(spec, o) | (extra(o) if extra else {})
        out.append(Alternative(o.id, value, o.slot, features))
    return out
