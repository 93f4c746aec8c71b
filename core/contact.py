"""Where the hand meets an object: the points the oracle's skills go to and the exam scorer
measures a rollout's closest approach against (a bowl's whole rim, any side of which the oracle
may take), so the two cannot drift apart.

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
    """Height of the grip site above the object's bottom while it is grasped (by its handle, the handle's)."""
    return kind.bottom + kind.handle[2] if kind.handle is not None else kind.height - kind.grasp_depth()


def grasp_point(kind: Kind, pos: np.ndarray) -> np.ndarray:
    """Where the grip site closes on an object to pick it up (or pushes against from above)."""
    return top(kind, pos) - [0.0, 0.0, kind.grasp_depth()]


def grasp_distance(kind: Kind, pos: np.ndarray, ee: np.ndarray) -> np.ndarray:
    """How far the grip site `ee` is from where the object can be held: its grasp point, or for a
    bowl (a `rim` kind, taken by its wall wherever a side is clear) the ring of its wall at the
    grasp depth. Per step of (T, 3) `ee` and object `pos`; what landing is judged by."""
    ee, point = np.asarray(ee, dtype=float), grasp_point(kind, pos)
    if not kind.rim:
        return np.linalg.norm(ee - point, axis=-1)
    across = np.linalg.norm(ee[..., :2] - point[..., :2], axis=-1) - kind.rim
    return np.hypot(across, ee[..., 2] - point[..., 2])


def release_point(destination: Kind, pos: np.ndarray, carried: Kind) -> np.ndarray:
    """Where the grip site lets go of `carried` over a destination at `pos`."""
    over = top(destination, pos)
    return np.stack([over[..., 0], over[..., 1], over[..., 2] + grip_height(carried) + PLACE_CLEARANCE], axis=-1)


def floor(container: Kind, pos: np.ndarray) -> float:
    """The height of a container's floor (the bottom of its `contain` box) standing upright at `pos`."""
    centre, half = container.contain
    return float(np.asarray(pos, dtype=float)[2] + centre[2] - half[2])


def distance(kind: Kind, pos: np.ndarray, ee: np.ndarray, carried: Kind | None = None) -> np.ndarray:
    """(T,) distances of the grip site `ee` from where it meets an object of `kind` at `pos`: where it
    is held (`grasp_distance`), or, when the hand brings `carried` there, the release point over it."""
    if carried is None:
        return grasp_distance(kind, pos, ee)
    return np.linalg.norm(np.asarray(ee, dtype=float) - release_point(kind, pos, carried), axis=-1)
