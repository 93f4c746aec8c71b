"""The arm's motion primitives, whatever controller the profile drives it with: move the grip site
to a pose or along a line, hold, open and close the fingers. Each plans (mink IK for the pose,
ruckig for the joint path) and executes at once on the scene, recording every action it executes
and the physics state before it. Under joint-position servos (native) an action is the path's next
joint waypoint; under an end-effector-delta controller (the libero profile) it is the delta from
where the hand is to where that waypoint puts it, amplified (the OSC covers only part of a
commanded delta in one step), and before the gripper closes or opens the hand settles on its goal.
"""

from __future__ import annotations

from collections.abc import Iterator

import mujoco
import numpy as np

from core.profiles import NATIVE, OSC_ORI_LIMIT, OSC_POS_LIMIT
from core.spec import EpisodeSpec
from oracle.ik import ArmIK, IKError
from oracle.scene import Scene, axis_angle
from oracle.trajectory import Limits, joint_path

OPEN, CLOSED = -1.0, 1.0
DELTA_GAIN = 3.0  # how much of the hand's error an end-effector delta asks for
GENTLE = Limits(velocity=1.0, acceleration=2.0, jerk=15.0)  # a bottle held by its neck stays in the hand at these
SETTLE_POS, SETTLE_ROT, MAX_SETTLE_STEPS = 0.005, 0.05, 40  # m, rad, control steps
# A thing moving faster than this (m per control step) is still falling: LIBERO-10's living room's
# initial states launch the milk and the orange juice 0.5 m up (LIBERO's own simulator as ours); an
# oracle planning around them waits, holding the arm, until they land (at most MAX_FALL_STEPS)
FALLING, MAX_FALL_STEPS = 0.005, 60


def rotation_vector(rot: np.ndarray) -> np.ndarray:
    """The axis-angle vector (world frame) of a rotation matrix, angle in [0, pi]."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.flatten())
    return axis_angle(quat if quat[0] >= 0 else -quat)


class Motion:
    """The arm of one episode's scene and what it has executed so far."""

    def __init__(self, scene: Scene, ik: ArmIK, spec: EpisodeSpec, limits: Limits = Limits()) -> None:
        self.scene = scene
        self.ik = ik
        self.spec = spec
        self.limits = limits
        self.dt = 1.0 / spec.setup.fps
        self.q = scene.data.qpos[scene.arm_qpos].copy()  # where the arm is: the home pose, or a recorded start
        self.yaw = 0.0
        self.facing: np.ndarray | None = None  # the hand's orientation when it does not point down (oracle/ik.py facing)
        self.gentle = False  # moves at GENTLE's limits: what the hand holds swings loose of a time-optimal move
        self.gripper = OPEN
        self.actions: list[np.ndarray] = []
        self.states: list[np.ndarray] = []  # physics state before each action
        self.deltas = scene.interface.controller != NATIVE.controller
        # joints to seed IK from where the arm's own pose leads it to none (a plan begun mid-course,
        # its wrist turned for another object); None: a plan from the arm's start never needs it
        self.reseed: np.ndarray | None = None

    def _execute(self, q: np.ndarray) -> None:
        # The action is rounded to float32 before execution: what is recorded is what ran.
        command = self._delta_toward(q) if self.deltas else q
        action = np.concatenate([command, [self.gripper]]).astype(np.float32)
        self.states.append(self.scene.physics_state())
        self.scene.step(action)
        self.actions.append(action)

    def _error(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position and rotation (world-frame axis-angle) from the hand to where `q` puts it."""
        pos, rot = self.ik.pose(q)
        return pos - self.scene.ee_pos(), rotation_vector(rot @ self.scene.ee_rot().T)

    def _delta_toward(self, q: np.ndarray) -> np.ndarray:
        dpos, drot = self._error(q)
        return np.clip(DELTA_GAIN * np.concatenate([dpos / OSC_POS_LIMIT, drot / OSC_ORI_LIMIT]), -1.0, 1.0)

    def _settle(self, q: np.ndarray) -> None:
        """Under deltas, hold the goal until the hand is on it (servos need no settling)."""
        for _ in range(MAX_SETTLE_STEPS if self.deltas else 0):
            dpos, drot = self._error(q)
            if np.linalg.norm(dpos) < SETTLE_POS and np.linalg.norm(drot) < SETTLE_ROT:
                return
            self._execute(q)

    def _path_to(self, pos: np.ndarray, yaw: float, start: np.ndarray | None = None) -> tuple[np.ndarray, list[np.ndarray]]:
        """The arm's goal putting the grip site at `pos`, and its joint path there from `start`
        (default: where the arm is)."""
        start = self.q if start is None else start
        try:
            goal = self.ik.solve(np.asarray(pos, dtype=float), yaw, seed=start, facing=self.facing)
        except IKError:
            if self.reseed is None:
                raise
            goal = self.ik.solve(np.asarray(pos, dtype=float), yaw, seed=self.reseed, facing=self.facing)
        return goal, joint_path(start, goal, self.dt, GENTLE if self.gentle else self.limits)

    def _follow(self, goal: np.ndarray, path: list[np.ndarray], yaw: float) -> None:
        for q in path:
            self._execute(q)
        self.q, self.yaw = goal, yaw

    def move_to(self, pos: np.ndarray, yaw: float | None = None) -> None:
        """Grip site to `pos`, pointing down at `yaw` (default: keep the current yaw), or as `facing` has it."""
        yaw = self.yaw if yaw is None else yaw
        self._follow(*self._path_to(pos, yaw), yaw)

    def move_linear(self, pos: np.ndarray, speed: float = 0.12) -> None:
        """Grip site along a straight line to `pos` (minimum-jerk timing), e.g. to push."""
        start = self.scene.ee_pos()
        goal = np.asarray(pos, dtype=float)
        for s in _minimum_jerk(float(np.linalg.norm(goal - start)) / (speed * self.dt)):
            self.q = self.ik.solve(start + s * (goal - start), self.yaw, seed=self.q, facing=self.facing)
            self._execute(self.q)

    def twist(self, yaw: float, speed: float = 0.8) -> None:
        """Turn the hand about its grip site to `yaw` at `speed` rad/s (minimum-jerk timing), the
        site kept where it is throughout: what turns a knob without pulling on its axis (a joint
        path between two yaws swings the site off it)."""
        start, site = self.yaw, self.scene.ee_pos()
        for s in _minimum_jerk(abs(yaw - start) / (speed * self.dt)):
            self.q = self.ik.solve(site, start + s * (yaw - start), seed=self.q, facing=self.facing)
            self._execute(self.q)
        self.yaw = yaw

    def hold(self, steps: int) -> None:
        for _ in range(steps):
            self._execute(self.q)

    def wait_still(self) -> None:
        """Hold the arm while anything in the scene is still falling (FALLING): nothing, where all is at rest."""
        for _ in range(MAX_FALL_STEPS):
            if self.scene.fastest() * self.dt <= FALLING:
                return
            self.hold(1)

    def close(self, steps: int = 8) -> None:
        self._settle(self.q)
        self.gripper = CLOSED
        self.hold(steps)

    def open(self, steps: int = 6) -> None:
        self._settle(self.q)
        self.gripper = OPEN
        self.hold(steps)


def _minimum_jerk(steps: float) -> Iterator[float]:
    """The fraction of a move done after each of its control steps (at least two, `steps` rounded up)
    on a minimum-jerk profile: it starts and ends at rest."""
    count = max(2, int(np.ceil(steps)))
    for k in range(1, count + 1):
        tau = k / count
        yield 10 * tau**3 - 15 * tau**4 + 6 * tau**5
