"""The oracle's skill API: what a referent's demonstration is written in (core/demo.py declares it).

Each skill is a few motions (oracle/motion.py) kept clear of what stands in the scene
(oracle/clearance.py), reading object poses from the simulation. A demonstration reads like a few
lines, e.g. `skills.grasp(spec.target); skills.lift()`.
"""

from __future__ import annotations

import numpy as np

from core import catalog, contact
from core.rotations import matrix_yaw, yaw_matrix
from core.success import PUSH_DIRECTION
from oracle.clearance import CARRY_MARGIN, FINGER_TIP
from oracle.furniture import FurnitureSkills
from oracle.ik import DOWN, IKError, grasp_yaw
from oracle.motion import CLOSED

RETREAT = 0.1  # how far the hand rises from where it let go
REACH_STEP = 0.01  # how far at a time a release point out of reach moves toward the robot
SWIFT_LIFT = 0.15  # the highest lift made as one time-optimal joint move
OVER_RIM = 0.025  # how far over a container's rim the grip site stays as it lets go inside (the fingertips clear the rim)
# how far at a time, and how many times, a held object slides out from under something; how far clear of it
UNDER_STEP, UNDER_STEPS, UNDER_MARGIN = 0.03, 5, 0.01
# a dish dragged by its inner wall: the wall's thickness, how far behind its centre the fingers come
# down, and how far above its bottom their tips are sent (below it: the hand presses on the floor, and holds the wall)
DISH_WALL, DISH_SET_BACK, DISH_FLOOR = 0.023, 0.02, -0.003
# a grasp whose hand would come down this near a neighbour is turned a quarter, where the thing is a box
# (its long side this many times its narrow one) that fits the fingers along it with this much to spare (`_roomier`)
TURN_NEAR, TURN_BOX, TURN_SPARE = 0.005, 1.3, 0.003


