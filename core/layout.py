"""The recorded features: camera, state and action names and shapes, and the joint limits.

Every consumer reads them from here — the writer and the reader, training, the exam's
environment and policies — so a dimension or a camera name is written down once. A layout is
what one dataset or exam records; `native` is the one the generator writes today.
"""

from __future__ import annotations

from dataclasses import dataclass

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


@dataclass(frozen=True)
class FeatureLayout:
    """What a dataset records and a policy exchanges each control step.

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

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(self.cameras)

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


NATIVE = FeatureLayout(
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
)
LAYOUTS = {layout.name: layout for layout in (NATIVE,)}
