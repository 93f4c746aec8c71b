"""LIBERO-10's scenes against LIBERO's own environment (`.venv-libero`, driven by
eval/sims/libero_env/reference.py), scene by scene as their worlds come (issue 53): the same
physics model, the fixtures where LIBERO stands them (within the 1 cm its placement draws anew at
each reset), and the same pictures at LIBERO-10's own initial states."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from core import contact, libero, libero_goals, programs, worlds
from core.exam import read
from core.furniture import Spot
from core.libero_goals import Goal
from core.spec import FAST, LOOKS, EpisodeSpec, SceneObject, Setup
from core.success import CONTAIN_FLOOR, Outcome
from eval.sims.libero import fixture_poses
from eval.sims.libero_env.reference import model_arrays  # the same readout on both models
from gen.planning.plan import plan, world_setup
from helpers import (
    PICTURE_STATES,
    Shared,
    canonical_reports,
    initial_state_pictures,
    liberos_own,
    liberos_replay,
    make_dataset,
    same_physics,
)
from oracle.episode import Demo, demonstrate
from oracle.ik import ArmIK
from oracle.scene import Scene, scene_for, spec_scene
from referents import registry

SUITE = "libero_10"
# world -> its LIBERO-10 task (the scene's first) and the objects it holds
SCENES = {
    "libero_10_kitchen_scene3": ("KITCHEN_SCENE3_turn_on_the_stove_and_put_the_moka_pot_on_it",
                                 (("chefmate_8_frypan", 1), ("moka_pot", 1))),
    "libero_10_kitchen_scene4": ("KITCHEN_SCENE4_put_the_black_bowl_in_the_bottom_drawer_of_the_cabinet_and_close_it",
                                 (("akita_black_bowl", 1), ("wine_bottle", 1))),
    "libero_10_kitchen_scene6": ("KITCHEN_SCENE6_put_the_yellow_and_white_mug_in_the_microwave_and_close_it",
                                 (("porcelain_mug", 1), ("white_yellow_mug", 1))),
    "libero_10_kitchen_scene8": ("KITCHEN_SCENE8_put_both_moka_pots_on_the_stove", (("moka_pot", 2),)),
    "libero_10_living_room": ("LIVING_ROOM_SCENE2_put_both_the_alphabet_soup_and_the_tomato_sauce_in_the_basket",
                              tuple((k, 1) for k in ("alphabet_soup", "cream_cheese", "tomato_sauce", "ketchup", "orange_juice",
                                                     "milk", "butter", "basket"))),
    "libero_10_study": ("STUDY_SCENE1_pick_up_the_book_and_place_it_in_the_back_compartment_of_the_caddy",
                        (("black_book", 1), ("white_yellow_mug", 1))),
}  # fmt: skip


@pytest.mark.reference
@pytest.mark.parametrize("world", SCENES)
def test_the_compiled_physics_is_liberos(world: str, tmp_path: Path) -> None:
    """Every body, joint, colliding geom, actuator and camera of the scene's LIBERO-10 task has its
    twin in ours, with the same values: the kitchen's table (its friction robosuite's 1, not the
    tabletop's 0.6) and mounted Panda, the living room's table and Panda on the floor, the stove,
    the moka pots, the frying pan, the groceries and the basket."""
    task, assets = SCENES[world]
    assert task in libero.tasks(SUITE)
    theirs = dict(np.load(liberos_own("model", {"suite": SUITE, "task": task}, tmp_path / "model.npz")))
    ours = model_arrays(scene_for(assets, "libero", world).model)
    compared = same_physics(theirs, ours, (f for f in libero.problem(SUITE, task).fixtures if not f.endswith("_table")))
    assert all(any(f":{kind}_1" in k for k in compared) for kind, _ in assets) and any("friction" in k for k in compared)
    for fixture in worlds.world(world).fixtures:  # at its region's centre: LIBERO draws it within 1 cm of it, turned as ours
        body = f"{fixture.name}_main"
        assert np.abs(theirs[f"body_pos:{body}"] - ours[f"body_pos:{body}"]).max() < 0.015, body
        assert np.allclose(theirs[f"body_quat:{body}"], ours[f"body_quat:{body}"], atol=1e-6), body


WORLDS = tuple(SCENES)  # every LIBERO-10 world, each standing its scenes (World.scenes)


# Things the fast look (core/spec.py LOOKS) cannot draw within helpers.OBJECT_BOUND: the stove's mirror
# top (22-29/255 agentview, its plate fitted in the kitchen too), the woven basket (24, as LIBERO-PRO's
# tests measure it) and the white mug's decimated mesh near the wrist camera (18). The full look draws
# every thing within it.
OWN_BOUNDS = {"flat_stove": 30.0, "basket": 28.0, "porcelain_mug": 19.0}
# Whole frames the fast look leaves over helpers.FRAME_BOUND (no shadows, no reflections): the living
# room's low camera sees the robot and the wall it shades (5.2/255; the full look 1.6), the second
# kitchen stove's mirror (4.15). Expected to fail until the fast look draws them.
FAST_SHORT = {"libero_10_living_room": "5.2/255 in the fast look", "libero_10_kitchen_scene8": "4.15/255 in the fast look"}


def _looks() -> list:
    return [
        pytest.param(world, look, marks=pytest.mark.xfail(strict=True, reason=FAST_SHORT[world]))
        if look == FAST and world in FAST_SHORT
        else (world, look)
        for world in WORLDS
        for look in LOOKS
    ]


@pytest.mark.reference
@pytest.mark.parametrize(("world", "look"), _looks())
def test_the_same_pictures_at_liberos_own_initial_states(world: str, look: str, tmp_path: Path) -> None:
    """The first initial states (PICTURE_STATES) of each of the world's LIBERO-10 tasks, its objects
    loaded by their LIBERO names and the fixtures posed as LIBERO drew them: both cameras within
    helpers.FRAME_BOUND, every object and fixture within helpers.OBJECT_BOUND inside its own pixels
    (in the fast look, OWN_BOUNDS excepted), every object within 1 mm of where LIBERO puts it."""
    tasks = [i for i, name in enumerate(libero.tasks(SUITE)) if name.startswith(worlds.world(world).scenes)]
    cases = [(t, s) for t in tasks for s in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, look, world=world)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


# LIBERO-10's tasks our skills do, most of two goals (core/libero_goals.py reads each as our programs from its
# BDDL file; the world standing each, worlds.standing). KITCHEN_SCENE8's goal is three, the stove on too, but every one of its
# initial states has the knob on already (0.54-1.85 rad, LIBERO's `Turnon` from 0.5): its goals here are
# the two pots (turned on again, a knob near its 2.1 stop moves too little for our scorer, which judges a
# turn from where the knob started). LIVING_ROOM_SCENE2's cream cheese and butter are left out: twice in
# LIBERO's first 10 states the hand comes down on the milk beside the cream cheese, once it misses the butter.
# STUDY_SCENE1's one goal, the book into the caddy's back compartment, is done leaning (core/furniture.py `Slot`).
TASKS = (
    "LIVING_ROOM_SCENE1_put_both_the_alphabet_soup_and_the_cream_cheese_box_in_the_basket",
    "LIVING_ROOM_SCENE2_put_both_the_alphabet_soup_and_the_tomato_sauce_in_the_basket",
    "LIVING_ROOM_SCENE5_put_the_white_mug_on_the_left_plate_and_put_the_yellow_and_white_mug_on_the_right_plate",
    "LIVING_ROOM_SCENE6_put_the_white_mug_on_the_plate_and_put_the_chocolate_pudding_to_the_right_of_the_plate",
    "KITCHEN_SCENE3_turn_on_the_stove_and_put_the_moka_pot_on_it",
    "KITCHEN_SCENE4_put_the_black_bowl_in_the_bottom_drawer_of_the_cabinet_and_close_it",
    "KITCHEN_SCENE6_put_the_yellow_and_white_mug_in_the_microwave_and_close_it",
    "KITCHEN_SCENE8_put_both_moka_pots_on_the_stove",
    "STUDY_SCENE1_pick_up_the_book_and_place_it_in_the_back_compartment_of_the_caddy",
)
MET_ALREADY = {"KITCHEN_SCENE8_put_both_moka_pots_on_the_stove": "turn_on"}  # a goal every initial state has met


def _goals(task: str) -> tuple[Goal, ...]:
    """A TASKS task's goals as our programs, in the order the oracle does them."""
    found = libero_goals.goals(libero.problem(SUITE, task), worlds.standing(task))
    assert found is not None, f"{task}: a goal our programs do not do"
    return tuple(g for g in found if g.program != MET_ALREADY.get(task))


