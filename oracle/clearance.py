"""Where the hand may go among the scene's objects: a height that passes over all of them, the side
of a bowl's wall whose outer finger has room, how close a path passes what stands beside it, the
turn of the hand that keeps what it carries clear as it comes down. Geometry over the simulated
scene, for the skills (oracle/skills.py)."""

from __future__ import annotations

import numpy as np

from core import catalog, contact
from oracle.ik import IKError
from oracle.motion import Motion

# robosuite's Panda gripper, open (measured): each finger spans this far from the grip site along
# the closing axis and this far across it, its tip this far below the grip site.
FINGER_REACH, FINGER_HALF_WIDTH, FINGER_TIP = (0.039, 0.066), 0.011, 0.0095
FINGER_MARGIN = 0.005  # how far above whatever stands beside a bowl the outer fingertip stays
# the hand's palm (its collision hull, measured): half its length along the closing axis and its
# width across, and how far above the grip site its underside is
PALM_HALF, PALM_OVER_GRIP = (0.104, 0.032), 0.031
CARRY_MARGIN = 0.03  # how far the hand, and what it carries, passes from the objects standing in the scene (m)
RELEASE_TURNS = np.radians([0.0, 45.0, -45.0, 90.0, -90.0])  # how far the hand may turn what it carries before lowering it
RIM_SIDES = np.radians(
    [0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0, 120.0, -120.0]
)  # where on a bowl's wall to grasp, from the robot-facing side


class Clearance(Motion):
    """The arm, and what it holds, among the objects of its scene."""

    held: tuple[str, float] | None = None  # (object id, grip site height above its bottom)

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

    def clearance_along(self, to: np.ndarray, margin: float = 0.05) -> float:
        """A height at which the held thing passes over every other object standing beside its straight
        way from here to over `to` (its footprint and theirs CARRY_MARGIN apart): what a thing hanging
        low from its handle is carried at, where passing over all of them reaches out of the arm's reach."""
        assert self.held is not None
        start, end = self.scene.object_pos(self.held[0])[:2], np.asarray(to[:2], float)
        reach = np.hypot(*self._kind(self.held[0]).size[:2]) / 2 + CARRY_MARGIN
        way, tops = end - start, [self.scene.world.surface_z]
        for o in self.spec.objects:
            kind = self._kind(o.id)
            if o.id == self.held[0] or kind.is_site:
                continue
            at = self.scene.object_pos(o.id)[:2]
            t = float(np.clip((at - start) @ way / max(float(way @ way), 1e-9), 0.0, 1.0))
            if np.linalg.norm(at - (start + t * way)) < reach + np.hypot(*kind.size[:2]) / 2:
                tops.append(float(self.top_of(o.id)[2]))
        return max(tops) + margin

    def _rim_side(self, kind: catalog.Kind, pos: np.ndarray, top: float) -> float:
        """Which side of a bowl's wall to grasp (the direction from its centre): the first, from
        the one facing the robot's base, under whose outer finger nothing (a neighbour, a stove)
        stands higher than the fingertip comes at the grasp depth, and over whose hand nothing
        (an open drawer) hangs lower than it comes down from; if none is clear (a bowl in a
        drawer), the facing side."""
        toward = np.subtract(self.scene.world.robot_base[:2], pos[:2])
        facing = float(np.arctan2(toward[1], toward[0]))
        above, lowest = self.clearance(), top - kind.grasp_depth() - FINGER_TIP - FINGER_MARGIN
        palm = top - kind.grasp_depth() + PALM_OVER_GRIP
        widths = (-FINGER_HALF_WIDTH, 0.0, FINGER_HALF_WIDTH)
        for side in facing + RIM_SIDES:
            radial, across = np.array([np.cos(side), np.sin(side)]), np.array([-np.sin(side), np.cos(side)])
            under = (pos[:2] + (kind.rim + r) * radial + w * across for r in FINGER_REACH for w in widths)
            hand = (
                pos[:2] + (kind.rim + r) * radial + w * across
                for r in np.linspace(-PALM_HALF[0], PALM_HALF[0], 5)
                for w in (-PALM_HALF[1], 0.0, PALM_HALF[1])
            )
            if all(self.scene.surface_below(xy, above) < lowest for xy in under) and all(
                self.scene.ceiling_above(xy, palm) > above for xy in hand
            ):
                return float(side)
        return facing

    def _release_yaw(self, above: list[float], down: list[float], destination_id: str) -> float:
        """The hand's yaw as it comes down from `above` the destination to `down`: the first of
        RELEASE_TURNS from its own that keeps CARRY_MARGIN from every standing object, else the one
        passing farthest (the hand reaches 10 cm each way along its fingers' closing axis, 3 cm across)."""
        gaps = {}
        for yaw in (self.yaw + RELEASE_TURNS).tolist():
            try:
                over, _ = self._path_to(above, yaw)
                gaps[yaw] = self._gap(self._path_to(down, yaw, start=over)[1], destination_id)
            except IKError:  # out of the wrist's reach turned so
                continue
            if gaps[yaw] >= CARRY_MARGIN:
                break
        return max(gaps, key=lambda yaw: gaps[yaw], default=self.yaw)

    def standing(self, *besides: str | None) -> list[str]:
        """The objects standing in the scene (not the places on furniture), those `besides` aside."""
        return [o.id for o in self.spec.objects if o.id not in besides and not self._kind(o.id).is_site]

    def _gap(self, path: list[np.ndarray], destination_id: str) -> float:
        """How close (up to CARRY_MARGIN) the hand, with what it holds, passes the objects standing in
        the scene, the destination aside, along the joint path `path`."""
        held = self.held[0] if self.held else None
        return self.scene.hand_gap(path, held, self.standing(held, destination_id), CARRY_MARGIN)
