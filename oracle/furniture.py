"""The furniture's skills: pull a drawer open and push it shut, turn the stove's knob, lay a bottle
along a sloping shelf, and where over an open drawer a carried thing is let down. Each reads its piece's
typed kind (core/furniture.py: `Drawer`, `Knob`, `Shelf`); the generic skills (oracle/skills.py)
build on these.
"""

from __future__ import annotations

import numpy as np

from core.furniture import Drawer, Inside, Shelf, Slot, Spot
from core.rotations import facing, turned, yaw_matrix
from oracle.clearance import CARRY_MARGIN, FINGER_TIP, Clearance
from oracle.ik import DOWN, grasp_yaw
from oracle.motion import CLOSED

KNOB_GRIP = 0.012  # how far below the top of the stove knob's ridge the fingers close on it
# how far the hand turns the knob (radians): past LIBERO's 0.5 with the fingers' slip (ours 1.06, LIBERO's 1.18:
# docs/LIBERO.md), short of its 2.1 stop; how fast (rad/s): faster, the knob's friction slips the fingers off
KNOB_TURN, KNOB_SPEED = 1.3, 0.3
# where the hand lines up in front of a drawer's handle; how far it pulls it (the drawer stops at 16 cm)
HANDLE_REACH, DRAWER_PULL = 0.08, 0.19
# laying a bottle along a sloping shelf (`_lay`): how far over the shelf its side is let go; how far
# downhill of where it lies the hand starts, and over it; how far off the shelf the hand turns it (in
# LAY_STEPS), and comes nearer; the steps it waits once let go; how far out of the shelf it backs off
LAY_GAP, LAY_START, LAY_ABOVE, LAY_OVER, LAY_NEAR = 0.025, 0.05, 0.05, 0.06, 0.04
LAY_STEPS, LAY_SETTLE, LAY_BACK = 6, 10, 0.08
# pushing a drawer shut: how far in front of it the fingertips come; how far past where it stands shut
# the hand is sent (it stops 1 cm past, LIBERO's `Close` wants it past 0: sent 1.5 cm past at 0.1 m/s,
# in LIBERO's simulator, whose arm lags more, it stayed 2 cm out); how fast; how far out the hand backs
# off before it rises (past the handle bar of the drawer above); how far below level it points
FRONT_GAP, SHUT_PAST, SHUT_SPEED, SHUT_BACK, SHUT_PITCH = 0.03, 0.04, 0.05, 0.06, float(np.radians(30))
BESIDE_MARGIN = 0.01  # how far inside a place's edge a thing let down beside another is aimed (it drifts as it lands)
# putting a thing in a drawer: how far the drawer is pulled (m: 12 cm of it then lie uncovered;
# wide open, its front would stand over what stands before the cabinet, the bowl to be put in it),
# and how high the thing is lifted (over the drawer's sides, so no later rise shakes it loose)
DRAWER_SLOT, DRAWER_LIFT = 0.13, 0.22
# putting a thing inside the microwave (`_push_inside`): how high it is lifted; how far over the floor it is
# let go (carried in straight from INSIDE_APPROACH before it: on a joint-space way in, it caught the floor's
# front edge); how far the hand backs off out of the opening, and rises, before it pushes; the push: the
# fingers' height over the floor, their gap before the thing's side, how far past the place it is sent, how fast
INSIDE_LIFT, INSIDE_DROP, INSIDE_BACK, INSIDE_RISE, INSIDE_APPROACH = 0.12, 0.012, 0.06, 0.08, 0.12
PUSH_LOW, PUSH_GAP, PUSH_PAST, PUSH_SPEED = 0.04, 0.02, 0.01, 0.08
# swinging a door shut (`_swing_shut`): how far out of the hinge's line the closed fingers press it, at its
# place (6 mm into its outer face); how far clear of it they come down; how far past shut they are sent (its
# hinge stops it there); in how many steps along the arc (12 took LIBERO-10's KITCHEN_SCENE6 past its 520)
DOOR_PRESS, DOOR_CLEAR, DOOR_PAST, DOOR_STEPS = 0.035, 0.04, 0.03, 6
# standing a thing in a narrow compartment (`_lean_in`): how far over the walls its foot is carried; in how
# many steps it is tilted there; how far over the floor its foot is let go; the steps it waits once let go
LEAN_OVER, LEAN_STEPS, LEAN_DROP, LEAN_SETTLE = 0.03, 4, 0.004, 10