def _sites(task: str) -> tuple[str, ...]:
    """The places on furniture a TASKS task's goals name (the world's kinds of them)."""
    problem = libero.problem(SUITE, task)
    return tuple(dict.fromkeys(g.target for g in _goals(task) if g.target not in problem.objects))


def test_liberos_goals_read_as_our_programs_in_the_oracles_order() -> None:
    """Each task's BDDL goal as programs: into the basket side by side, onto the plates, the pudding
    right of the plate before the mug goes on it, the pot on the burner before the knob is turned,
    the bowl into the drawer before it is shut, two moka pots on one burner side by side."""
    read = {t[:18]: [(g.program, g.target, g.params) for g in _goals(t)] for t in TASKS}
    basket = {"destination": "basket_1"}
    assert read["LIVING_ROOM_SCENE2"] == [
        ("pick_place", "alphabet_soup_1", {**basket, "at": [0.0, 0.03]}),
        ("pick_place", "tomato_sauce_1", {**basket, "at": [-0.0, -0.03]}),
    ]
    assert read["LIVING_ROOM_SCENE5"] == [("pick_place_on", "porcelain_mug_1", {"destination": "plate_1"}),
                                          ("pick_place_on", "white_yellow_mug_1", {"destination": "plate_2"})]  # fmt: skip
    assert read["LIVING_ROOM_SCENE6"] == [("place", "plate_right", {"object": "chocolate_pudding_1"}),
                                          ("pick_place_on", "porcelain_mug_1", {"destination": "plate_1"})]  # fmt: skip
    assert read["KITCHEN_SCENE3_tur"] == [("place", "stove_burner", {"object": "moka_pot_1"}), ("turn_on", "stove_knob", {})]
    assert read["KITCHEN_SCENE4_put"] == [("place_in", "white_bottom_drawer", {"object": "akita_black_bowl_1"}),
                                          ("close", "white_bottom_drawer", {})]  # fmt: skip
    assert read["KITCHEN_SCENE8_put"] == [("place", "stove_burner", {"object": "moka_pot_1", "at": [0.045, 0.0]}),
                                          ("place", "stove_burner", {"object": "moka_pot_2", "at": [-0.045, -0.0]})]  # fmt: skip
    assert read["KITCHEN_SCENE6_put"] == [("place_in", "microwave_inside", {"object": "white_yellow_mug_1"}),
                                          ("close", "microwave_door", {})]  # fmt: skip
    assert read["STUDY_SCENE1_pick_"] == [("place_in", "caddy_back", {"object": "black_book_1"})]