class Skills(FurnitureSkills):
    """grasp, lift, place (or lay along a sloping shelf), push, and the furniture's motions (turn a
    knob, pull a drawer open: oracle/furniture.py), over the scene of one episode."""

    placed = False  # whether the hand has let something go where it was brought (a goal before this one's)

    def open(self, steps: int = 6) -> None:
        self.held, self.gentle = None, False
        super().open(steps)

    def rise(self) -> None:
        """Straight up until the hand passes over every object, where it is lower: where a plan that
        changes course mid-approach starts, so the new way to another object sweeps nothing over."""
        ee = self.scene.ee_pos()
        if ee[2] < self.clearance():
            self.move_linear([ee[0], ee[1], self.clearance()])

    def carry_on(self, object_id: str) -> None:
        """Take up a plan with `object_id` in the closed hand, turned as the plan before left it (a
        course changed while carrying it: the new plan's grasp of it is already done)."""
        kind = self._kind(object_id)
        self.held, self.gentle, self.gripper = (object_id, contact.grip_height(kind)), kind.neck, CLOSED
        self.yaw = matrix_yaw(self.scene.ee_rot() @ DOWN.T)

    def grasp(self, object_id: str, approach: float = 0.07, onto: str | None = None) -> None:
        """Come down on the object from above, fingers across its narrow axis, and close; to be laid
        `onto` a sloping shelf, fingers across the slope (the hand then turns it down along it).
        Nothing when the hand already holds it (`carry_on`)."""
        if self.held is not None and self.held[0] == object_id:
            return
        kind = self._kind(object_id)
        pos = self.scene.object_pos(object_id)  # where it stood before the hand came near
        top = contact.top(kind, pos)
        point = contact.grasp_point(kind, pos)
        axis = self.scene.object_yaw(object_id) + (0.0 if kind.grasp_axis == "x" else np.pi / 2)
        if onto is not None and self._kind(onto).shelf is not None:
            x = self._shelf_axes(onto)[:, 0]
            axis = float(np.arctan2(x[1], x[0])) + np.pi / 2
        if kind.rim:  # fingers across the wall, closing along its radius
            axis = self._rim_side(kind, pos, top[2])
            point[:2] = top[:2] = pos[:2] + kind.rim * np.array([np.cos(axis), np.sin(axis)])
        if kind.handle is not None:  # down onto the handle, turned as the thing is
            point = top = pos + yaw_matrix(self.scene.object_yaw(object_id)) @ np.asarray(kind.handle)
        yaw = grasp_yaw(axis)
        if not kind.rim and kind.handle is None and onto is None:
            yaw = self._roomier(object_id, point, yaw)
        above = [top[0], top[1], max(top[2] + approach, self.clearance())]
        if self.placed:  # from where an earlier goal let go (the basket) the way here sagged into what stands
            # near it (a can pushed off 7 cm, LIBERO-10's living room): straight over it at the hand's height first
            self.move_linear([top[0], top[1], max(self.scene.ee_pos()[2], above[2])])
        self.move_to(above, yaw)
        if kind.rim:  # straight down onto the wall: a joint-space path could sweep a finger through the bowl
            self.move_linear(point)
        else:
            self.move_to(point, yaw)
        self.close()
        self.held = (object_id, contact.grip_height(kind))
        self.gentle = kind.neck  # held by a narrow neck, a bottle swings: carried gently

    def _roomier(self, object_id: str, point: np.ndarray, yaw: float) -> float:
        """`yaw`, or the hand turned a quarter where, closing at `yaw`, it would come within TURN_NEAR of
        a neighbour (the hand is 20 cm wide along the axis its fingers close on: LIBERO-10's living room
        stands the milk 11 cm beside the butter, and the hand came down on the milk's top), the thing is a
        box (one side TURN_BOX times the other: a can turned made LIBERO-10's soup fail, measured) that the
        fingers fit across its long side with TURN_SPARE to spare, and closing there passes farther off."""
        kind = self._kind(object_id)
        narrow, other = (kind.size[0], kind.size[1]) if kind.grasp_axis == "x" else (kind.size[1], kind.size[0])
        if other > catalog.GRIPPER_SPAN - TURN_SPARE or other < narrow * TURN_BOX:  # not a box that fits turned
            return yaw

        def gap(at: float) -> float:  # how near the hand closing at that yaw comes to a neighbour
            try:
                return self.scene.hand_gap([self.ik.solve(point, at, seed=self.q)], None, self.standing(object_id), CARRY_MARGIN)
            except IKError:
                return -np.inf

        near, turned = gap(yaw), grasp_yaw(yaw + np.pi)  # grasp_yaw(axis) is axis - pi/2: a quarter on is yaw + pi
        if near >= TURN_NEAR:
            return yaw
        return turned if gap(turned) > near else yaw

    def lift(self, height: float = 0.15) -> None:
        """Raise the hand straight up by `height`; what it holds first slides toward the robot out
        from under whatever hangs over it (an open drawer over a bowl)."""
        if self.held is not None:
            self._out_from_under(self.held[0], height)
        if height > SWIFT_LIFT:  # straight and steady: a bowl held by its wall shakes loose on a long time-optimal rise
            self.move_linear(self.scene.ee_pos() + [0.0, 0.0, height], speed=0.2)
        else:
            self.move_to(self.scene.ee_pos() + [0.0, 0.0, height])
        self.hold(2)

    def _out_from_under(self, object_id: str, height: float) -> None:
        kind = self._kind(object_id)
        toward = np.subtract(self.scene.world.robot_base[:2], self.scene.object_pos(object_id)[:2])
        toward /= np.linalg.norm(toward)
        radius = max(kind.size[:2]) / 2 + UNDER_MARGIN
        footprint = [np.zeros(2)] + [
            r * np.array([np.cos(a), np.sin(a)])
            for r in (radius / 2, radius)
            for a in np.linspace(0, 2 * np.pi, 16, endpoint=False)
        ]
        for _ in range(UNDER_STEPS):
            pos = self.scene.object_pos(object_id)
            top = contact.top(kind, pos)[2] + 0.002
            if all(self.scene.ceiling_above(pos[:2] + r, top, object_id) > top + height for r in footprint):
                return
            self.move_linear(self.scene.ee_pos() + [*(UNDER_STEP * toward), 0.0])

    def place(self, destination_id: str, at: tuple[float, float] | None = None) -> None:
        """Carry the held object over the destination (`at` from its centre, where given), lower it
        onto it (lay it along a sloping shelf), release, retreat; the hand and what it carries keep
        CARRY_MARGIN from the objects standing beside the way."""
        if self.held is None:
            raise RuntimeError("place() needs an object in the gripper: grasp() first")
        if self._kind(destination_id).shelf is not None:
            self._lay(destination_id)
            return
        over = self._drop_point(destination_id)
        if at is not None:
            over[:2] = self.top_of(destination_id)[:2] + np.asarray(at)
        held = self._kind(self.held[0])
        rim = held.rim > 0  # a bowl, held by its wall, hanging off-centre
        aside = rim or held.handle is not None  # held off its centre: by its wall, by its handle
        if rim:  # the hand goes where the bowl's centre comes over the destination
            over[:2] -= self.scene.object_pos(self.held[0])[:2] - self.scene.ee_pos()[:2]
        elif aside:  # and where the thing's origin does, the handle where it is on the thing standing (hanging, it swings)
            over[:2] += (yaw_matrix(self.scene.object_yaw(self.held[0])) @ np.asarray(held.handle))[:2]
        destination = self._kind(destination_id)
        release_z = contact.release_point(destination, self.scene.object_pos(destination_id), self._kind(self.held[0]))[2]
        release_z += destination.drawer.drop if destination.drawer else 0.0
        if destination.walled:  # down inside, over its floor: a tall carton dropped from over the rim tips against a wall
            release_z = min(release_z, max(self._lowest_release(destination_id), self.top_of(destination_id)[2] + OVER_RIM))
        over_all = self.clearance_along(over) if held.handle is not None else self.clearance()
        carry_z = max(self.scene.ee_pos()[2], release_z + 0.06, over_all + self.held[1])
        over = self._within_reach(over, max(carry_z, release_z + RETREAT), destination_id)
        above, down = [over[0], over[1], carry_z], [over[0], over[1], release_z]
        yaw = self.yaw if aside else self._release_yaw(above, down, destination_id)  # turned, it would hang elsewhere
        across = self._path_to(above, yaw)
        # Up first where the way across, still rising, would pass near a standing object, a hanging
        # bowl could swing into furniture, or a bottle hanging by its neck pass under the cabinet's
        # top (where the hand reaches that high: from the table's far corner it crosses on the rise).
        up = [*self.scene.ee_pos()[:2], carry_z]
        if rim or (self.gentle and self._reachable(up)) or self._gap(across[1], destination_id) < CARRY_MARGIN:
            self.move_to(up)
            across = self._path_to(above, yaw)
        self._follow(*across, yaw)
        if rim:  # straight down from where the hand is
            self.move_linear(down)
        else:  # from over the destination: an end-effector controller lags the plan, and would come down on a diagonal
            self._settle(self.q)
            self.move_to(down)
        self.open()
        self.placed = True
        self.move_to([over[0], over[1], release_z + RETREAT])

    def _lowest_release(self, container_id: str) -> float:
        """The grip site's height when the held thing is let go PLACE_CLEARANCE over the container's floor
        (the bottom of its `contain` box)."""
        floor = contact.floor(self._kind(container_id), self.scene.object_pos(container_id))
        return floor + contact.grip_height(self._kind(self.held[0])) + contact.PLACE_CLEARANCE

    def _within_reach(self, over: np.ndarray, height: float, destination_id: str) -> np.ndarray:
        """`over`, or where the hand cannot reach that high there (a tall bottle carried over the
        cabinet), the first point toward the robot, within the destination's `inner` square, where it can."""
        toward = np.subtract(self.scene.world.robot_base[:2], over[:2])
        toward /= np.linalg.norm(toward)
        inner = self._kind(destination_id).inner
        for step in np.arange(0.0, inner / np.max(np.abs(toward)), REACH_STEP):
            point = np.append(over[:2] + step * toward, over[2])
            if self._reachable(np.append(point[:2], height)):
                return point
        return over

    def _reachable(self, pos: list[float] | np.ndarray) -> bool:
        """Whether the hand, pointing down at its yaw, reaches `pos`."""
        try:
            self.ik.solve(np.asarray(pos, float), self.yaw, seed=self.q)
        except IKError:
            return False
        return True

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

    def push_to(self, object_id: str, region_id: str, speed: float = 0.08) -> None:
        """Slide a dish (a plate) along the table to the region's centre, straight or round a corner,
        whichever way keeps it farthest from the objects standing beside it (`_dish_route`).

        The closed fingers come down inside it, on the side away from where it goes, and drag it by
        its inner wall; the hand stays over the dish all along, so nothing beside the way (a
        cabinet's handles) is in the hand's way. At a corner the fingers cross to the other side.
        """
        kind = self._kind(object_id)
        inside = kind.size[0] / 2 - DISH_WALL  # how far from its centre the inner wall is
        self.gripper = CLOSED
        for leg, stop in enumerate(self._dish_route(object_id, self.scene.object_pos(region_id)[:2])):
            start = self.scene.object_pos(object_id)[:2]
            way = np.array([*(stop - start), 0.0])
            distance = float(np.linalg.norm(way))
            direction = way / distance
            down = self.bottom_of(object_id) - DISH_SET_BACK * direction + [0.0, 0.0, FINGER_TIP + DISH_FLOOR]
            if leg == 0:
                self.move_to(down + [0.0, 0.0, 0.08], yaw=grasp_yaw(float(np.arctan2(direction[1], direction[0])) + np.pi / 2))
            self.move_linear(down)
            self.move_linear(down + (distance + inside - DISH_SET_BACK) * direction, speed=speed)
        self.move_to(self.scene.ee_pos() + [0.0, 0.0, 0.1])

    def _dish_route(self, object_id: str, goal: np.ndarray) -> list[np.ndarray]:
        """The stops of the way a dish is slid to `goal`: straight there, or by the corner of either
        axis first, the one whose sweep passes farthest from the other objects' footprints."""
        radius = max(self._kind(object_id).size[:2]) / 2
        start = self.scene.object_pos(object_id)[:2]
        others = self.standing(object_id)
        routes = [[goal], [np.array([start[0], goal[1]]), goal], [np.array([goal[0], start[1]]), goal]]

        def gap(route: list[np.ndarray]) -> float:
            stops = [start, *route]
            swept = [a + t * (b - a) for a, b in zip(stops, stops[1:]) for t in np.linspace(0, 1, 25)]
            return min((self._footprint_gap(o, p) for o in others for p in swept), default=np.inf) - radius

        return max(routes, key=gap)

    def _footprint_gap(self, object_id: str, xy: np.ndarray) -> float:
        """How far the point `xy` is from the object's footprint (its resting extents, turned as it stands)."""
        yaw = self.scene.object_yaw(object_id)
        local = yaw_matrix(yaw)[:2, :2].T.copy() @ (xy - self.scene.object_pos(object_id)[:2])
        outside = np.maximum(np.abs(local) - np.asarray(self._kind(object_id).size[:2]) / 2, 0.0)
        return float(np.linalg.norm(outside))
