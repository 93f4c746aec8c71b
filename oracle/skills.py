"""The oracle's skill API: what a referent's demonstration is written in.

Each skill plans (mink IK for the pose, ruckig for the joint path) and executes at once on the
scene, reading object poses from the simulation, and records every action it executes. A plan
reads like a few lines, e.g. `skills.grasp(spec.target); skills.lift()`.
"""

from __future__ import annotations

import mujoco
import numpy as np

from core import catalog, contact
from core.layout import NATIVE, OSC_ORI_LIMIT, OSC_POS_LIMIT
from core.spec import EpisodeSpec
from core.success import PUSH_DIRECTION
from oracle.ik import ArmIK, IKError, grasp_yaw
from oracle.scene import Scene, axis_angle
from oracle.trajectory import Limits, joint_path

OPEN, CLOSED = -1.0, 1.0
# Under an end-effector-delta controller (the libero profile) the plan stays a joint path; each
# control step sends the delta from where the hand is to where the path's next waypoint puts it,
# amplified (the OSC covers only part of a commanded delta in one step), and before the gripper
# closes or opens the hand settles on its goal.
DELTA_GAIN = 3.0
SETTLE_POS, SETTLE_ROT, MAX_SETTLE_STEPS = 0.005, 0.05, 40  # m, rad, control steps
# robosuite's Panda gripper, open (measured): each finger spans this far from the grip site along
# the closing axis and this far across it, its tip this far below the grip site.
FINGER_REACH, FINGER_HALF_WIDTH, FINGER_TIP = (0.039, 0.066), 0.011, 0.0095
FINGER_MARGIN = 0.005  # how far above whatever stands beside a bowl the outer fingertip stays
CARRY_MARGIN = 0.03  # how far the hand, and what it carries, passes from the objects standing in the scene (m)
RELEASE_TURNS = np.radians([0.0, 45.0, -45.0, 90.0, -90.0])  # how far the hand may turn what it carries before lowering it
RIM_SIDES = np.radians([0.0, 30.0, -30.0, 60.0, -60.0])  # where on a bowl's wall to grasp, from the robot-facing side