def test_every_task_stands_in_one_world() -> None:
    """Each of LIBERO-10's ten tasks has its scene in one world of ours (World.scenes); the living room stands four."""
    standing = Counter(worlds.standing(task).name for task in libero.tasks(SUITE))
    assert set(standing) == set(SCENES) and standing["libero_10_living_room"] == 5 and sum(standing.values()) == 10
    with pytest.raises(worlds.UnknownWorld, match="no world"):
        worlds.standing("FLOOR_SCENE10_pick_up_the_ketchup")


TWO_GOAL_STATES = 2


def _goals_spec(task: str, state: int, scene: Scene, setup: Setup) -> tuple[EpisodeSpec, np.ndarray]:
    """A LIBERO-10 task at one of its initial states as a spec of its goals (TASKS): its objects
    under their LIBERO names, where the state puts them, and the places on furniture it names, where
    they stand shut (the state opens a drawer); the first goal the spec's target, the others in
    `task.params["then"]`. Returns the spec and the physics state."""
    problem, sites = libero.problem(SUITE, task), _sites(task)
    goals = _goals(task)
    objects = tuple(SceneObject(i, k, k, 0, (0.0, 0.0, 1.0)) for i, k in (*problem.objects.items(), *((s, s) for s in sites)))
    spec = EpisodeSpec(
        SUITE, state, 0, objects, goals[0].target, libero.language(task), "", (), _inventory(task),
        task=libero_goals.task(goals), setup=setup, split="exam",
    )  # fmt: skip
    vector = libero.initial_states(SUITE, task)[state]
    scene.reset(spec)
    shut = {s: tuple(map(float, scene.object_pos(s))) for s in sites}
    for _ in range(2):  # the second time every object is posed where the state puts it, as in the spec
        scene.reset(spec)
        scene.set_joints(*libero.split_state(vector, problem))
        spec = replace(
            spec, objects=tuple(replace(o, pos=shut.get(o.id) or tuple(map(float, scene.object_pos(o.id)))) for o in objects)
        )
    return spec, scene.physics_state()


