"""Category referent: one object per category in each scene; the category word names the
target (see referents.compose.naming_design). The audit also checks that the set of categories
in a scene does not predict which one is asked for."""

from __future__ import annotations

from core.spec import EpisodeSpec, SceneObject
from referents.balance import Balance
from referents.compose import naming_design
from referents.design import Design
from referents.schema import ReferentConfig
from referents.variables import IDENTITY, Alternative, Variable, object_alternatives

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    return naming_design(cfg, balance)


def alternatives(cfg: ReferentConfig, spec: EpisodeSpec) -> list[Alternative]:
    present = tuple(sorted(o.attributes["category"] for o in spec.objects))

    def extra(o: SceneObject) -> dict[str, Variable]:
        return {"co-appearing categories": Variable((present, o.attributes["category"]), IDENTITY)}

    return object_alternatives(cfg, spec, extra=extra)
