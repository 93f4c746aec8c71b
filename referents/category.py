"""Category referent: one object per category in each scene; the category word names the
target (see referents.base.naming_design). The audit also checks that the set of categories
in a scene does not predict which one is asked for."""

from __future__ import annotations

from collections.abc import Hashable

from core.spec import EpisodeSpec, SceneObject
from referents.base import Alternative, Balance, Design, ReferentConfig, naming_design, object_alternatives

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    return naming_design(cfg, balance)


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    present = tuple(sorted(o.attributes["category"] for o in spec.objects))

    def extra(o: SceneObject) -> dict[str, Hashable]:
        return {"co-appearing categories": (present, o.attributes["category"])}

    return object_alternatives(cfg, spec, extra=extra)
