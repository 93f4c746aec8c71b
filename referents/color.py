"""Color referent: every scene holds one shape (balanced) in several colors; the color word
names the target (see referents.base.naming_design)."""

from __future__ import annotations

from referents.base import Balance, Design, ReferentConfig, naming_design

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    shape = balance.pick("shape", list(dict.fromkeys(c.name for c in cfg.objects)))
    return naming_design(cfg, balance, [c for c in cfg.objects if c.name == shape])
