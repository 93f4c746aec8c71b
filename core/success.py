"""Success predicates, one per motor program (core/programs.py names which): false at the initial
state by construction.

Every measure is relative to where the objects started, so a scene whose target starts high
cannot score, and a do-nothing rollout achieves nothing. Plain data in, no simulator: the exam
scorer judges logged rollouts with the same predicates.

* pick  — the target rose by at least `lift_margin` and no other object did.
* push  — the target slid at least `push_margin` along the push direction, never left the table
          by more than 2 cm, and no object was lifted.
* place — the carried object (`params.object`) rests inside the target destination's footprint
          and is not held above it; the destination itself stayed put. Onto a region of the table
          (a place with a `contain` box: LIBERO-10's right of the plate), LIBERO's `On` of it.
* pick_place — the target ends inside the container `params.destination`: its origin in the
          container's `contain` box (LIBERO's `In` predicate, as LIBERO-Object's goals use it),
          turned as LIBERO turns it where the basket's orientation is known (`_in_box`).
* pick_place_on — the target ends on `params.destination`: LIBERO's `On` (as LIBERO-Spatial's
          goals use it): its origin within 3 cm of the destination's (horizontally) and not below
          it, and resting on it (its bottom at most 2 cm above the destination's top: positions
          stand in for LIBERO's contact test).
* open  — the target (a drawer, its place inside it) slid out at least its `Drawer.open_travel`:
          LIBERO's `Open` of a cabinet drawer, its joint past -0.14 m (LIBERO's drawers all start closed).
* close — the target (a drawer, its place inside it), which started open (its `Drawer.open_travel`
          out of where it stands shut, its recorded place), ends in past where it stands shut:
          LIBERO's `Close` of a cabinet drawer, its joint above 0 (LIBERO-10's drawer starts open).
* turn_on — the target (a point on the stove's knob) was carried along an arc of at least its
          `Knob.turn_on` radians about the knob's axis: LIBERO's `TurnOn` of the stove, its knob's
          joint at 0.5 rad or more (it starts at 0 and turns one way only).
* place_in — the carried object (`params.object`) ends in the target place's `contain` box, its
          floor lowered 1 cm: LIBERO's `In(object, <drawer region>)`.
* push_to — the object (`params.object`) ends over the target region (its `contain` box): LIBERO's
          `On(object, <table region>)`, as "push the plate to the front of the stove" asks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core import worlds
from core.furniture import Drawer, Knob, Shelf, Spot
from core.rotations import quat_matrix, unit, yaw_matrix, yaw_quat
from core.spec import EpisodeSpec

PUSH_DIRECTION = (1.0, 0.0)  # away from the robot, along +x
PUSH_MARGIN = 0.05
SLIDE_MAX_RISE = 0.02
PLACE_MAX_HOVER = 0.02  # carried object's bottom at most this far above the destination's top
CONTAIN_FLOOR = 0.01  # LIBERO's `in_box` lowers the container box's floor by this much
ON_RADIUS = 0.03  # LIBERO's `check_ontop`: origins this close horizontally


@dataclass(frozen=True)
class Outcome:
    """Where every object started and ended, where the end effector finished, and how the
    containers that move (a basket) ended turned, where that was recorded."""

    start: dict[str, tuple[float, float, float]]
    end: dict[str, tuple[float, float, float]]
    ee: tuple[float, float, float]
    turns: dict[str, tuple[float, ...]] = field(default_factory=dict)  # object -> its end orientation (w, x, y, z)

    def rise(self, object_id: str) -> float:
        return self.end[object_id][2] - self.start[object_id][2]

    def shift(self, object_id: str) -> np.ndarray:
        """Horizontal displacement (dx, dy)."""
        return np.subtract(self.end[object_id][:2], self.start[object_id][:2])


def lifted(spec: EpisodeSpec, outcome: Outcome, target: str) -> bool:
    margin = spec.task.lift_margin
    return outcome.rise(target) >= margin and all(outcome.rise(k) < margin for k in outcome.end if k != target)


def pushed(spec: EpisodeSpec, outcome: Outcome, target: str) -> bool:
    along = float(outcome.shift(target) @ np.asarray(PUSH_DIRECTION))
    no_lift = all(outcome.rise(k) < SLIDE_MAX_RISE for k in outcome.end)
    return along >= PUSH_MARGIN and no_lift


def placed(spec: EpisodeSpec, outcome: Outcome, destination: str) -> bool:
    carried = spec.task.params["object"]
    dest = worlds.kind(spec.object(destination).kind, spec.setup.world)
    if dest.shelf is not None:  # what lies on a sloping shelf is judged as LIBERO judges it
        return _on_tilted(spec, outcome, carried, destination)
    if dest.is_site and dest.contain is not None:  # a region of the table: LIBERO's `On` of it (site_object.py `under`)
        return _in_box(spec, outcome, carried, destination, 0.0)
    obj = worlds.kind(spec.object(carried).kind, spec.setup.world)
    d_end, o_end = np.asarray(outcome.end[destination]), np.asarray(outcome.end[carried])
    inside = bool(np.all(np.abs(o_end[:2] - d_end[:2]) <= dest.inner))
    dest_top = d_end[2] - dest.bottom + dest.height
    resting = (o_end[2] - obj.bottom) <= dest_top + PLACE_MAX_HOVER
    dest_still = float(np.linalg.norm(outcome.shift(destination))) < 0.03
    return inside and resting and dest_still


def _on_tilted(spec: EpisodeSpec, outcome: Outcome, thing: str, place: str) -> bool:
    """LIBERO's `On(thing, <site>)` of a tilted site (the wine rack's shelf; envs/objects/site_object.py
    `under`): `thing`'s origin within the site's box and up to `Shelf.rise` over its face, the
    offset multiplied by the site's matrix itself, as LIBERO multiplies it (the fixture stands
    where its world puts it)."""
    kind = worlds.kind(spec.object(place).kind, spec.setup.world)
    shelf, site = kind.part(Shelf), kind.part(Spot).site
    yaw = next(p.yaw for p in worlds.world(spec.setup.world).fixtures if site.startswith(f"{p.name}_"))
    return shelf.holds(yaw_matrix(yaw) @ shelf.turn() @ np.subtract(outcome.end[thing], outcome.end[place]))


def _in_box(spec: EpisodeSpec, outcome: Outcome, thing: str, container: str, floor: float) -> bool:
    """Whether `thing`'s origin ends in `container`'s `contain` box, its floor lowered by `floor`.
    A container whose end orientation is known (`Outcome.turns`) has its box where LIBERO's `in_box`
    puts its region site's: the offset turned with it, the extents |R half| along the world's axes
    (R the site's orientation, `Kind.contain_quat` turned as the container turned)."""
    placed = spec.object(container)
    kind = worlds.kind(placed.kind, spec.setup.world)
    if kind.contain is None:
        raise ValueError(f"{kind.name} is not a container (no contain box)")
    offset, half = (np.asarray(v) for v in kind.contain)
    if container in outcome.turns:
        turn = quat_matrix(unit(outcome.turns[container])) @ quat_matrix(unit(yaw_quat(placed.yaw, kind.quat))).T
        offset, half = turn @ offset, np.abs(turn @ quat_matrix(unit(yaw_quat(placed.yaw, kind.contain_quat))) @ half)
    d = np.asarray(outcome.end[thing]) - (np.asarray(outcome.end[container]) + offset)
    return bool(np.all(np.abs(d[:2]) < half[:2]) and -half[2] - floor < d[2] < half[2])


def contained(spec: EpisodeSpec, outcome: Outcome, target: str) -> bool:
    """LIBERO's `In(target, <container>_contain_region)`: the target's origin inside the box,
    whose floor LIBERO lowers by 1 cm (envs/objects/site_object.py `in_box`)."""
    return _in_box(spec, outcome, target, spec.task.params["destination"], CONTAIN_FLOOR)


def put_in(spec: EpisodeSpec, outcome: Outcome, place: str) -> bool:
    """LIBERO's `In(<carried object>, <place>)`, the place the target (a drawer's region)."""
    return _in_box(spec, outcome, spec.task.params["object"], place, CONTAIN_FLOOR)


def pushed_to(spec: EpisodeSpec, outcome: Outcome, region: str) -> bool:
    """LIBERO's `On(<object>, <table region>)` (site_object.py `under`): the object's origin over the region."""
    return _in_box(spec, outcome, spec.task.params["object"], region, 0.0)


def opened(spec: EpisodeSpec, outcome: Outcome, drawer: str) -> bool:
    return worlds.kind(spec.object(drawer).kind, spec.setup.world).part(Drawer).opened(outcome.start[drawer], outcome.end[drawer])


def closed(spec: EpisodeSpec, outcome: Outcome, place: str) -> bool:
    """LIBERO's `Close` of a drawer's region or of a door (the microwave's): shut from open, the
    place recorded where it stands shut."""
    kind = worlds.kind(spec.object(place).kind, spec.setup.world)
    start, end, shut = outcome.start[place], outcome.end[place], spec.object(place).pos
    if kind.door is not None:
        return kind.door.closed(start, end, shut, float(np.linalg.norm(kind.part(Spot).offset)))
    return kind.part(Drawer).closed(start, end, shut)


def turned_on(spec: EpisodeSpec, outcome: Outcome, knob: str) -> bool:
    kind = worlds.kind(spec.object(knob).kind, spec.setup.world)
    radius = float(np.hypot(*kind.part(Spot).offset[:2]))
    return kind.part(Knob).on(outcome.start[knob], outcome.end[knob], radius)


def on(spec: EpisodeSpec, outcome: Outcome, target: str) -> bool:
    """LIBERO's `On(target, destination)` (envs/object_states `check_ontop`), from positions."""
    destination = spec.task.params["destination"]
    dest = worlds.kind(spec.object(destination).kind, spec.setup.world)
    carried = worlds.kind(spec.object(target).kind, spec.setup.world)
    t_end, d_end = np.asarray(outcome.end[target]), np.asarray(outcome.end[destination])
    near = float(np.hypot(*(t_end[:2] - d_end[:2]))) < ON_RADIUS
    resting = t_end[2] - carried.bottom <= d_end[2] - dest.bottom + dest.height + PLACE_MAX_HOVER
    return near and t_end[2] >= d_end[2] and resting
