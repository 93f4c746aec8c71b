"""Rotations, one home: quaternions (w, x, y, z) and matrices, the turns objects, fixtures and the
hand make. Simulator-free (mink's `lie`, which the oracle's IK uses, brings MuJoCo with it), so the
success predicates and the oracle build the same rotation the same way: the scene records, the
success predicates, the skills and the IK all read it from here.
"""

from __future__ import annotations

import math

import numpy as np

IDENTITY = (1.0, 0.0, 0.0, 0.0)
X_AXIS = np.array([1.0, 0.0, 0.0])


def yaw_quat(yaw: float, rest: tuple[float, ...] = IDENTITY) -> tuple[float, float, float, float]:
    """The orientation of an object turned by `yaw` about the world's z from its resting
    orientation `rest`."""
    c, s = math.cos(yaw / 2), math.sin(yaw / 2)
    w, x, y, z = rest
    return (c * w - s * z, c * x - s * y, c * y + s * x, c * z + s * w)


def yaw_of(quat: tuple[float, ...] | list[float], rest: tuple[float, ...] = IDENTITY) -> float:
    """The turn about the world's z that takes the resting orientation `rest` to `quat` (the
    inverse of `yaw_quat`, for orientations that differ by such a turn)."""
    w, x, y, z = quat
    rw, rx, ry, rz = rest  # quat times the conjugate of rest
    cw = w * rw + x * rx + y * ry + z * rz
    cz = -w * rz - x * ry + y * rx + z * rw
    return 2.0 * math.atan2(cz, cw)


def unit(quat: tuple[float, ...] | list[float]) -> tuple[float, ...]:
    """`quat` normalised (logged quaternions carry float rounding)."""
    norm = math.sqrt(sum(c * c for c in quat))
    return tuple(v / norm for v in quat)


def quat_matrix(quat: tuple[float, ...] | list[float]) -> np.ndarray:
    """The rotation matrix of a unit quaternion."""
    w, x, y, z = quat
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def yaw_matrix(yaw: float) -> np.ndarray:
    """The turn by `yaw` about the world's z."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def matrix_yaw(rotation: np.ndarray) -> float:
    """The `yaw` of a rotation `yaw_matrix(yaw)` (the inverse of `yaw_matrix`, for rotations about
    the world's z)."""
    return float(np.arctan2(rotation[1, 0], rotation[0, 0]))


def turned(axis: np.ndarray, angle: float) -> np.ndarray:
    """The turn by `angle` about the unit vector `axis` (Rodrigues): a sloping shelf's tilt, a held
    bottle turned down along it."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def facing(direction: tuple[float, float], roll: float = 0.0) -> np.ndarray:
    """A frame pointing level along the horizontal `direction`, its first axis down, turned `roll`
    about that direction: the grip site taking a drawer's handle bar from the front (its columns
    the grip frame's axes: closing, across, approach; closing down rather than up keeps the Panda's
    wrist within its range)."""
    x, y = np.asarray(direction, float) / np.hypot(*direction)
    down, across = np.array([0.0, 0.0, -1.0]), np.array([-y, x, 0.0])
    c, s = np.cos(roll), np.sin(roll)
    return np.column_stack([c * down + s * across, c * across - s * down, [x, y, 0.0]])