def rotation_vector(rot: np.ndarray) -> np.ndarray:
    """The axis-angle vector (world frame) of a rotation matrix, angle in [0, pi]."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.flatten())
    return axis_angle(quat if quat[0] >= 0 else -quat)


class Skills:
    def __init__(self, scene: Scene, ik: ArmIK, spec: EpisodeSpec, limits: Limits = Limits()) -> None:
        self.scene = scene
        self.ik = ik
        self.spec = spec
        self.limits = limits
        self.dt = 1.0 / spec.sim.fps
        self.q = scene.data.qpos[scene.arm_qpos].copy()  # where the arm is: the home pose, or a recorded start
        self.yaw = 0.0
        self.gripper = OPEN
        self.held: tuple[str, float] | None = None  # (object id, grip site height above its bottom)
        self.actions: list[np.ndarray] = []
        self.states: list[np.ndarray] = []  # physics state before each action
        self.deltas = scene.layout.controller != NATIVE.controller

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

    def _kind(self, object_id: str) -> catalog.Kind:
        return self.scene.world.kind(self.spec.object(object_id).kind)

    def bottom_of(self, object_id: str) -> np.ndarray:
        """Centre of the object's bottom face, from its current simulated pose."""
        pos = self.scene.object_pos(object_id)
        return np.array([pos[0], pos[1], pos[2] - self._kind(object_id).bottom])

    def top_of(self, object_id: str) -> np.ndarray:
        """Centre of the object's top face, from its current simulated pose."""
        return contact.top(self._kind(object_id), self.scene.object_pos(object_id))

    def clearance(self, margin: float = 0.05) -> float:
        """A height at which the hand passes over every object in the scene (places on furniture
        are not in the way: like the furniture, they stand apart from the objects' places)."""
        return max(self.top_of(o.id)[2] for o in self.spec.objects if not self._kind(o.id).is_site) + margin

    def _plan(self, pos: np.ndarray, yaw: float, start: np.ndarray | None = None) -> tuple[np.ndarray, list[np.ndarray]]:
        """The arm's goal putting the grip site at `pos`, and its joint path there from `start`
        (default: where the arm is)."""
        start = self.q if start is None else start
        goal = self.ik.solve(np.asarray(pos, dtype=float), yaw, seed=start)
        return goal, joint_path(start, goal, self.dt, self.limits)

    def _follow(self, goal: np.ndarray, path: list[np.ndarray], yaw: float) -> None:
        for q in path:
            self._execute(q)
        self.q, self.yaw = goal, yaw

    def move_to(self, pos: np.ndarray, yaw: float | None = None) -> None:
        """Grip site to `pos`, pointing down, at `yaw` (default: keep the current yaw)."""
        yaw = self.yaw if yaw is None else yaw
        self._follow(*self._plan(pos, yaw), yaw)

    def move_linear(self, pos: np.ndarray, speed: float = 0.12) -> None:
        """Grip site along a straight line to `pos` (minimum-jerk timing), e.g. to push."""
        start = self.scene.ee_pos()
        goal = np.asarray(pos, dtype=float)
        steps = max(2, int(np.ceil(np.linalg.norm(goal - start) / (speed * self.dt))))
        for k in range(1, steps + 1):
            tau = k / steps
            s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
            self.q = self.ik.solve(start + s * (goal - start), self.yaw, seed=self.q)
            self._execute(self.q)

    def hold(self, steps: int) -> None:
        for _ in range(steps):
            self._execute(self.q)

    def close(self, steps: int = 8) -> None:
        self._settle(self.q)
        self.gripper = CLOSED
        self.hold(steps)

    def open(self, steps: int = 6) -> None:
        self._settle(self.q)
        self.gripper = OPEN
        self.held = None
        self.hold(steps)

    def grasp(self, object_id: str, approach: float = 0.07) -> None:
        """Come down on the object from above, fingers across its narrow axis, and close."""
        kind = self._kind(object_id)
        pos = self.scene.object_pos(object_id)  # where it stood before the hand came near
        top = contact.top(kind, pos)
        point = contact.grasp_point(kind, pos)
        axis = self.scene.object_yaw(object_id) + (0.0 if kind.grasp_axis == "x" else np.pi / 2)
        if kind.rim:  # fingers across the wall, closing along its radius
            axis = self._rim_side(kind, pos, top[2])
            point[:2] = top[:2] = pos[:2] + kind.rim * np.array([np.cos(axis), np.sin(axis)])
        yaw = grasp_yaw(axis)
        self.move_to([top[0], top[1], max(top[2] + approach, self.clearance())], yaw)
        if kind.rim:  # straight down onto the wall: a joint-space path could sweep a finger through the bowl
            self.move_linear(point)
        else:
            self.move_to(point, yaw)
        self.close()
        self.held = (object_id, contact.grip_height(kind))

    def _rim_side(self, kind: catalog.Kind, pos: np.ndarray, top: float) -> float:
        """Which side of a bowl's wall to grasp (the direction from its centre): the first, from
        the one facing the robot's base, under whose outer finger nothing (a neighbour, a stove)
        stands higher than the fingertip comes at the grasp depth; if none is clear (a bowl in a
        drawer), the facing side."""
        toward = np.subtract(self.scene.world.robot_base[:2], pos[:2])
        facing = float(np.arctan2(toward[1], toward[0]))
        above, lowest = self.clearance(), top - kind.grasp_depth() - FINGER_TIP - FINGER_MARGIN
        widths = (-FINGER_HALF_WIDTH, 0.0, FINGER_HALF_WIDTH)
        for side in facing + RIM_SIDES:
            radial, across = np.array([np.cos(side), np.sin(side)]), np.array([-np.sin(side), np.cos(side)])
            under = (pos[:2] + (kind.rim + r) * radial + w * across for r in FINGER_REACH for w in widths)
            if all(self.scene.surface_below(xy, above) < lowest for xy in under):
                return float(side)
        return facing

    def lift(self, height: float = 0.15) -> None:
        self.move_to(self.scene.ee_pos() + [0.0, 0.0, height])
        self.hold(2)

    def place(self, destination_id: str) -> None:
        """Carry the held object over the destination, lower it onto it, release, retreat; the hand
        and what it carries keep CARRY_MARGIN from the objects standing beside the way."""
        if self.held is None:
            raise RuntimeError("place() needs an object in the gripper: grasp() first")
        over = self.top_of(destination_id)
        rim = self._kind(self.held[0]).rim > 0  # a bowl, held by its wall, hanging off-centre
        if rim:  # the hand goes where the bowl's centre comes over the destination
            over[:2] -= self.scene.object_pos(self.held[0])[:2] - self.scene.ee_pos()[:2]
        release_z = contact.release_point(
            self._kind(destination_id), self.scene.object_pos(destination_id), self._kind(self.held[0])
        )[2]
        carry_z = max(self.scene.ee_pos()[2], release_z + 0.06, self.clearance() + self.held[1])
        above, down = [over[0], over[1], carry_z], [over[0], over[1], release_z]
        yaw = self.yaw if rim else self._release_yaw(above, down, destination_id)  # a turned bowl would hang elsewhere
        across = self._plan(above, yaw)
        # Up first where the way across, still rising, would pass near a standing object, or a
        # hanging bowl could swing into furniture.
        if rim or self._gap(across[1], destination_id) < CARRY_MARGIN:
            self.move_to([*self.scene.ee_pos()[:2], carry_z])
            across = self._plan(above, yaw)
        self._follow(*across, yaw)
        if rim:  # straight down from where the hand is
            self.move_linear(down)
        else:  # from over the destination: an end-effector controller lags the plan, and would come down on a diagonal
            self._settle(self.q)
            self.move_to(down)
        self.open()
        self.move_to([over[0], over[1], release_z + 0.1])

    def _release_yaw(self, above: list[float], down: list[float], destination_id: str) -> float:
        """The hand's yaw as it comes down from `above` the destination to `down`: the first of
        RELEASE_TURNS from its own that keeps CARRY_MARGIN from every standing object, else the one
        passing farthest (the hand reaches 10 cm each way along its fingers' closing axis, 3 cm across)."""
        gaps = {}
        for yaw in (self.yaw + RELEASE_TURNS).tolist():
            try:
                over, _ = self._plan(above, yaw)
                gaps[yaw] = self._gap(self._plan(down, yaw, start=over)[1], destination_id)
            except IKError:  # out of the wrist's reach turned so
                continue
            if gaps[yaw] >= CARRY_MARGIN:
                break
        return max(gaps, key=lambda yaw: gaps[yaw], default=self.yaw)

    def _gap(self, path: list[np.ndarray], destination_id: str) -> float:
        """How close (up to CARRY_MARGIN) the hand, with what it holds, passes the objects standing in
        the scene, the destination aside, along the joint path `path`."""
        held = self.held[0] if self.held else None
        standing = [o.id for o in self.spec.objects if o.id not in (held, destination_id) and not self._kind(o.id).is_site]
        return self.scene.hand_gap(path, held, standing, CARRY_MARGIN)

    def push(self, object_id: str, distance: float = 0.09, speed: float = 0.12) -> None:
        """Slide the object along the table (away from the robot) with the closed fingers.

        The fingers come down well behind the object on a straight line, so they never land on
        it. Short objects would wedge under the tapered fingertips, so they are pushed with one
        finger's flat outer face (fingers one behind the other); tall ones with both side by side.
        """
        kind = self._kind(object_id)
        direction = np.array([*PUSH_DIRECTION, 0.0])
        gap = 0.04
        reach = float(np.hypot(kind.size[0], kind.size[1])) / 2 + gap
        height = min(0.03, kind.height / 2)  # grip-site height above the object's bottom
        behind = self.bottom_of(object_id) - reach * direction + [0.0, 0.0, height]
        self.gripper = CLOSED
        yaw = np.pi / 2 if kind.height < 0.07 else 0.0
        self.move_to(behind + [0.0, 0.0, 0.08], yaw=yaw)
        self.move_linear(behind)
        self.move_linear(behind + (distance + gap) * direction, speed=speed)
        self.move_to(self.scene.ee_pos() + [0.0, 0.0, 0.1])
