"""How an action moves the robot: one class per feature layout's controller (core/layout.py).

* `JointServo` (native): seven joint-position targets held by position servos with gravity
  compensation, and a gripper command mapped straight to the finger targets.
* `OscPose` (libero): LIBERO's arm controller. robosuite's own `OperationalSpaceController`
  (OSC_POSE: delta input in the world frame, kp 150, damping ratio 1, output limits 0.05 m /
  0.5 rad, position and orientation uncoupled, nullspace pull to the home joints) runs on our
  compiled model through robosuite's `MjSim` binding, once per physics substep as robosuite's
  environments call it, the goal set from the action on the first substep of each control
  period. The gripper follows robosuite 1.4's PandaGripper, which LIBERO ran: the sign of the
  command moves the finger targets 0.01 of their range per substep.

A drive is made for one `Scene` (oracle/scene.py) and shares its model and data.
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from core.layout import OSC_ORI_LIMIT, OSC_POS_LIMIT

FINGER_OPEN = 0.04  # finger joint travel, metres

# Joint-position servo gains (N m / rad, N m s / rad), joints 1..7.
SERVO_KP = (1500.0, 1500.0, 1500.0, 1500.0, 600.0, 400.0, 200.0)
SERVO_KV = (120.0, 120.0, 120.0, 120.0, 40.0, 25.0, 12.0)

OSC_KP, OSC_DAMPING_RATIO = 150.0, 1.0
GRIPPER_SPEED = 0.01  # robosuite 1.4 PandaGripper.speed, per physics substep


class Drive(Protocol):
    def reset(self, home: np.ndarray) -> None:
        """Forget any controller state: the next action starts from the current pose."""

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

    def step(self, action: np.ndarray, substeps: int) -> None:
        self.data.ctrl[:7] = action[:7]
        self.data.ctrl[7:9] = _finger_targets(action[7])
        mujoco.mj_step(self.model, self.data, nstep=substeps)


class OscPose:
    def __init__(self, sim, arm_joints: tuple[str, ...], ee_site: str) -> None:  # noqa: ANN001
        """`sim`: robosuite's `MjSim` binding of the scene's model; its data is the scene's."""
        from robosuite.controllers.parts.arm.osc import OperationalSpaceController

        m = sim.model._model
        ids = [m.joint(j).id for j in arm_joints]
        self.model, self.data = m, sim.data._data
        self.osc = OperationalSpaceController(
            sim,
            ref_name=ee_site,
            joint_indexes={
                "joints": ids,
                "qpos": [int(m.jnt_qposadr[i]) for i in ids],
                "qvel": [int(m.jnt_dofadr[i]) for i in ids],
            },
            actuator_range=(m.actuator_ctrlrange[: len(ids), 0].copy(), m.actuator_ctrlrange[: len(ids), 1].copy()),
            output_max=(OSC_POS_LIMIT,) * 3 + (OSC_ORI_LIMIT,) * 3,
            output_min=(-OSC_POS_LIMIT,) * 3 + (-OSC_ORI_LIMIT,) * 3,
            kp=OSC_KP,
            damping_ratio=OSC_DAMPING_RATIO,
            input_ref_frame="world",
            uncouple_pos_ori=True,
            lite_physics=True,
            part_name="right",
            naming_prefix="robot0_",
        )
        self.fingers = np.zeros(2)  # robosuite's gripper `current_action`: [-1, 1] per finger

    def reset(self, home: np.ndarray) -> None:
        self.osc.update_initial_joints(np.asarray(home, float))  # the nullspace target; the goal becomes the current pose
        half = FINGER_OPEN / 2
        self.fingers = np.array([self.data.ctrl[7] / half - 1.0, 1.0 + self.data.ctrl[8] / half])

    def step(self, action: np.ndarray, substeps: int) -> None:
        d = self.data
        n = len(self.osc.qpos_index)
        for k in range(substeps):
            mujoco.mj_step1(self.model, d)  # kinematics, mass matrix and bias forces for the controller
            if k == 0:
                self.osc.set_goal(np.asarray(action[:6], float))
            torques = self.osc.run_controller()
            d.ctrl[:n] = np.clip(torques, self.osc.actuator_min, self.osc.actuator_max)
            self.fingers = np.clip(self.fingers + np.array([-1.0, 1.0]) * GRIPPER_SPEED * np.sign(action[6]), -1.0, 1.0)
            d.ctrl[n : n + 2] = FINGER_OPEN / 2 * (1.0 + self.fingers[0]), -FINGER_OPEN / 2 * (1.0 - self.fingers[1])
            mujoco.mj_step2(self.model, d)
