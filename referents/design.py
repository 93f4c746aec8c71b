"""What a referent type's `design` returns: the discrete choices of one episode (which objects,
in which slots, which is the target, the instruction and its counterfactuals). Poses are
realised from them in gen/planning/plan.py, so re-realising a failed demo never changes a role."""

from __future__ import annotations

from dataclasses import dataclass

from core.spec import Counterfactual, TaskSpec
from referents.schema import Candidate


@dataclass(frozen=True)
class Placement:
    """A candidate put at a slot under a scene-unique id."""

    id: str
    candidate: Candidate
    slot: int


@dataclass(frozen=True)
class Design:
    """The discrete choices of one episode, before poses are realised."""

    placements: tuple[Placement, ...]
    target: str
    template: str
    instruction: str
    counterfactuals: tuple[Counterfactual, ...]
    task: TaskSpec | None = None  # None: the referent's task
    switch: int | None = None  # the counterfactual the instruction becomes mid-course (gen's `switched=`)
