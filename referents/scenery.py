"""A LIBERO task's objects as a type's candidates, for the types that lay out LIBERO's own scenes
(their `canonical` hook: gen.canonical), LIBERO-PRO's perturbed ones included.

An object of a kind the spec lists is that candidate; a recoloured or resized copy (LIBERO-PRO's
`_object` suites: `green_butter`, `yellow_plate`) is the candidate it copies, under its own kind
(LIBERO-PRO's instructions keep their words: the butter is still "the butter"); any other object (an
added distractor: LIBERO-PRO's mug, book, milk) is scenery, named as the world calls it, which
stands in the scene but is never named by a swap.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from core import worlds
from core.libero import Problem
from referents.schema import Candidate, ReferentConfig

SCENERY = "scenery"  # the role of an object no candidate of the type is


def base_kind(cfg: ReferentConfig, kind: str) -> str:
    """The kind `kind` copies (itself if it copies none)."""
    return worlds.world(cfg.world).kind(kind).variant_of or kind


def candidate(cfg: ReferentConfig, kind: str) -> Candidate:
    """The candidate an object of `kind` in a LIBERO problem is (see the module docstring)."""
    for c in cfg.objects:
        if c.kind == kind:
            return c
    for c in cfg.objects:
        if c.kind == base_kind(cfg, kind):
            return replace(c, kind=kind)
    return Candidate(kind, worlds.world(cfg.world).kind(kind).noun, role=SCENERY)


def nearest_slot(cfg: ReferentConfig, problem: Problem, instance: str, among: Sequence[int] | None = None) -> int:
    """The layout slot (of `among`, default all) nearest the centre of the region a LIBERO problem
    stands `instance` in: where a type's `canonical` design puts it until LIBERO's state poses it."""
    x, y = problem.centre(problem.region_of(instance))
    slots = list(range(len(cfg.layout.slots))) if among is None else list(among)
    return slots[int(np.argmin([np.hypot(x - cfg.layout.slots[s][0], y - cfg.layout.slots[s][1]) for s in slots]))]
