"""Time-optimal, jerk-limited joint trajectories (ruckig), sampled at the control rate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ruckig


@dataclass(frozen=True)
class Limits:
    """Joint-space limits of the demonstrations (inside the Panda's own: 2.2-2.6 rad/s)."""

    velocity: float = 2.0  # rad/s
    acceleration: float = 6.0  # rad/s^2
    jerk: float = 50.0  # rad/s^3


def joint_path(start: np.ndarray, goal: np.ndarray, dt: float, limits: Limits = Limits()) -> list[np.ndarray]:
    """Waypoints from rest at `start` to rest at `goal`, one per control period.

    The last waypoint is exactly `goal`; a zero-length move yields no waypoints.
    """
    dofs = len(start)
    inp = ruckig.InputParameter(dofs)
    inp.current_position = list(start)
    inp.current_velocity = [0.0] * dofs
    inp.current_acceleration = [0.0] * dofs
    inp.target_position = list(goal)
    inp.target_velocity = [0.0] * dofs
    inp.target_acceleration = [0.0] * dofs
    inp.max_velocity = [limits.velocity] * dofs
    inp.max_acceleration = [limits.acceleration] * dofs
    inp.max_jerk = [limits.jerk] * dofs
    traj = ruckig.Trajectory(dofs)
    result = ruckig.Ruckig(dofs).calculate(inp, traj)
    if result not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise RuntimeError(f"ruckig could not plan a trajectory: {result}")
    steps = int(np.ceil(traj.duration / dt - 1e-9))
    path = [np.array(traj.at_time(min((k + 1) * dt, traj.duration))[0]) for k in range(steps)]
    if path:
        path[-1] = np.asarray(goal, dtype=float).copy()
    return path
