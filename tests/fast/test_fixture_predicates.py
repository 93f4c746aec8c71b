"""LIBERO-Goal's motions judged from positions alone (core/success.py), at the edges LIBERO's own
predicates draw: a drawer is open past 14 cm, the stove on from a knob turn of 0.5 rad, a thing in a
drawer when its origin is in the region's box (floor lowered 1 cm), the plate in front of the stove
when its origin is over that region, the bottle on the rack when its origin is in the tilted box
over the rack's sloping shelf."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from core import libero
from core.profiles import LIBERO
from core.programs import achieved, named
from core.spec import EpisodeSpec, SceneObject, Setup, TaskSpec
from core.success import Outcome

OPEN_TRAVEL = libero.KINDS["top_drawer"].drawer.open_travel  # LIBERO's thresholds, as the pieces own them
TURN_ON = libero.KINDS["stove_knob"].knob.turn_on
DRAWER = (0.0267, -0.2513, 1.0906)  # the top drawer's region site, closed
KNOB_AXIS = np.array([-0.41, 0.21, 0.905])
FRONT = (-0.05, 0.21, 0.895)  # the table's region in front of the stove
BOWL, PLATE = (-0.09, 0.0, 0.898), (0.05, -0.02, 0.903)
RACK = np.array([-0.26, -0.18003, 1.13745])  # the rack's top region's site, the rack turned half about
# up the rack's shelf, and out of it, in the world: the site's z and -y (turned RACK_TILT about x, then half about z)
UP_SHELF = np.array([0.0, np.sin(libero.RACK_TILT), np.cos(libero.RACK_TILT)])
OUT_OF_SHELF = np.array([0.0, np.cos(libero.RACK_TILT), -np.sin(libero.RACK_TILT)])


def _spec(program: str, target: str, moved: str | None = None) -> EpisodeSpec:
    objects = (
        SceneObject("bowl", "akita_black_bowl", "bowl", 0, BOWL),
        SceneObject("plate", "plate", "plate", 1, PLATE),
        SceneObject("drawer", "top_drawer", "top drawer", 8, DRAWER),
        SceneObject("knob", "stove_knob", "stove knob", 10, tuple(KNOB_AXIS + [-libero.KNOB_RADIUS, 0.0, 0.0])),
        SceneObject("front", "stove_front", "front of the stove", 11, FRONT),
        SceneObject("bottle", "wine_bottle", "wine bottle", 3, (0.05, 0.14, 0.899)),
        SceneObject("rack", "wine_rack_top", "rack", 12, tuple(RACK)),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_goal")
    task = TaskSpec(program=program, params={"object": moved} if moved else {})
    return EpisodeSpec("libero_goal", 0, 0, objects, target, "", "", (), (), task, setup)


def _judge(spec: EpisodeSpec, moves: dict[str, tuple[float, float, float]]) -> bool:
    start = {o.id: o.pos for o in spec.objects}
    return bool(achieved(spec, Outcome(start, {**start, **moves}, (0.0, 0.0, 1.2)), spec.target, spec.task.program))


@pytest.mark.parametrize(("out", "is_open"), [(OPEN_TRAVEL - 0.005, False), (OPEN_TRAVEL + 0.005, True), (0.16, True)])
def test_a_drawer_is_open_past_fourteen_centimetres(out: float, is_open: bool) -> None:
    spec = _spec("open", "drawer")
    assert _judge(spec, {"drawer": (DRAWER[0], DRAWER[1] + out, DRAWER[2])}) is is_open
    assert not _judge(spec, {"knob": (0.0, 0.0, 0.0)}), "nothing moved at the drawer: not open"


@pytest.mark.parametrize(("turn", "on"), [(TURN_ON - 0.05, False), (TURN_ON + 0.05, True), (2.0, True)])
def test_the_stove_is_on_from_half_a_radian_of_the_knob(turn: float, on: bool) -> None:
    """The point standing for the knob, turned `turn` about the knob's axis."""
    spec = _spec("turn_on", "knob")
    c, s = np.cos(turn), np.sin(turn)
    arm = np.array(spec.object("knob").pos) - KNOB_AXIS
    turned = KNOB_AXIS + [c * arm[0] - s * arm[1], s * arm[0] + c * arm[1], arm[2]]
    assert _judge(spec, {"knob": tuple(turned)}) is on


@pytest.mark.parametrize(
    ("offset", "inside"),
    [
        ((0.0, 0.0, -0.025), True),  # on the drawer's floor
        ((0.0, 0.07, -0.025), True),
        ((0.0, 0.08, -0.025), False),  # past the region's half width (7.56 cm)
        ((0.0, 0.0, -0.045), False),  # below its box, the floor lowered 1 cm
    ],
)
def test_a_thing_is_in_a_drawer_when_its_origin_is_in_the_regions_box(offset: tuple[float, float, float], inside: bool) -> None:
    spec = _spec("place_in", "drawer", moved="bowl")
    opened = np.add(DRAWER, (0.0, 0.13, 0.0))
    assert _judge(spec, {"drawer": tuple(opened), "bowl": tuple(opened + offset)}) is inside


@pytest.mark.parametrize(
    ("where", "over"), [((-0.05, 0.21), True), ((-0.02, 0.24), True), ((-0.05, 0.26), False), ((0.0, 0.21), False)]
)
def test_the_plate_is_in_front_of_the_stove_when_over_that_region(where: tuple[float, float], over: bool) -> None:
    spec = _spec("push_to", "front", moved="plate")
    assert _judge(spec, {"plate": (*where, PLATE[2])}) is over
    lifted = _judge(spec, {"plate": (*where, FRONT[2] + 0.12)})
    assert not lifted, "held 12 cm over the region is not on it"


@pytest.mark.parametrize(
    ("up", "out", "along", "on"),
    [
        (0.04, 0.0, 0.0, True),  # laid on the shelf
        (0.04, 0.015, 0.09, True),
        (0.001, 0.0, 0.0, False),  # not past the site's box (0.25 cm)
        (0.11, 0.0, 0.0, False),  # more than 10 cm up the slope
        (0.04, 0.03, 0.0, False),  # 3 cm off the shelf, past the box's 2.2
        (0.04, 0.0, 0.11, False),  # past the shelf's end
    ],
)
def test_the_bottle_is_on_the_rack_when_its_origin_is_in_the_tilted_box(up: float, out: float, along: float, on: bool) -> None:
    spec = _spec("place", "rack", moved="bottle")
    assert _judge(spec, {"bottle": tuple(RACK + up * UP_SHELF + out * OUT_OF_SHELF + [along, 0.0, 0.0])}) is on


def test_liberos_goal_of_each_motion_names_liberos_own_things() -> None:
    kinds = {k: libero.KINDS[k] for k in ("top_drawer", "stove_knob", "stove_front")}
    assert libero.goal(named("open").libero, libero.place_name(kinds["top_drawer"], "wooden_cabinet_1_top_region")) == [
        "Open",
        "wooden_cabinet_1_top_region",
    ]
    assert libero.goal(named("turn_on").libero, libero.place_name(kinds["stove_knob"], kinds["stove_knob"].anchor)) == [
        "Turnon",
        "flat_stove_1",
    ]
    assert libero.goal(named("push_to").libero, libero.place_name(kinds["stove_front"], "x"), "plate_1") == [
        "On",
        "plate_1",
        "main_table_stove_front_region",
    ]
    assert replace(kinds["stove_knob"]).anchor == f"flat_stove_1_button@0.0,{libero.KNOB_RADIUS},0.0"