def _inventory(task: str) -> tuple[tuple[str, int], ...]:
    """The bodies of a TASKS task's scene: its objects and the places it names."""
    return tuple(sorted((Counter(libero.problem(SUITE, task).objects.values()) + Counter(_sites(task))).items()))


@pytest.mark.reference
def test_two_goals_done_in_turn_and_judged_each_as_libero_judges_them(tmp_path: Path) -> None:
    """The oracle does every one of each TASKS task's goals from LIBERO's own initial states (waiting
    first for what those states launch to land: the living room's milk and orange juice, 0.5 m up
    in LIBERO's simulator as in ours; taking the mugs and the moka pot by their handles), our
    scorer judges each goal, and the same actions stepped in LIBERO's environment of the task's own
    BDDL file from the same state meet LIBERO's own predicates goal for goal."""
    cases, ours, asked = [], [], []
    for task in TASKS:
        world = worlds.standing(task)
        name = world.name
        setup = world_setup(world)
        scene, ik = scene_for(_inventory(task), setup.profile, name), ArmIK(np.asarray(world.robot_home), name)
        settle, hold = setup.interface.settle_steps, setup.interface.hold_action(world.robot_home)
        for state in range(TWO_GOAL_STATES):
            spec, physics = _goals_spec(task, state, scene, setup)
            demo = demonstrate(scene, ik, spec, programs.perform, physics, settle)
            assert demo.outcome is not None, f"{task} state {state}: {demo.failure}"
            assert len(demo.actions) <= world.episode_steps, f"{task} state {state}: {len(demo.actions)} steps"
            ours.append(programs.each(spec, demo.outcome))
            asked.append((spec, demo.outcome))
            actions = [hold.tolist()] * settle + demo.actions.tolist()
            places, fixtures = list(_places(spec).values()), fixture_poses(spec.scene_record())
            cases.append({"task": task, "state": state, "actions": actions, "places": places, "fixtures": fixtures})
    theirs = json.loads(liberos_own("task_replay", {"suite": SUITE, "cases": cases}, tmp_path / "replay.json").read_text())
    liberos = [_in_our_order(spec, r["goals"]) for (spec, _), r in zip(asked, theirs)]
    # our scorer on where LIBERO's simulator left everything (the two simulators part where a can is
    # let go onto another: in one it balances, in the other it falls out), as sim=libero judges a
    # rollout: its objects and the places on its furniture (a drawer's region, a point on the knob)
    judged = []
    for (spec, outcome), r in zip(asked, theirs):
        ended = {i: tuple(r["places"][anchor]) for i, anchor in _places(spec).items()} | {i: tuple(p) for i, *p in r["objects"]}
        judged.append(programs.each(spec, Outcome(outcome.start, ended, outcome.ee)))
    print("ours", ours, "LIBERO's", liberos, "ours on LIBERO's", judged, "LIBERO's joints", [r["joints"] for r in theirs])
    assert judged == liberos, "our scorer and LIBERO's predicates judge the goals differently"
    assert [r["success"] for r in theirs] == [all(g) for g in liberos]
    assert sum(all(g) for g in ours) >= len(ours) - 1, f"every goal reached in {ours}"
    # LIBERO's simulator parts from ours where a mug or a can is let down (at states 0-9: 67 of 70
    # replays reached every goal, docs/LIBERO.md)
    assert sum(all(g) for g in liberos) >= 0.8 * len(liberos), f"every goal reached in LIBERO's {liberos}"