class FurnitureSkills(Clearance):
    """The motions of the furniture's parts, over the scene of one episode."""

    def _shelf_axes(self, shelf_id: str) -> np.ndarray:
        """A sloping shelf's site axes in the world (columns): along the shelf, out of it (negated),
        up its slope."""
        return self.scene.body_pose(shelf_id)[1] @ self._kind(shelf_id).part(Shelf).turn()

    def _lay(self, shelf_id: str) -> None:
        """Lay the held object along a sloping shelf (the wine rack's), its top uphill: over the
        shelf, turn the hand with it down toward the slope, come down to LAY_GAP over the shelf, let
        go, and back off out of it."""
        axes, grip = self._shelf_axes(shelf_id), self.held[1]
        up, out = axes[:, 2], -axes[:, 1]
        along, rise = self._kind(shelf_id).part(Shelf).lay
        radius = min(self._kind(self.held[0]).size[:2]) / 2
        bottom = self.scene.object_pos(shelf_id) + along * axes[:, 0] + rise * up + (radius + LAY_GAP) * out
        downhill = -np.append(up[:2] / np.linalg.norm(up[:2]), 0.0)
        self.move_to(bottom + LAY_START * downhill + [0.0, 0.0, max(self.scene.ee_pos()[2] - bottom[2], grip + LAY_ABOVE)])
        pivot = np.cross([0.0, 0.0, 1.0], up)
        angle, upright = float(np.arccos(up[2])), yaw_matrix(self.yaw) @ DOWN
        for k in range(1, LAY_STEPS + 1):  # turned a step at a time, kept over the shelf as it turns
            turn = turned(pivot / np.linalg.norm(pivot), angle * k / LAY_STEPS)
            self.facing = turn @ upright
            self.move_to(bottom + grip * turn[:, 2] + (LAY_OVER * (1 - k / LAY_STEPS) + LAY_NEAR) * out)
        self.move_linear(bottom + grip * up, speed=0.05)
        self.open()
        self.hold(LAY_SETTLE)
        self.move_linear(self.scene.ee_pos() + LAY_BACK * out, speed=0.05)
        self.facing = None

    def turn_on(self, knob_id: str) -> None:
        """Take the knob's ridge from above, fingers across it, and turn the hand KNOB_TURN about
        the knob's axis (the way its joint turns on). Where the way to it passes near a standing
        thing (LIBERO-10's moka pot just set on the stove: LIBERO's simulator, its hand a few
        millimetres off ours, knocked it off), the hand goes over at the clearance height first."""
        axis, rot = self.scene.body_pose(knob_id)
        ridge = np.append(rot[:2, 1], 0.0)  # the ridge lies along the knob's y
        top = self.scene.surface_below(axis[:2], axis[2] + 0.3)
        yaw = grasp_yaw(float(np.arctan2(-ridge[0], ridge[1])))  # fingers closing across the ridge
        grip = np.array([axis[0], axis[1], top - KNOB_GRIP])
        above = grip + [0.0, 0.0, 0.07]
        if self._gap(self._path_to(above, yaw)[1], knob_id) < CARRY_MARGIN:  # over what stands beside the way, then down
            high = max(self.scene.ee_pos()[2], self.clearance())
            self.move_to([*self.scene.ee_pos()[:2], high], yaw)
            self.move_to([*above[:2], high], yaw)
        self.move_to(above, yaw)
        self.move_to(grip, yaw)
        self.close()
        self.twist(yaw + KNOB_TURN, KNOB_SPEED)
        self.hold(5)
        self.q = self.scene.data.qpos[self.scene.arm_qpos].copy()  # where the knob let the hand go: let go there
        self.open()
        self.move_to(grip + [0.0, 0.0, 0.1])

    def _drop_point(self, destination_id: str) -> np.ndarray:
        """Where over a destination a carried thing is let down: the centre of its top (where
        something already stands on it, `_beside`), or of an open drawer's uncovered part (between
        the cabinet's front and the drawer's)."""
        drawer, top = self._kind(destination_id).drawer, self.top_of(destination_id)
        if drawer is None:
            return self._beside(destination_id, top)
        mouth, front = drawer.opening
        return top + (mouth + front - self._pulled(destination_id)) / 2 * self._pull_direction(destination_id)

    def _beside(self, destination_id: str, top: np.ndarray) -> np.ndarray:
        """`top`, or where something already stands on or in the destination (LIBERO-10's second moka
        pot on the burner, second grocery in the basket), the point of the square the destination
        holds things in (its `inner`; a container's `contain` box, the carried thing's half width in
        from its edge) that is farthest from what stands there."""
        kind, held = self._kind(destination_id), self.held[0] if self.held else None
        half = max(kind.inner - BESIDE_MARGIN, 0.0)  # where a thing's origin may come on it
        if kind.contain is not None and held:  # in it: the whole thing inside
            half = max(kind.contain[1][0] - min(self._kind(held).size[:2]) / 2 - BESIDE_MARGIN, 0.0)
        standing = (self.scene.object_pos(o) for o in self.standing(held, destination_id))
        on = [
            at[:2] for at in standing if np.all(np.abs(at[:2] - top[:2]) < max(half, kind.inner)) and at[2] > top[2] - kind.height
        ]
        if not on or half == 0.0:
            return top
        grid = [top[:2] + [x, y] for x in np.linspace(-half, half, 9) for y in np.linspace(-half, half, 9)]
        best = max(grid, key=lambda p: min(float(np.linalg.norm(p - q)) for q in on))
        return np.array([best[0], best[1], top[2]])

    def _pull_direction(self, drawer_id: str) -> np.ndarray:
        """The way a drawer slides out, in the world."""
        return self.scene.body_pose(drawer_id)[1] @ np.asarray(self._kind(drawer_id).part(Drawer).pull)

    def _pulled(self, drawer_id: str) -> float:
        """How far the drawer is out of where it stands shut (its place's recorded position)."""
        shut = np.asarray(self.spec.object(drawer_id).pos)
        return float((self.scene.object_pos(drawer_id) - shut) @ self._pull_direction(drawer_id))

    def pull_open(self, drawer_id: str, travel: float = DRAWER_PULL) -> None:
        """Take the drawer's handle bar from the front, the hand level and its fingers closing up and
        down on the bar, and pull it `travel` out along its slide; let go and back off, up and out.
        Nothing where it is out that far already (LIBERO-10's drawer starts open)."""
        if self._pulled(drawer_id) >= travel:
            return
        drawer = self._kind(drawer_id).part(Drawer)
        site, rot = self.scene.object_pos(drawer_id), self.scene.body_pose(drawer_id)[1]
        handle = site + rot @ np.asarray(drawer.handle)
        out = self._pull_direction(drawer_id)
        self.move_to([*self.scene.ee_pos()[:2], max(self.scene.ee_pos()[2], self.clearance())])
        self.facing = facing(tuple(-out[:2]), drawer.roll)
        self.move_to(handle + HANDLE_REACH * out)
        self._settle(self.q)
        self.move_linear(handle, speed=0.15)
        self.close()
        self.move_linear(handle + travel * out, speed=0.15)
        self.open()
        self.move_linear(self.scene.ee_pos() + 0.04 * out + [0.0, 0.0, 0.06], speed=0.2)
        self.facing = None  # the next move turns the hand down again

    def put_in(self, object_id: str, place_id: str) -> None:
        """Put the object inside a place: a drawer opened part way first (where it is not open that far
        already), the microwave's inside let down at its front and pushed in, a narrow compartment
        stood in leaning."""
        if self._kind(place_id).slot is not None:
            self._lean_in(object_id, place_id)
            return
        if self._kind(place_id).inside is not None:
            self._push_inside(object_id, place_id)
            return
        self.pull_open(place_id, DRAWER_SLOT)
        self.grasp(object_id, onto=place_id)
        self.lift(DRAWER_LIFT)
        self.place(place_id)

    def _push_inside(self, object_id: str, place_id: str) -> None:
        """Carry the object (by its handle, from above) over the inside's floor at its front, let it
        go there and back out; then push it in to the place with the closed fingers, the hand
        pointing in SHUT_PITCH below level (held from above deeper in, the hand meets the box's top)."""
        inside, kind = self._kind(place_id).part(Inside), self._kind(object_id)
        site, rot = self.scene.object_pos(place_id), self.scene.body_pose(place_id)[1]
        out = rot @ np.asarray(inside.out)
        floor = site[2] + inside.floor
        self.grasp(object_id)
        self.lift(INSIDE_LIFT)
        hand = self.scene.ee_pos() - self.scene.object_pos(object_id)
        let_go = site + inside.front * out
        let_go = np.array([let_go[0], let_go[1], floor + kind.bottom + INSIDE_DROP]) + hand
        self.move_to(let_go + INSIDE_APPROACH * out)  # before the opening, then straight in over the floor's lip
        self.move_linear(let_go, speed=0.1)
        self.open()
        self.move_linear(self.scene.ee_pos() + INSIDE_BACK * out, speed=0.1)
        self.move_linear(self.scene.ee_pos() + [0.0, 0.0, INSIDE_RISE], speed=0.1)
        pos, reach = self.scene.object_pos(object_id), max(kind.size[:2]) / 2  # how far it reaches out of its origin
        level = facing(tuple(-out[:2]), np.pi / 2)
        frame = turned(level[:, 0], SHUT_PITCH) @ level

        def low(at: np.ndarray) -> np.ndarray:  # the fingers at the push's height over the floor
            return np.array([at[0], at[1], floor + PUSH_LOW])

        start, end = low(pos + (reach + PUSH_GAP) * out), low(site + (reach - PUSH_PAST) * out)  # its side, now and in place
        self.gripper = CLOSED
        self.facing = frame
        self.move_to(start + [0.0, 0.0, INSIDE_RISE])
        self.move_linear(start, speed=0.1)
        self.move_linear(end, speed=PUSH_SPEED)
        self.move_linear(self.scene.ee_pos() + 2 * INSIDE_BACK * out, speed=0.1)
        self.move_linear(self.scene.ee_pos() + [0.0, 0.0, 2 * INSIDE_RISE], speed=0.1)
        self.facing = None

    def _lean_in(self, object_id: str, place_id: str) -> None:
        """Stand the object in a narrow compartment leaning on its wall (core/furniture.py `Slot`): taken
        from above, the fingers turned to close across the compartment, carried over where its foot goes
        with its bottom LEAN_OVER over the walls, tilted `lean` toward the wall it will rest on, let down to
        LEAN_DROP over the floor and let go; the hand then rises out, upright again."""
        slot, kind = self._kind(place_id).part(Slot), self._kind(object_id)
        site, rot = self.scene.object_pos(place_id), self.scene.body_pose(place_id)[1]
        toward = rot @ np.asarray(slot.toward)
        foot = site - slot.foot * toward
        foot[2] = site[2] + slot.floor + kind.bottom + LEAN_DROP  # where its origin is let go
        over = site[2] + slot.rim + LEAN_OVER + kind.bottom  # its origin's height, its bottom LEAN_OVER over the walls
        self.grasp(object_id)
        self.lift(over - self.scene.object_pos(object_id)[2])
        yaw = grasp_yaw(float(np.arctan2(toward[1], toward[0])))  # the fingers, and the thing's narrow side, across it
        self.move_to(self.scene.ee_pos(), yaw)
        hand = self.scene.ee_pos() - self.scene.object_pos(object_id)  # the grip from the thing's origin, upright
        high = np.array([foot[0], foot[1], over])
        self.move_to(high + hand, yaw)
        pivot, upright = np.cross([0.0, 0.0, 1.0], toward), yaw_matrix(yaw) @ DOWN
        for k in range(1, LEAN_STEPS + 1):  # tilted over the compartment a step at a time
            turn = turned(pivot / np.linalg.norm(pivot), slot.lean * k / LEAN_STEPS)
            self.facing = turn @ upright
            self.move_to(high + turn @ hand)
        self.move_linear(foot + turn @ hand, speed=0.05)
        self.open()
        self.hold(LEAN_SETTLE)
        self.move_linear(self.scene.ee_pos() + turn @ [0.0, 0.0, 0.1], speed=0.1)
        self.facing = None

    def shut(self, place_id: str) -> None:
        """Shut a drawer (pushed in) or a door (swung round its hinge)."""
        if self._kind(place_id).door is not None:
            self._swing_shut(place_id)
        else:
            self.push_closed(place_id)

    def _swing_shut(self, door_id: str) -> None:
        """Swing an open door shut: the closed fingers, the hand pointing down and turned across the
        door, come down clear of its outer face at its place (`Spot.offset` from the hinge) and press
        it round the hinge in DOOR_STEPS to DOOR_PAST beyond where it stands shut; then back off and rise."""
        hinge, rot = self.scene.body_pose(door_id)
        along = np.asarray(self._kind(door_id).part(Spot).offset)
        shut = np.subtract(self.spec.object(door_id).pos, hinge)
        now = float(np.arctan2(rot[1, 0], rot[0, 0]))
        closed = float(np.arctan2(shut[1], shut[0]) - np.arctan2(along[1], along[0]))
        closed = now + float(np.arctan2(np.sin(closed - now), np.cos(closed - now)))  # the shut angle nearest the door's

        def pressing(angle: float, out: float) -> np.ndarray:
            return hinge + yaw_matrix(angle) @ (along + [0.0, -out, 0.0])

        self.gripper = CLOSED
        start = pressing(now, DOOR_PRESS + DOOR_CLEAR)
        self.move_to([*start[:2], max(self.scene.ee_pos()[2], self.clearance())], yaw=now + np.pi / 2)
        self.move_linear(start, speed=0.1)
        for angle in np.linspace(now, closed + np.sign(closed - now) * DOOR_PAST, DOOR_STEPS):
            self.move_to(pressing(float(angle), DOOR_PRESS), yaw=float(angle) + np.pi / 2)
        self.move_linear(self.scene.ee_pos() + DOOR_CLEAR * (yaw_matrix(closed) @ [0.0, -1.0, 0.0]), speed=0.1)
        self.move_linear(self.scene.ee_pos() + [0.0, 0.0, 0.1], speed=0.1)

    def push_closed(self, drawer_id: str) -> None:
        """Push an open drawer shut: the closed fingers side by side, the hand pointing into the
        cabinet SHUT_PITCH below level (pointing down, the hand would meet the cabinet over the
        drawer; level, the wrist behind it the wine rack), from FRONT_GAP before where its front is
        pressed (`Drawer.press`, beside its handle bar) in along its slide to SHUT_PAST beyond
        where it stands shut; then back off, out and up. The hand comes down to it in front of the
        drawer, clear of its front."""
        out = self._pull_direction(drawer_id)
        rot = self.scene.body_pose(drawer_id)[1]
        press = self.scene.object_pos(drawer_id) + rot @ np.asarray(self._kind(drawer_id).part(Drawer).press)
        level = facing(tuple(-out[:2]), np.pi / 2)
        frame = turned(level[:, 0], SHUT_PITCH) @ level
        start = press - FINGER_TIP * frame[:, 2] + FRONT_GAP * out
        self.gripper = CLOSED
        self.move_to([*self.scene.ee_pos()[:2], max(self.scene.ee_pos()[2], self.clearance())])
        self.facing = frame
        self.move_to(start + [0.0, 0.0, SHUT_BACK])
        self.move_linear(start)
        self.move_linear(start - (self._pulled(drawer_id) + FRONT_GAP + SHUT_PAST) * out, speed=SHUT_SPEED)
        self.move_linear(self.scene.ee_pos() + SHUT_BACK * out, speed=0.2)
        self.move_linear(self.scene.ee_pos() + [0.0, 0.0, SHUT_BACK], speed=0.2)
        self.facing = None
