"""The profiles (`profile=` of the generator): the recorded features, camera, state and action
names and shapes, and the joint limits.

Every consumer reads them from here — the writer and the reader, training, the exam's
environment and policies — so a dimension or a camera name is written down once. A profile is
what one dataset or exam records and how its actions drive the arm:

* `native` — joint-position targets through position servos, a 16-d state, 128 px cameras;
* `libero` — the convention of LIBERO and the VLAs trained on it (lerobot's LIBERO datasets):
  7-d end-effector deltas through robosuite's OSC_POSE controller, an 8-d state (grip-site
  position, axis-angle of the hand body's orientation, the two finger positions), cameras
  `image` (agentview) and `image2` (wrist) at 256 px, stored as lerobot's LIBERO datasets store
  them: upright and mirrored left to right (robosuite's raw OpenGL frame turned 180 degrees,
  which is what lerobot's LiberoProcessorStep and openpi's LIBERO client feed a policy).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STATE_KEY = "observation.state"
ACTION_KEY = "action"
TASK_KEY = "task"  # the instruction, as lerobot names it
IMAGE_PREFIX = "observation.images."
AGENTVIEW, WRIST = "agentview", "wrist"  # the front camera that sees the whole workspace; the hand camera

ARM_JOINTS = 7
# Franka Panda joint limits (rad), as robosuite's model declares them.
JOINT_LOW = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
JOINT_HIGH = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
GRIPPER_OPEN, GRIPPER_CLOSED = -1.0, 1.0
# LIBERO's OSC_POSE output limits: an action of 1 moves the goal 5 cm / 0.5 rad.
OSC_POS_LIMIT, OSC_ORI_LIMIT = 0.05, 0.5
LIBERO_SETTLE_STEPS = 10  # lerobot's LIBERO env sends this many [0]*6+[-1] actions before the policy acts


@dataclass(frozen=True)
class Profile:
    """A profile: what a dataset records and a policy exchanges each control step.

    `cameras` maps each recorded camera (feature name) to the model camera it renders; actions
    are bounded by `action_low`/`action_high` elementwise.
    """

    name: str
    cameras: dict[str, str]
    state_names: tuple[str, ...]
    action_names: tuple[str, ...]
    action_low: tuple[float, ...]
    action_high: tuple[float, ...]
    action_meaning: str
    controller: str  # "joint_servo" or "osc_pose" (oracle/drives.py)
    image_size: int  # default frame size, pixels
    mirrored: bool = False  # frames stored mirrored left to right
    settle_steps: int = 0  # actions that hold the robot before an exam rollout's policy acts

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(self.cameras)

    @property
    def agentview(self) -> str:
        """The recorded camera that renders the model's front camera, the one that sees the whole workspace."""
        return next(c for c, model in self.cameras.items() if model == NATIVE.cameras[AGENTVIEW])

    @property
    def state_size(self) -> int:
        return len(self.state_names)

    @property
    def action_size(self) -> int:
        return len(self.action_names)

    def image_key(self, camera: str) -> str:
        return IMAGE_PREFIX + camera

    @property
    def image_keys(self) -> tuple[str, ...]:
        return tuple(self.image_key(c) for c in self.cameras)

    @property
    def hand(self) -> slice:
        """Where the state holds the hand's position (x, y, z, m, in the world frame)."""
        start = next(i for i, name in enumerate(self.state_names) if name in ("ee_x", "eef_x"))
        return slice(start, start + 3)

    def hold_action(self, home: tuple[float, ...]) -> np.ndarray:
        """The action that keeps the arm still with the gripper open (what a settle step sends):
        the home joint targets, or a zero end-effector delta."""
        arm = np.asarray(home) if self.controller == "joint_servo" else np.zeros(self.action_size - 1)
        return np.array([*arm, GRIPPER_OPEN], np.float32)


NATIVE = Profile(
    name="native",
    cameras={AGENTVIEW: "agentview", WRIST: "robot0_eye_in_hand"},
    state_names=(
        *(f"joint{i}" for i in range(1, ARM_JOINTS + 1)),
        "finger_left",
        "finger_right",
        "ee_x",
        "ee_y",
        "ee_z",
        "ee_qw",
        "ee_qx",
        "ee_qy",
        "ee_qz",
    ),
    action_names=(*(f"joint{i}_target" for i in range(1, ARM_JOINTS + 1)), "gripper"),
    action_low=(*JOINT_LOW, GRIPPER_OPEN),
    action_high=(*JOINT_HIGH, GRIPPER_CLOSED),
    action_meaning="joint-position targets 1-7 (rad) and gripper command (-1 open, +1 closed), held for 1/fps s",
    controller="joint_servo",
    image_size=128,
)
LIBERO = Profile(
    name="libero",
    cameras={"image": "agentview", "image2": "robot0_eye_in_hand"},
    state_names=(
        "eef_x",
        "eef_y",
        "eef_z",
        "eef_axis_angle_x",
        "eef_axis_angle_y",
        "eef_axis_angle_z",
        "finger_left",
        "finger_right",
    ),
    action_names=("dx", "dy", "dz", "drx", "dry", "drz", "gripper"),
    action_low=(-1.0,) * 7,
    action_high=(1.0,) * 7,
    action_meaning=(
        f"end-effector delta through OSC_POSE: position / {OSC_POS_LIMIT} m and axis-angle rotation (world frame) "
        f"/ {OSC_ORI_LIMIT} rad, clipped to [-1, 1]; gripper -1 open, +1 closed"
    ),
    controller="osc_pose",
    image_size=256,
    mirrored=True,
    settle_steps=LIBERO_SETTLE_STEPS,
)
PROFILES = {profile.name: profile for profile in (NATIVE, LIBERO)}


def named(name: str) -> Profile:
    """The profile called `name` (a `profile=` option's value), or a ValueError naming the known ones."""
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown profile {name!r}; known: {', '.join(PROFILES)}") from None