def test_a_bowl_put_in_the_open_drawer_and_the_drawer_pushed_shut() -> None:
    """KITCHEN_SCENE4 from LIBERO's own initial state 0, which leaves the white cabinet's bottom drawer
    open 14.6 cm: the oracle lets the bowl down into it (not pulling it further) and pushes it shut
    past where it stands shut; our scorer judges both goals done, the drawer no longer open."""
    task = next(t for t in TASKS if t.startswith("KITCHEN_SCENE4"))
    world = worlds.standing(task)
    setup = world_setup(world)
    scene, ik = scene_for(_inventory(task), setup.profile, world.name), ArmIK(np.asarray(world.robot_home), world.name)
    spec, physics = _goals_spec(task, 0, scene, setup)
    drawer = spec.target
    assert np.linalg.norm(np.subtract(scene.object_pos(drawer), spec.object(drawer).pos)) > 0.14, "the state opens it"
    demo = demonstrate(scene, ik, spec, programs.perform, physics, setup.interface.settle_steps)
    assert demo.outcome is not None, demo.failure
    assert programs.each(spec, demo.outcome) == (True, True)
    assert len(demo.actions) <= world.episode_steps


def test_a_mug_put_in_the_microwave_and_its_door_swung_shut() -> None:
    """KITCHEN_SCENE6 from LIBERO's own initial state 0, which leaves the microwave's door open 90°:
    the oracle lets the yellow and white mug down at the front of its floor, pushes it in, and
    swings the door shut round its hinge; our scorer judges both goals done."""
    task = next(t for t in TASKS if t.startswith("KITCHEN_SCENE6"))
    world = worlds.standing(task)
    setup = world_setup(world)
    scene, ik = scene_for(_inventory(task), setup.profile, world.name), ArmIK(np.asarray(world.robot_home), world.name)
    spec, physics = _goals_spec(task, 0, scene, setup)
    door = spec.goals()[1].target
    assert np.linalg.norm(np.subtract(scene.object_pos(door), spec.object(door).pos)) > 0.2, "the state opens it"
    demo = demonstrate(scene, ik, spec, programs.perform, physics, setup.interface.settle_steps)
    assert demo.outcome is not None, demo.failure
    assert programs.each(spec, demo.outcome) == (True, True)
    assert len(demo.actions) <= world.episode_steps


def test_a_book_stood_in_the_caddys_back_compartment_leaning() -> None:
    """STUDY_SCENE1 from LIBERO's own initial state 0: the oracle stands the book in the caddy's back
    compartment leaning on the wall before it, where LIBERO's `In` (the region's floor lowered 1 cm)
    holds; standing upright on the compartment's floor its origin would be 3.5 mm under that bound."""
    task = next(t for t in TASKS if t.startswith("STUDY_SCENE1"))
    world = worlds.standing(task)
    spec, scene, demo = _demonstrated(task, 0)
    book = scene.placed["black_book_1"].body_id
    lean = np.degrees(np.arccos(scene.data.xmat[book].reshape(3, 3)[2, 2]))
    site, (_, region) = scene.object_pos(spec.target), worlds.kind("caddy_back", world.name).contain
    height = scene.object_pos("black_book_1")[2]
    assert 10 < lean < 25 and height > site[2] - region[2] - CONTAIN_FLOOR, (lean, height)
    assert programs.each(spec, demo.outcome) == (True,)
    assert len(demo.actions) <= world.episode_steps


