"""Where the hand meets an object: the points the oracle's skills go to and the exam scorer
measures a rollout's closest approach against, so the two cannot drift apart.

Positions are body origins (x, y, z), one or a batch (..., 3); kinds come from the catalog.
"""

from __future__ import annotations

import numpy as np

from core.catalog import Kind

PLACE_CLEARANCE = 0.015  # the carried object is released this far above resting on the destination


def top(kind: Kind, pos: np.ndarray) -> np.ndarray:
    """Centre of the object's top face."""
    pos = np.asarray(pos, dtype=float)
    return np.stack([pos[..., 0], pos[..., 1], pos[..., 2] - kind.bottom + kind.height], axis=-1)


def grip_height(kind: Kind) -> float:
    """Height of the grip site above the object's bottom while it is grasped."""
    return kind.height - kind.grasp_depth()


def grasp_point(kind: Kind, pos: np.ndarray) -> np.ndarray:
    """Where the grip site closes on an object to pick it up (or pushes against from above)."""
    return top(kind, pos) - [0.0, 0.0, kind.grasp_depth()]


def release_point(destination: Kind, pos: np.ndarray, carried: Kind) -> np.ndarray:
    """Where the grip site lets go of `carried` over a destination at `pos`."""
    over = top(destination, pos)
    return np.stack([over[..., 0], over[..., 1], over[..., 2] + grip_height(carried) + PLACE_CLEARANCE], axis=-1)
