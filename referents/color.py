"""Color referent: every scene holds one shape (balanced) in several colors; the color word
names the target (see referents.compose.naming_design)."""

from __future__ import annotations

from referents.balance import Balance
from referents.compose import naming_design
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    shape = balance.pick("shape", list(dict.fromkeys(c.name for c in cfg.objects)))
    return naming_design(cfg, balance, [c for c in cfg.objects if c.name == shape])