def test_a_box_beside_a_tall_carton_is_taken_turned_a_quarter() -> None:
    """LIVING_ROOM_SCENE2's state 41 stands the milk 11 cm beside the butter along the axis the fingers
    would close on: the hand, 20 cm wide that way, came down on the milk's top and closed 7 cm over the
    butter. Turned a quarter (the butter's 7.6 cm under the fingers' 8), it takes the butter, and both
    goals are done."""
    spec, _, demo = _demonstrated("LIVING_ROOM_SCENE2_put_both_the_cream_cheese_box_and_the_butter_in_the_basket", 41)
    assert programs.each(spec, demo.outcome) == (True, True)


def _demonstrated(task: str, state: int) -> tuple[EpisodeSpec, Scene, Demo]:
    """The oracle's demonstration of a TASKS task's goals from LIBERO's initial state `state`: its spec,
    the scene it ran in, and the demonstration (which ran to its end)."""
    world = worlds.standing(task)
    setup = world_setup(world)
    scene, ik = scene_for(_inventory(task), setup.profile, world.name), ArmIK(np.asarray(world.robot_home), world.name)
    spec, physics = _goals_spec(task, state, scene, setup)
    demo = demonstrate(scene, ik, spec, programs.perform, physics, setup.interface.settle_steps)
    assert demo.outcome is not None, demo.failure
    return spec, scene, demo


def _places(spec: EpisodeSpec) -> dict[str, str]:
    """The spec's places on furniture: id -> where LIBERO's simulator finds it (`Spot.anchor`)."""
    kinds = {o.id: worlds.kind(o.kind, spec.setup.world) for o in spec.objects}
    return {i: k.part(Spot).anchor for i, k in kinds.items() if k.is_site}


def _in_our_order(spec: EpisodeSpec, goals: list) -> tuple[bool, ...]:
    """LIBERO's verdicts on a task's goals ([[predicate words], done] in its BDDL file's order) in the
    order of the spec's goals: each found by what it moves, or for a motion of the furniture by
    LIBERO's name of the furniture (the knob's: the stove)."""
    verdicts = {words[1]: done for words, done in goals}
    found = []
    for goal in spec.goals():
        params, kind = goal.task.params, worlds.kind(goal.object(goal.target).kind, goal.setup.world)
        moves = params.get("object", goal.target if "destination" in params else None)
        found.append(verdicts[moves or libero.place_name(kind, kind.part(Spot).anchor)])
    return tuple(found)


PUT_BOTH = "libero_10"  # the referent type of LIBERO-10's "put both" in its living room
LIVING_ROOM = "libero_10_living_room"
PUT_BOTH_REPLAYS = 10  # the reference test's episodes (docs/LIBERO.md); make test replays 2


def _put_both_replayed(tmp_path: Path, n: int) -> list[dict]:
    """`referent=libero_10` episodes (n, 32 px) replayed in LIBERO's own living room (LIVING_ROOM_SCENE2's
    BDDL file, which holds its seven groceries and the basket; the groceries an episode leaves out parked
    off the table), each of the two goals judged by LIBERO's `In` of the basket."""
    root = make_dataset(tmp_path / "put_both", f"referent={PUT_BOTH}", f"n={n}", "image_size=32", "seed=1")
    request = liberos_replay(root, worlds.world(LIVING_ROOM))
    return json.loads(liberos_own("replay", request, tmp_path / "replay.json").read_text())


def test_put_both_episodes_reach_both_goals_in_liberos_own_living_room(tmp_path: Path) -> None:
    """Two generated episodes, every grocery displaced from LIBERO's regions: LIBERO's simulator, stepping
    the recorded actions, finds both named groceries in the basket."""
    results = _put_both_replayed(tmp_path, 2)
    print([r["goals"] for r in results])
    assert [[ok for _, ok in r["goals"]] for r in results] == [[True, True]] * 2


