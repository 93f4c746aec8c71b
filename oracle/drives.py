"""How an action moves the robot: one class per profile's controller (core/profiles.py).

* `JointServo` (native): seven joint-position targets held by position servos with gravity
  compensation, and a gripper command mapped straight to the finger targets.
* `OscPose` (libero): LIBERO's arm controller, robosuite's `OperationalSpaceController`
  (OSC_POSE: delta input in the world frame, kp 150, damping ratio 1, output limits 0.05 m /
  0.5 rad, position and orientation uncoupled, nullspace pull to the home joints), computed by
  robosuite's own functions once per physics substep as robosuite's environments call it, the
  goal set from the action on the first substep of each control period. Where robosuite 1.4,
  which LIBERO runs, differs from 1.5, it acts as 1.4 does: an action whose rotation is exactly
  zero keeps the goal orientation (1.4 updates it only for a non-zero rotation), and after a
  state is restored without a reset (LIBERO's `set_init_state`) the controller's first control
  step still reads the arm as it stood at the reset (1.4 refreshes what it read only after it
  has run once); both move the hand during LIBERO's settle steps from its own initial states,
  and eval/sims/libero.py runs exams in LIBERO to compare. The gripper follows robosuite 1.4's
  PandaGripper: the sign of the command moves the finger targets 0.01 of their range per substep.

A drive is made for one `Scene` (oracle/scene.py) and shares its model and data.
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from core.profiles import OSC_ORI_LIMIT, OSC_POS_LIMIT

FINGER_OPEN = 0.04  # finger joint travel, metres

# Joint-position servo gains (N m / rad, N m s / rad), joints 1..7.
SERVO_KP = (1500.0, 1500.0, 1500.0, 1500.0, 600.0, 400.0, 200.0)
SERVO_KV = (120.0, 120.0, 120.0, 120.0, 40.0, 25.0, 12.0)

OSC_KP, OSC_DAMPING_RATIO = 150.0, 1.0
GRIPPER_SPEED = 0.01  # robosuite 1.4 PandaGripper.speed, per physics substep


class Drive(Protocol):
    def reset(self, home: np.ndarray) -> None:
        """Forget any controller state: the next action starts from the current pose."""

    def restored(self) -> None:
        """The simulation's state was set from outside (a recorded or another simulator's state)
        without a reset: what the controller read at its reset is what it acts on first."""

    def step(self, action: np.ndarray, substeps: int) -> None:
        """Execute one control period of `substeps` physics steps."""


def _finger_targets(closing: float) -> tuple[float, float]:
    """Finger joint targets for a closure in [-1 open, +1 closed]."""
    opening = FINGER_OPEN * (1.0 - float(np.clip(closing, -1.0, 1.0))) / 2.0
    return opening, -opening


class JointServo:
    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self.model, self.data = model, data

    def reset(self, home: np.ndarray) -> None:
        pass

    def restored(self) -> None:
        pass

    def step(self, action: np.ndarray, substeps: int) -> None:
        self.data.ctrl[:7] = action[:7]
        self.data.ctrl[7:9] = _finger_targets(action[7])
        mujoco.mj_step(self.model, self.data, nstep=substeps)


class OscPose:
    """robosuite's OSC_POSE controller (robosuite/controllers/parts/arm/osc.py), its equations
    computed by robosuite's own functions (`opspace_matrices`, `nullspace_torques`,
    `orientation_error`, the axis-angle and quaternion conversions) on the scene's state read
    directly: robosuite's controller object spends most of a step looking names up and copying
    arrays. tests/sim/test_libero.py checks that both drive the arm along the same path (to 1e-9)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, arm_joints: tuple[str, ...], ee_site: str) -> None:
        ids = [model.joint(j).id for j in arm_joints]
        self.model, self.data = model, data
        self.qpos_index = np.array([model.jnt_qposadr[i] for i in ids])
        self.dof = np.array([model.jnt_dofadr[i] for i in ids])
        self.site = model.site(ee_site).id
        self.low, self.high = model.actuator_ctrlrange[: len(ids), 0].copy(), model.actuator_ctrlrange[: len(ids), 1].copy()
        self.kp = np.full(6, OSC_KP)
        self.kd = 2 * np.sqrt(self.kp) * OSC_DAMPING_RATIO
        output = np.array((OSC_POS_LIMIT,) * 3 + (OSC_ORI_LIMIT,) * 3)
        self.scale = abs(output - -output) / abs(np.ones(6) - -np.ones(6))  # robosuite's scale_action, inputs in [-1, 1]
        nv = model.nv
        self._jacp, self._jacr, self._mass = np.zeros((3, nv)), np.zeros((3, nv)), np.zeros((nv, nv))
        self.initial_joint = np.zeros(len(ids))  # the nullspace target
        self.goal_pos, self.goal_ori = np.zeros(3), np.eye(3)
        self.fingers = np.zeros(2)  # robosuite's gripper `current_action`: [-1, 1] per finger
        self.stale = False  # robosuite 1.4's `new_update` unset: the next substep acts on what was read at reset

    def _update(self) -> None:
        """robosuite's Controller.update with lite physics: the state after mj_step1."""
        m, d = self.model, self.data
        mujoco.mj_jacSite(m, d, self._jacp, self._jacr, self.site)
        self.J_pos, self.J_ori = np.array(self._jacp[:, self.dof]), np.array(self._jacr[:, self.dof])
        self.J_full = np.vstack([self.J_pos, self.J_ori])
        self.ref_pos, self.ref_ori = np.array(d.site_xpos[self.site]), np.array(d.site_xmat[self.site].reshape(3, 3))
        self.vel_pos, self.vel_ori = np.dot(self._jacp, d.qvel), np.dot(self._jacr, d.qvel)
        self.joint_pos, self.joint_vel = np.array(d.qpos[self.qpos_index]), np.array(d.qvel[self.dof])
        mujoco.mj_fullM(m, self._mass, d.qM)
        self.mass = self._mass[self.dof, :][:, self.dof]

    def reset(self, home: np.ndarray) -> None:
        """robosuite's update_initial_joints: the nullspace target is `home`, the goal the current pose."""
        mujoco.mj_forward(self.model, self.data)
        self._update()
        self.initial_joint = np.array(home, float)
        self.goal_pos, self.goal_ori = np.array(self.ref_pos), np.array(self.ref_ori)
        half = FINGER_OPEN / 2
        self.fingers = np.array([self.data.ctrl[7] / half - 1.0, 1.0 + self.data.ctrl[8] / half])
        self.stale = False

    def restored(self) -> None:
        """robosuite 1.4 after LIBERO's set_init_state: its controller keeps the arm it read at the
        reset (pose, velocities, Jacobians, mass) until it has run once, so the first goal is
        relative to the reset pose and the first substep's torques are computed for it; the
        gripper keeps its reset state too."""
        self.stale = True

    def _set_goal(self, action: np.ndarray) -> None:
        """robosuite's set_goal: delta input in the world frame, goals from the achieved pose; the
        orientation goal only for a non-zero rotation (robosuite 1.4's `math.isclose(x, 0.0)`)."""
        import robosuite.utils.transform_utils as T

        delta = np.clip(action, -1.0, 1.0) * self.scale
        self.goal_pos = self.ref_pos + delta[0:3]
        if np.any(delta[3:6] != 0.0):
            self.goal_ori = np.dot(T.quat2mat(T.axisangle2quat(delta[3:6])), self.ref_ori)

    def _torques(self) -> np.ndarray:
        """robosuite's OperationalSpaceController.run_controller, uncoupled position and orientation."""
        from robosuite.utils.control_utils import nullspace_torques, opspace_matrices, orientation_error

        # the base is fixed: robosuite subtracts its site's velocity, which is zero
        desired_force = np.multiply(self.goal_pos - self.ref_pos, self.kp[0:3]) + np.multiply(-self.vel_pos, self.kd[0:3])
        ori_error = orientation_error(self.goal_ori, self.ref_ori)
        desired_torque = np.multiply(np.array(ori_error), self.kp[3:6]) + np.multiply(-self.vel_ori, self.kd[3:6])
        _, lambda_pos, lambda_ori, nullspace = opspace_matrices(self.mass, self.J_full, self.J_pos, self.J_ori)
        wrench = np.concatenate([np.dot(lambda_pos, desired_force), np.dot(lambda_ori, desired_torque)])
        torques = np.dot(self.J_full.T, wrench) + self.data.qfrc_bias[self.dof]
        return torques + nullspace_torques(self.mass, nullspace, self.initial_joint, self.joint_pos, self.joint_vel)

    def step(self, action: np.ndarray, substeps: int) -> None:
        d, n = self.data, len(self.dof)
        for k in range(substeps):
            mujoco.mj_step1(self.model, d)  # kinematics, mass matrix and bias forces for the controller
            if not self.stale:
                self._update()
            self.stale = False
            if k == 0:
                self._set_goal(np.asarray(action[:6], float))
            d.ctrl[:n] = np.clip(self._torques(), self.low, self.high)
            self.fingers = np.clip(self.fingers + np.array([-1.0, 1.0]) * GRIPPER_SPEED * np.sign(action[6]), -1.0, 1.0)
            d.ctrl[n : n + 2] = FINGER_OPEN / 2 * (1.0 + self.fingers[0]), -FINGER_OPEN / 2 * (1.0 - self.fingers[1])
            mujoco.mj_step2(self.model, d)
