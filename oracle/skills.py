"""The oracle's skill API: what a referent's demonstration is written in (core/demo.py declares it).

Each skill is a few motions (oracle/motion.py) kept clear of what stands in the scene
(oracle/clearance.py), reading object poses from the simulation. A demonstration reads like a few
lines, e.g. `skills.grasp(spec.target); skills.lift()`.
"""

from __future__ import annotations

import numpy as np

from core import contact
from core.success import PUSH_DIRECTION
from oracle.clearance import CARRY_MARGIN, Clearance
from oracle.ik import grasp_yaw
from oracle.motion import CLOSED


class Skills(Clearance):
    """grasp, lift, place and push, over the scene of one episode."""

    def open(self, steps: int = 6) -> None:
        self.held = None
        super().open(steps)

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
        across = self._path_to(above, yaw)
        # Up first where the way across, still rising, would pass near a standing object, or a
        # hanging bowl could swing into furniture.
        if rim or self._gap(across[1], destination_id) < CARRY_MARGIN:
            self.move_to([*self.scene.ee_pos()[:2], carry_z])
            across = self._path_to(above, yaw)
        self._follow(*across, yaw)
        if rim:  # straight down from where the hand is
            self.move_linear(down)
        else:  # from over the destination: an end-effector controller lags the plan, and would come down on a diagonal
            self._settle(self.q)
            self.move_to(down)
        self.open()
        self.move_to([over[0], over[1], release_z + 0.1])

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