def test_a_tall_carton_is_let_down_inside_the_basket_not_dropped_over_its_rim() -> None:
    """The ketchup (14.6 cm tall) brought second, beside a grocery already in the basket: the hand lets
    it go inside, its bottom under 6 cm over the basket's floor (let go over the rim, it fell 16 cm, and
    in LIBERO's simulator 3 cartons of 20 came to rest on the basket's near wall); both goals done."""
    world = worlds.world(LIVING_ROOM)
    designs = plan(registry.load(PUT_BOTH), 20, 0, world_setup(world))
    spec = next(s for s in designs if s.object(s.goals()[1].target).kind == "ketchup")
    scene = spec_scene(spec)
    demo = demonstrate(scene, ArmIK(np.asarray(world.robot_home), world.name), spec, programs.perform)
    assert demo.outcome is not None and programs.each(spec, demo.outcome) == (True, True), demo.failure
    grip = demo.actions[:, -1]
    let_go = np.flatnonzero((grip[:-1] > 0) & (grip[1:] <= 0)) + 1  # the steps the fingers open on what they held
    assert len(let_go) == 2
    scene.set_physics_state(demo.states[let_go[1]])
    ketchup, basket = spec.goals()[1].target, spec.task.params["destination"]
    floor = contact.floor(worlds.kind("basket", world.name), scene.object_pos(basket))
    fell = scene.object_pos(ketchup)[2] - worlds.kind("ketchup", world.name).bottom - floor
    assert fell < 0.06, f"the ketchup let go {fell * 100:.1f} cm over the basket's floor"


@pytest.mark.reference
def test_put_both_episodes_replay_in_liberos_own_living_room(tmp_path: Path) -> None:
    """Ten generated episodes: LIBERO's predicates find both goals reached in nine or more (issue 53's 90%)."""
    results = _put_both_replayed(tmp_path, PUT_BOTH_REPLAYS)
    done = sum(r["success"] for r in results)
    print(f"both goals in LIBERO's simulator: {done}/{len(results)}", [r["goals"] for r in results])
    assert done >= 0.9 * PUT_BOTH_REPLAYS


def test_the_living_rooms_canonical_exam_holds_its_put_both_tasks(shared: Shared) -> None:
    """`gen.canonical world=libero_10_living_room`: the three "put both" tasks on LIBERO's own states,
    a swap from each other grocery renaming the first name or the second in turn (the other kept); the
    mugs onto the plates and the pudding right of the plate as LIBERO sets them, with no swap (the red
    mug beside them is too wide to take)."""
    exam = read(shared.canonical(LIVING_ROOM))
    canonical = exam.meta["canonical"]
    assert [t[:18] for t in canonical["tasks"]] == ["LIVING_ROOM_SCENE2", "LIVING_ROOM_SCENE2", "LIVING_ROOM_SCENE5",
                                                    "LIVING_ROOM_SCENE6", "LIVING_ROOM_SCENE1"]  # fmt: skip
    assert not canonical["left_out"]
    mugs = exam.trials[exam.trials["trial"].isin([2, 3])]
    assert "swap" not in set(mugs["face"]) and list(mugs["face"]).count("task") == 2
    first = exam.trials[exam.trials["trial"] == 4]  # LIVING_ROOM_SCENE1: alphabet soup and cream cheese box
    swaps = sorted(first[first["face"] == "swap"]["instruction"])
    assert swaps == ["put both the alphabet soup and the ketchup in the basket",
                     "put both the tomato sauce and the cream cheese box in the basket"]  # fmt: skip
    assert {a.get("goal", 0) for a in json.loads(exam.trials["alternatives"].iloc[0])} == {0, 1}


@pytest.mark.reference
def test_the_oracle_does_the_living_rooms_canonical_exam_and_the_remembered_layout_reads_no_name(shared: Shared) -> None:
    """On LIBERO's own first states of the living room's five tasks (three "put both", the mugs onto
    the plates, the mug and the pudding) the oracle does the tasks and most swaps (12 of 12 since a basket is entered, not
    dropped into; 10 before), at least the 90% asked; the remembered layout (`position`: a scene's
    groceries say which task, the first by name where two share one) does the
    tasks whose scene it knows and no swap; `nothing` does nothing. A swap is read at its `achieved`
    level (the whole renamed ask done): the hand lands on the kept name's grocery whichever it read."""
    reports = canonical_reports(shared, {"oracle": 5, "position": 5, "nothing": 1}, LIVING_ROOM)
    faces = {policy: report["faces"] for policy, report in reports.items()}
    assert faces["oracle"]["task"]["k"] >= 4 and faces["oracle"]["obeyed_name"]["rate"] >= 0.9, faces["oracle"]
    assert faces["position"]["task"]["k"] >= 3 and faces["position"]["obeyed_name"]["k"] == 0, faces["position"]
    assert all(f["k"] == 0 for f in faces["nothing"].values())
    assert reports["oracle"]["partial"]["done"].get("1+2", 0) >= 4, reports["oracle"]["partial"]


