"""Object referent: the instruction names the target by its noun (see referents.compose.naming_design)."""

from __future__ import annotations

from referents.balance import Balance
from referents.compose import naming_design
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    return naming_design(cfg, balance)
