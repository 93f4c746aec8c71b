"""The oracle's skill API: what a referent's demonstration is written in.

Each skill plans (mink IK for the pose, ruckig for the joint path) and executes at once on the
scene, reading object poses from the simulation, and records every action it executes. A plan
reads like a few lines, e.g. `skills.grasp(spec.target); skills.lift()`.
"""

from __future__ import annotations

import numpy as np

from gen.spec import EpisodeSpec
from oracle import catalog
from oracle.ik import ArmIK, grasp_yaw
from oracle.scene import Scene
from oracle.trajectory import Limits, joint_path

OPEN, CLOSED = -1.0, 1.0


class Skills:
    def __init__(self, scene: Scene, ik: ArmIK, spec: EpisodeSpec, limits: Limits = Limits()) -> None:
        self.scene = scene
        self.ik = ik
        self.spec = spec
        self.limits = limits
        self.dt = 1.0 / spec.sim.fps
        self.q = np.asarray(spec.sim.robot_home, dtype=float)
        self.yaw = 0.0
        self.gripper = OPEN
        self.actions: list[np.ndarray] = []

    def _execute(self, q: np.ndarray) -> None:
        # The action is rounded to float32 before execution: what is recorded is what ran.
        action = np.concatenate([q, [self.gripper]]).astype(np.float32)
        self.scene.step(action)
        self.actions.append(action)

    def move_to(self, pos: np.ndarray, yaw: float | None = None) -> None:
        """Grip site to `pos`, pointing down, at `yaw` (default: keep the current yaw)."""
        yaw = self.yaw if yaw is None else yaw
        goal = self.ik.solve(np.asarray(pos, dtype=float), yaw, seed=self.q)
        for q in joint_path(self.q, goal, self.dt, self.limits):
            self._execute(q)
        self.q, self.yaw = goal, yaw

    def hold(self, steps: int) -> None:
        for _ in range(steps):
            self._execute(self.q)

    def close(self, steps: int = 8) -> None:
        self.gripper = CLOSED
        self.hold(steps)

    def open(self, steps: int = 6) -> None:
        self.gripper = OPEN
        self.hold(steps)

    def top_of(self, object_id: str) -> np.ndarray:
        """The centre of the object's top face, from its current simulated pose."""
        kind = catalog.kind(self.spec.object(object_id).kind)
        pos = self.scene.object_pos(object_id)
        return np.array([pos[0], pos[1], pos[2] - kind.bottom + kind.height])

    def grasp(self, object_id: str, approach: float = 0.07) -> None:
        """Come down on the object from above, fingers across its narrow axis, and close."""
        kind = catalog.kind(self.spec.object(object_id).kind)
        top = self.top_of(object_id)
        axis = self.scene.object_yaw(object_id) + (0.0 if kind.grasp_axis == "x" else np.pi / 2)
        yaw = grasp_yaw(axis)
        self.move_to(top + [0.0, 0.0, approach], yaw)
        self.move_to(top - [0.0, 0.0, kind.grasp_depth()], yaw)
        self.close()

    def lift(self, height: float = 0.15) -> None:
        self.move_to(self.scene.ee_pos() + [0.0, 0.0, height])
        self.hold(2)

    def place(self, pos: np.ndarray, clearance: float = 0.08) -> None:
        """Carry what is held over `pos` (the held object's bottom lands there), release, retreat."""
        drop = np.asarray(pos, dtype=float)
        self.move_to(np.array([drop[0], drop[1], self.scene.ee_pos()[2] + 0.0]))
        self.move_to(drop + [0.0, 0.0, clearance])
        self.open()
        self.move_to(drop + [0.0, 0.0, clearance + 0.08])