def test_libero_10s_canonical_exam_spans_the_worlds_of_its_scenes(shared: Shared) -> None:
    """`gen.canonical world=libero_10`: one exam of LIBERO-10's tasks across the worlds its scenes stand
    in, each trial's spec naming its own (exam.json lists them under `worlds`, the audit per world):
    all ten tasks, the kitchens', the mugs' and the study's as LIBERO sets them, with no swap."""
    exam = read(shared.canonical(SUITE))
    canonical = exam.meta["canonical"]
    assert len(canonical["tasks"]) == 10 and not canonical["left_out"], list(canonical["tasks"])
    stood = {EpisodeSpec.from_json(s).setup.world for s in exam.trials["spec"]}
    assert stood == set(exam.meta["worlds"]) == set(SCENES) == set(exam.meta["audit"])
    assert "world" not in exam.meta and exam.meta["command"].startswith("python -m gen.canonical world=libero_10 states=1")
    kitchens = exam.trials[exam.trials["spec"].map(lambda s: "kitchen" in EpisodeSpec.from_json(s).setup.world)]
    assert len(kitchens) and "swap" not in set(kitchens["face"])


def test_the_oracle_does_the_kitchens_tasks_of_libero_10s_canonical_exam(shared: Shared) -> None:
    """Its first four trials are the kitchens' (the stove on and the pot on it, the bowl in the drawer
    and the drawer shut, the mug in the microwave and its door shut, both pots on the stove), from
    LIBERO's own first states, each judged goal by goal: the oracle does all four; a drawer or door the
    state leaves open is recorded where it stands shut, and the log's first step is still its start."""
    report = canonical_reports(shared, {"oracle": 4}, SUITE)["oracle"]
    assert report["faces"]["task"]["k"] == 4, report["faces"]["task"]


@pytest.mark.parametrize(
    ("command", "argv", "needle"),
    [
        ("gen.canonical", ["world=libero_10_kitchen_scene9"], "unknown world 'libero_10_kitchen_scene9'"),
        ("gen", ["referent=libero_10", "world=libero_10_kitchen_scene3", "n=1"], "lays out only LIBERO's own tasks in world"),
        ("gen.canonical", ["suite=libero_10_with_milk"], "none of its tasks is set in a scene of ours (its first: FLOOR_SCENE1"),
        ("eval.suites", ["policy=nothing", "world=native"], "has no LIBERO suite; canonical exams are LIBERO's: libero_10,"),
    ],
)
def test_libero_10s_bad_input_is_refused_in_one_line(command: str, argv: list[str], needle: str, tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", command, *argv, f"out={out}"], capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and needle in lines[0], done.stderr
    assert not out.exists()


def test_the_suites_of_libero_10_are_those_its_worlds_lay_out() -> None:
    """`python -m eval.suites world=libero_10` (as `gen.canonical world=libero_10`) takes LIBERO-10's
    suites across its worlds, and so does one of its worlds: the suites with a task set in a scene of
    ours, not the added-object ones LIBERO-PRO sets on a floor of its own."""
    from eval.suites import SuitesOptions, chosen

    taken = chosen(SuitesOptions(policy="nothing", world="libero_10"))
    assert taken[0] == "libero_10" and {"libero_10_lan", "libero_10_swap"} <= set(taken), taken
    assert not any("_with_" in name for name in taken), taken
    assert chosen(SuitesOptions(policy="nothing", world="libero_10_study")) == taken
