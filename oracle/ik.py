"""Grasp poses -> arm joint angles, with mink's differential IK on the robot alone: the hand
pointing down at a yaw, or (a drawer's handle, taken from the front) at a given orientation."""

from __future__ import annotations

import mink
import mujoco
import numpy as np

from core.rotations import yaw_matrix
from oracle.drives import FINGER_OPEN
from oracle.scene import EE_SITE, robot_xml

# The grip site pointing straight down, fingers closing along world y (yaw 0).
DOWN = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


class IKError(RuntimeError):
    """The pose is out of reach: IK did not converge."""


def grasp_yaw(axis_angle: float) -> float:
    """Gripper yaw whose fingers close along the world direction `axis_angle`.

    The hand is symmetric, so the yaw is taken in (-pi/2, pi/2]: the wrist never winds up.
    """
    yaw = axis_angle - np.pi / 2
    return float((yaw + np.pi / 2) % np.pi - np.pi / 2)


class ArmIK:
    """Solves for the arm joints that put the grip site at a position, pointing down at a yaw (or
    at the orientation `facing` gives).

    A posture task toward the home pose keeps solutions in the same elbow-up family, so ruckig
    segments between them stay short and smooth.
    """

    def __init__(self, home: np.ndarray, world: str = "native", tol: float = 1e-3, max_iters: int = 300) -> None:
        self.model = mujoco.MjModel.from_xml_string(robot_xml(world))
        self.config = mink.Configuration(self.model)
        self.frame = mink.FrameTask(EE_SITE, "site", position_cost=1.0, orientation_cost=1.0)
        self.posture = mink.PostureTask(self.model, cost=1e-3)
        self.posture.set_target(np.concatenate([home, [FINGER_OPEN, -FINGER_OPEN]]))
        self.tol = tol
        self.max_iters = max_iters
        self._fk = mujoco.MjData(self.model)
        self._site = self.model.site(EE_SITE).id

    def pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: the grip site's position and rotation matrix at arm joints `q`."""
        self._fk.qpos[: len(q)] = q
        mujoco.mj_kinematics(self.model, self._fk)
        return self._fk.site_xpos[self._site].copy(), self._fk.site_xmat[self._site].reshape(3, 3).copy()

    def solve(self, pos: np.ndarray, yaw: float, seed: np.ndarray, facing: np.ndarray | None = None) -> np.ndarray:
        self.config.update(np.concatenate([seed, [FINGER_OPEN, -FINGER_OPEN]]))
        rotation = yaw_matrix(yaw) @ DOWN if facing is None else facing
        target = mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rotation), np.asarray(pos))
        self.frame.set_target(target)
        for _ in range(self.max_iters):
            velocity = mink.solve_ik(self.config, [self.frame, self.posture], 0.1, "quadprog", damping=1e-3)
            self.config.integrate_inplace(velocity, 0.1)
            err = self.frame.compute_error(self.config)
            if np.linalg.norm(err[:3]) < self.tol and np.linalg.norm(err[3:]) < self.tol:
                return self.config.q[:7].copy()
        raise IKError(f"no IK solution within {self.tol} for position {np.round(pos, 3).tolist()} yaw {yaw:.2f}")
