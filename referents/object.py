"""Object referent: the instruction names the target by its noun (see referents.base.naming_design)."""

from __future__ import annotations

from referents.base import Balance, Design, ReferentConfig, naming_design

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    return naming_design(cfg, balance)
