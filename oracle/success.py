"""Success predicates: lift-gated and false at the initial state by construction.

Every measure is relative to where the objects started, so a scene whose target starts high
cannot score, and a do-nothing rollout scores nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gen.spec import EpisodeSpec
from oracle.scene import Scene


@dataclass(frozen=True)
class Outcome:
    """What a rollout did to the scene, measured on its final state."""

    rise: dict[str, float]  # object id -> final minus initial height, metres
    moved: dict[str, float]  # object id -> horizontal displacement, metres
    ee: tuple[float, float, float]  # final end-effector position


def start_positions(scene: Scene, spec: EpisodeSpec) -> dict[str, np.ndarray]:
    return {o.id: scene.object_pos(o.id) for o in spec.objects}


def measure(scene: Scene, spec: EpisodeSpec, start: dict[str, np.ndarray]) -> Outcome:
    end = {o.id: scene.object_pos(o.id) for o in spec.objects}
    return Outcome(
        rise={k: float(end[k][2] - start[k][2]) for k in end},
        moved={k: float(np.linalg.norm(end[k][:2] - start[k][:2])) for k in end},
        ee=tuple(float(v) for v in scene.ee_pos()),  # type: ignore[arg-type]
    )


def lifted(spec: EpisodeSpec, outcome: Outcome, target: str | None = None) -> bool:
    """The target rose by at least the margin and no other object did."""
    target = spec.target if target is None else target
    margin = spec.task.lift_margin
    others = [r for k, r in outcome.rise.items() if k != target]
    return outcome.rise[target] >= margin and all(r < margin for r in others)


def succeeded(spec: EpisodeSpec, outcome: Outcome) -> bool:
    if spec.task.program == "pick":
        return lifted(spec, outcome)
    raise ValueError(f"no success predicate for program {spec.task.program!r}")
