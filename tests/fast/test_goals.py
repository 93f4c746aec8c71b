"""A task of more goals than one (LIBERO-10's): one spec, its goals after the first in
`task.params["then"]`, each judged by its own program's predicate; the task done when every goal is.
Positions alone, no simulator."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from core import programs, worlds
from core.exam import Exam, trial_rows
from core.profiles import LIBERO
from core.spec import THEN, Counterfactual, EpisodeSpec, SceneObject, Setup, SpecError, TaskSpec
from core.success import CONTAIN_FLOOR, Outcome
from eval.scoring.score import score
from eval.sims.libero import RowStart, predicate

BASKET = (0.0, 0.27, 0.432)  # LIVING_ROOM_SCENE1's basket, at rest
SOUP, CHEESE = (-0.1, -0.15, 0.475), (0.08, -0.19, 0.445)
IN_BASKET = (0.0, 0.27, 0.47)  # a grocery's origin inside the basket's box
PUDDING = (-0.05, 0.1, 0.45)
RIGHT_OF_PLATE = (0.15, 0.1, 0.41)  # the table's region right of the plate (its site)
SAUCE = (0.1, -0.05, 0.46)


def _spec() -> EpisodeSpec:
    """LIVING_ROOM_SCENE1: both the alphabet soup and the cream cheese in the basket."""
    objects = (
        SceneObject("alphabet_soup_1", "alphabet_soup", "alphabet soup", 0, SOUP),
        SceneObject("cream_cheese_1", "cream_cheese", "cream cheese", 1, CHEESE),
        SceneObject("basket_1", "basket", "basket", 2, BASKET),
    )
    then = [{"program": "pick_place", "target": "cream_cheese_1", "params": {"destination": "basket_1"}}]
    task = TaskSpec("pick_place", params={"destination": "basket_1", THEN: then})
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_living_room")
    return EpisodeSpec("libero_10", 0, 0, objects, "alphabet_soup_1", "", "", (), (), task, setup)


def test_the_goals_are_the_first_then_each_listed() -> None:
    spec = _spec()
    first, second = spec.goals()
    into = {"destination": "basket_1"}
    assert (first.target, first.task.program, first.task.params) == ("alphabet_soup_1", "pick_place", into)
    assert (second.target, second.task.program, second.task.params) == ("cream_cheese_1", "pick_place", into)
    assert second.objects == spec.objects and second.setup == spec.setup
    assert first.goals() == (first,), "a spec of one goal is its own only goal"
    assert EpisodeSpec.from_json(spec.to_json()) == spec, "the goals round-trip through the spec's JSON"


@pytest.mark.parametrize(
    ("moved", "each"),
    [({}, (False, False)), ({"alphabet_soup_1": IN_BASKET}, (True, False)),
     ({"cream_cheese_1": IN_BASKET}, (False, True)), ({"alphabet_soup_1": IN_BASKET, "cream_cheese_1": IN_BASKET}, (True, True))],
)  # fmt: skip
def test_each_goal_is_judged_on_its_own_and_the_task_when_all_are(moved: dict, each: tuple[bool, bool]) -> None:
    spec = _spec()
    start = {o.id: o.pos for o in spec.objects}
    outcome = Outcome(start, {**start, **moved}, (0.0, 0.0, 1.0))
    assert programs.each(spec, outcome) == each
    assert programs.succeeded(spec, outcome) is all(each)


@pytest.mark.parametrize(
    ("end", "on"),
    [((0.15, 0.1, 0.45), True), ((0.19, 0.14, 0.45), True), ((0.21, 0.1, 0.45), False), ((0.15, 0.1, 0.53), False)],
)
def test_a_thing_is_right_of_the_plate_when_its_origin_is_over_the_region(end: tuple, on: bool) -> None:
    """LIBERO's `On(x, living_room_table_plate_right_region)`: x's origin over the region's 10 cm
    square, from 2 mm to 10.7 cm above its site."""
    objects = (
        SceneObject("chocolate_pudding_1", "chocolate_pudding", "chocolate pudding", 0, PUDDING),
        SceneObject("plate_right", "plate_right", "right of the plate", 1, RIGHT_OF_PLATE),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_living_room")
    task = TaskSpec("place", params={"object": "chocolate_pudding_1"})
    spec = EpisodeSpec("libero_10", 0, 0, objects, "plate_right", "", "", (), (), task, setup)
    start = {o.id: o.pos for o in objects}
    assert programs.succeeded(spec, Outcome(start, {**start, "chocolate_pudding_1": end}, (0.0, 0.0, 1.0))) is on


def test_liberos_goal_for_a_region_of_the_table_is_on_it() -> None:
    """What `sim=libero` asks LIBERO's `check_success` for a thing brought to a region of the table
    (a place with a `contain` box): `On` the region, as LIVING_ROOM_SCENE6's BDDL file says; into a
    container: `In` its contain region."""
    objects = (
        SceneObject("pudding", "chocolate_pudding", "chocolate pudding", 0, PUDDING),
        SceneObject("region", "plate_right", "right of the plate", 1, RIGHT_OF_PLATE),
        SceneObject("basket", "basket", "basket", 2, BASKET),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_living_room")
    spec = EpisodeSpec(
        "libero_10", 0, 0, objects, "region", "", "", (), (), TaskSpec("place", params={"object": "pudding"}), setup
    )
    start = RowStart(
        "k", {}, {}, None, ("pudding", "basket", "region"), ("chocolate_pudding_1", "basket_1"),
        ("living_room_table_plate_right_region",),
    )  # fmt: skip
    assert predicate(spec, start, "region", "place") == ["On", "chocolate_pudding_1", "living_room_table_plate_right_region"]
    assert predicate(spec, start, "basket", "place") == ["In", "chocolate_pudding_1", "basket_1_contain_region"]


SHUT = (0.00328, 0.31128, 0.952)  # KITCHEN_SCENE4's bottom drawer's site, the drawer shut
OPEN = (0.00328, 0.16528, 0.952)  # pulled 14.6 cm out, as LIBERO's initial states open it


def _drawer_spec(shut: tuple = SHUT) -> EpisodeSpec:
    """KITCHEN_SCENE4: the black bowl in the bottom drawer, then the drawer shut."""
    objects = (
        SceneObject("akita_black_bowl_1", "akita_black_bowl", "black bowl", 0, (0.03, -0.06, 0.898)),
        SceneObject("white_bottom_drawer", "white_bottom_drawer", "bottom drawer", 1, shut),
    )
    then = [{"program": "close", "target": "white_bottom_drawer", "params": {}}]
    task = TaskSpec("place_in", params={"object": "akita_black_bowl_1", THEN: then})
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_kitchen_scene4")
    return EpisodeSpec("libero_10", 0, 0, objects, "white_bottom_drawer", "", "", (), (), task, setup)


@pytest.mark.parametrize(
    ("start", "end", "closed"),
    [(OPEN, (0.00328, 0.31328, 0.952), True),  # pushed 2 mm past shut (LIBERO's joint at +0.002)
     (OPEN, (0.00328, 0.31028, 0.952), False),  # 1 mm short of shut: LIBERO's joint at -0.001
     (OPEN, OPEN, False),  # left open
     ((0.00328, 0.30128, 0.952), (0.00328, 0.31328, 0.952), False)],  # it was not open to begin with
)  # fmt: skip
def test_a_drawer_is_closed_when_pushed_in_past_where_it_stands_shut(start: tuple, end: tuple, closed: bool) -> None:
    """LIBERO's `Close(<drawer region>)`: its slide's joint above 0, the drawer pushed in past where it
    stands shut (the spec records a drawer's place where it stands shut); only a drawer that started open."""
    spec = _drawer_spec()
    begin = {o.id: o.pos for o in spec.objects} | {"white_bottom_drawer": start}
    outcome = Outcome(begin, {**begin, "white_bottom_drawer": end}, (0.0, 0.0, 1.0))
    assert programs.each(spec, outcome)[1] is closed


def test_liberos_goal_for_closing_a_drawer_is_close_of_its_region() -> None:
    """What `sim=libero` asks LIBERO's `check_success` for a drawer shut, and for a thing put in it:
    KITCHEN_SCENE4's BDDL words."""
    spec = _drawer_spec()
    start = RowStart("k", {}, {}, None, ("akita_black_bowl_1", "white_bottom_drawer"), ("akita_black_bowl_1",),
                     ("white_cabinet_1_bottom_region",))  # fmt: skip
    close, put_in = spec.goals()[1], spec.goals()[0]
    assert predicate(close, start, "white_bottom_drawer", "close") == ["Close", "white_cabinet_1_bottom_region"]
    assert predicate(put_in, start, "white_bottom_drawer", "place_in") == [
        "In", "akita_black_bowl_1", "white_cabinet_1_bottom_region"
    ]  # fmt: skip


def _swapped() -> EpisodeSpec:
    """LIVING_ROOM_SCENE1 with the tomato sauce beside, and the swap of its second name: "put both
    the alphabet soup and the tomato sauce in the basket"."""
    spec = _spec()
    sauce = SceneObject("tomato_sauce_1", "tomato_sauce", "tomato sauce", 3, SAUCE)
    cf = Counterfactual("put both the alphabet soup and the tomato sauce in the basket", "tomato_sauce_1",
                        ("cream cheese", "tomato sauce"), goal=1)  # fmt: skip
    instruction = "put both the alphabet soup and the cream cheese box in the basket"
    return replace(spec, objects=(*spec.objects, sauce), instruction=instruction, counterfactuals=(cf,))


@pytest.mark.parametrize(
    ("moved", "task", "swap"),
    [({"alphabet_soup_1": IN_BASKET, "cream_cheese_1": IN_BASKET}, True, False),
     ({"alphabet_soup_1": IN_BASKET, "tomato_sauce_1": IN_BASKET}, False, True),
     ({"tomato_sauce_1": IN_BASKET}, False, False)],
)  # fmt: skip
def test_a_swap_of_the_second_name_asks_the_first_goal_as_it_was(moved: dict, task: bool, swap: bool) -> None:
    """A counterfactual renames one goal of the two (`goal`); it is achieved when that goal is done of
    the newly named object and the other goal as first asked."""
    spec = _swapped()
    start = {o.id: o.pos for o in spec.objects}
    outcome = Outcome(start, {**start, **moved}, (0.0, 0.0, 1.0))
    assert programs.achieved(spec, outcome, spec.target, spec.task.program) is task
    assert programs.achieved(spec, outcome, *spec.choice(spec.counterfactuals[0]), spec.counterfactuals[0].goal) is swap


def test_a_counterfactuals_goal_is_written_only_where_not_the_first() -> None:
    """Specs whose counterfactuals rename the first goal keep the JSON (and hash) they had before
    `goal`; one naming a goal the task does not have is refused."""
    spec = _swapped()
    assert json.loads(spec.to_json())["counterfactuals"][0]["goal"] == 1
    assert EpisodeSpec.from_json(spec.to_json()) == spec
    first = replace(spec, counterfactuals=(replace(spec.counterfactuals[0], goal=0),))
    assert "goal" not in json.loads(first.to_json())["counterfactuals"][0]
    beyond = json.loads(spec.to_json())
    beyond["counterfactuals"][0]["goal"] = 2
    with pytest.raises(SpecError, match="goal"):
        EpisodeSpec.from_dict(beyond)


def test_the_partial_face_counts_each_goal_of_the_task_rows() -> None:
    """Scored from logs: a task row that put only the soup in did its first goal and not the task; a
    swap row that put the soup and the sauce in obeyed the swap of the second name."""
    spec = _swapped()
    rows = trial_rows(0, spec, {}, [], 10, [0.0, 0.0, 1.0])
    for i, r in enumerate(rows):
        r["row"] = i
    exam = Exam(Path("."), {"referent": "libero_10", "trials": 1, "seed": 0}, pd.DataFrame(rows))
    ends = {"task": {"alphabet_soup_1": IN_BASKET}, "swap": {"alphabet_soup_1": IN_BASKET, "tomato_sauce_1": IN_BASKET}}
    logs = []
    for r in rows:
        start = {o.id: o.pos for o in spec.objects}
        end = {**start, **ends.get(r["face"], {})}
        hand = end.get(r["target"], (0.0, 0.0, 1.0)) if r["face"] in ends else (0.0, 0.0, 1.0)
        objects = json.dumps({k: [list(start[k]), list(end[k])] for k in start})
        logs.append({"row": r["row"], "ee": [[0.0, 0.0, 1.0], list(np.add(hand, (0.0, 0.0, 0.05)))], "objects": objects,
                     "error": None})  # fmt: skip
    report = score(exam, pd.DataFrame(logs), "scripted")
    assert report["faces"]["task"]["k"] == 0 and report["faces"]["swap_success"]["k"] == 1
    assert report["partial"]["goals"] == 2 and report["partial"]["done"] == {"1": 1}
    assert [e["k"] for e in report["partial"]["each"]] == [1, 0]


HINGE = np.array([-0.1725, 0.262, 1.016])  # KITCHEN_SCENE6's microwave door's hinge


def _door_at(angle: float) -> tuple[float, float, float]:
    """Where the door's place (20 cm along it from the hinge) stands, the door turned `angle` from shut."""
    return tuple(HINGE + 0.2 * np.array([np.cos(angle), np.sin(angle), 0.0]))


@pytest.mark.parametrize(
    ("start", "end", "closed"),
    [(-1.58, -0.004, True), (-1.58, 0.0, True), (-1.58, -0.006, False), (-1.58, -1.2, False), (-0.3, 0.0, False)],
)
def test_a_door_is_closed_when_swung_from_open_to_within_liberos_turn_of_shut(start: float, end: float, closed: bool) -> None:
    """LIBERO's `Close(microwave_1)`: its hinge above -0.005 rad; only a door that started open (0.5 rad or more)."""
    objects = (
        SceneObject("white_yellow_mug_1", "white_yellow_mug", "yellow and white mug", 0, (0.0, 0.0, 0.9)),
        SceneObject("microwave_door", "microwave_door", "microwave", 1, _door_at(0.0)),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_kitchen_scene6")
    spec = EpisodeSpec("libero_10", 0, 0, objects, "microwave_door", "", "", (), (), TaskSpec("close"), setup)
    begin = {o.id: o.pos for o in objects} | {"microwave_door": _door_at(start)}
    outcome = Outcome(begin, {**begin, "microwave_door": _door_at(end)}, (0.0, 0.0, 1.0))
    assert programs.succeeded(spec, outcome) is closed


def test_liberos_goals_for_the_microwave_are_in_its_heating_region_and_close_of_it() -> None:
    """What `sim=libero` asks LIBERO's `check_success` for KITCHEN_SCENE6: its BDDL file's words."""
    objects = (
        SceneObject("white_yellow_mug_1", "white_yellow_mug", "yellow and white mug", 0, (0.0, 0.0, 0.9)),
        SceneObject("microwave_inside", "microwave_inside", "microwave", 1, (0.0, 0.36, 1.016)),
        SceneObject("microwave_door", "microwave_door", "microwave", 2, _door_at(0.0)),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_kitchen_scene6")
    then = [{"program": "close", "target": "microwave_door", "params": {}}]
    task = TaskSpec("place_in", params={"object": "white_yellow_mug_1", THEN: then})
    spec = EpisodeSpec("libero_10", 0, 0, objects, "microwave_inside", "", "", (), (), task, setup)
    start = RowStart("k", {}, {}, None, tuple(o.id for o in objects), ("white_yellow_mug_1",),
                     ("microwave_1_heating_region", "microwave_1_microdoorroot@0.2,0.0,0.0"))  # fmt: skip
    put_in, close = spec.goals()
    assert predicate(put_in, start, "microwave_inside", "place_in") == ["In", "white_yellow_mug_1", "microwave_1_heating_region"]
    assert predicate(close, start, "microwave_door", "close") == ["Close", "microwave_1"]


@pytest.mark.parametrize(("rise", "inside"), [(0.0005, True), (-0.0005, False), (-0.0035, False)])
def test_a_book_is_in_the_caddys_back_compartment_only_above_liberos_lowered_floor(rise: float, inside: bool) -> None:
    """LIBERO's `In(black_book_1, desk_caddy_1_back_contain_region)`: the book's origin in the region's
    box, its floor lowered 1 cm (0.9021 m in LIBERO-10's study). Stood on the compartment's floor its origin
    is 3.5 mm under that, judged not in; leaning on the wall before it, over it (core/furniture.py `Slot`)."""
    site = (-0.43364, -0.13936, 0.97258)
    floor = site[2] - worlds.kind("caddy_back", "libero_10_study").contain[1][2] - CONTAIN_FLOOR
    objects = (
        SceneObject("black_book_1", "black_book", "book", 0, (-0.2, 0.15, 0.883)),
        SceneObject("caddy_back", "caddy_back", "back compartment of the caddy", 1, site),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world="libero_10_study")
    task = TaskSpec("place_in", params={"object": "black_book_1"})
    spec = EpisodeSpec("libero_10", 0, 0, objects, "caddy_back", "", "", (), (), task, setup)
    begin = {o.id: o.pos for o in objects}
    outcome = Outcome(begin, {**begin, "black_book_1": (-0.441, -0.139, floor + rise)}, (0.0, 0.0, 1.0))
    assert programs.succeeded(spec, outcome) is inside
