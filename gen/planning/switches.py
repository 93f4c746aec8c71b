"""Episodes that change course (`switched=`): which of a training set's episodes have their
instruction changed mid-course, and into which of their counterfactuals.

A seeded draw of round(share x n) episodes among those that have an alternative; each switches to
the counterfactual whose object, slot and program have so far been the second target least often
(ties drawn), so every alternative is as often the second target as any other, as the roles
balance the first. Which episodes switch depends on nothing in them, and where one switches is
the oracle's (oracle/episode.py `change_course`: on the approach, at a step drawn from the
episode's seed and index up to where the hand is 2 cm from what it takes hold of, or, when the
new ask brings the held object elsewhere, once it is carried), so the step says at most whether
the new ask keeps the object, which its words say too, never which target. The plan audits the
second targets as it audits the first (gen/planning/plan.py).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

import numpy as np

from core.spec import Counterfactual
from referents.design import Design

STREAM = 0x5717  # the draw's own random stream: switching episodes never moves a role or a pose


def switched(designs: list[Design], share: float, seed: int) -> list[Design]:
    """`designs` with round(share x n) of them (fewer where too few have an alternative) switching."""
    if not share:
        return designs
    rng = np.random.default_rng([seed, STREAM])
    able = [i for i, design in enumerate(designs) if design.counterfactuals]
    chosen = sorted(int(i) for i in rng.choice(able, min(round(share * len(designs)), len(able)), replace=False))
    out, counts = list(designs), Counter[tuple]()
    for i in chosen:
        options = [_parts(designs[i], cf) for cf in designs[i].counterfactuals]
        scores = [sum(counts[part] for part in parts) for parts in options]
        fewest = [k for k, score in enumerate(scores) if score == min(scores)]
        pick = fewest[int(rng.integers(len(fewest)))]
        counts.update(options[pick])
        out[i] = replace(designs[i], switch=pick)
    return out


def _parts(design: Design, cf: Counterfactual) -> tuple[tuple, ...]:
    """What a second target is, for the balance: its object, its slot, the program it is asked."""
    placed = next((p for p in design.placements if p.id == cf.target), None)
    program = cf.program or (design.task.program if design.task else "")
    where = (("object", placed.candidate.key), ("slot", placed.slot)) if placed else (("place", cf.target),)
    return (*where, ("program", program))
