"""LIBERO-10's scenes against LIBERO's own environment (`.venv-libero`, driven by
eval/sims/libero_env/reference.py), scene by scene as their worlds come (issue 53): the same
physics model, the fixtures where LIBERO stands them (within the 1 cm its placement draws anew at
each reset), and the same pictures at LIBERO-10's own initial states."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from core import libero, programs, worlds
from core.furniture import Spot
from core.spec import FAST, LOOKS, THEN, EpisodeSpec, SceneObject, Setup, TaskSpec
from core.success import Outcome
from eval.sims.libero import fixture_poses
from eval.sims.libero_env.reference import model_arrays  # the same readout on both models
from gen.planning.plan import world_setup
from helpers import PICTURE_STATES, initial_state_pictures, liberos_own, same_physics
from oracle.episode import demonstrate
from oracle.ik import ArmIK
from oracle.scene import Scene, scene_for

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


# the scene each world stands for, by the prefix of its tasks' names (the living room: four scenes)
PREFIXES = {
    "libero_10_kitchen_scene3": ("KITCHEN_SCENE3_",),
    "libero_10_kitchen_scene4": ("KITCHEN_SCENE4_",),
    "libero_10_kitchen_scene6": ("KITCHEN_SCENE6_",),
    "libero_10_kitchen_scene8": ("KITCHEN_SCENE8_",),
    "libero_10_living_room": ("LIVING_ROOM_SCENE",),
    "libero_10_study": ("STUDY_SCENE1_",),
}


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
        for world in PREFIXES
        for look in LOOKS
    ]


@pytest.mark.reference
@pytest.mark.parametrize(("world", "look"), _looks())
def test_the_same_pictures_at_liberos_own_initial_states(world: str, look: str, tmp_path: Path) -> None:
    """The first initial states (PICTURE_STATES) of each of the world's LIBERO-10 tasks, its objects
    loaded by their LIBERO names and the fixtures posed as LIBERO drew them: both cameras within
    helpers.FRAME_BOUND, every object and fixture within helpers.OBJECT_BOUND inside its own pixels
    (in the fast look, OWN_BOUNDS excepted), every object within 1 mm of where LIBERO puts it."""
    tasks = [i for i, name in enumerate(libero.tasks(SUITE)) if name.startswith(PREFIXES[world])]
    cases = [(t, s) for t in tasks for s in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, look, world=world)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


# LIBERO-10's tasks of two goals our skills do, each as our programs in the order the oracle does
# them (LIBERO leaves the order free): (world, places on furniture it names, [(program, target,
# params)]). The pudding goes right of the plate before the mug goes on it (the mug's handle, over
# the plate's edge, is where the pudding comes down); the moka pot goes on the stove before the
# knob is turned (from the turned knob the hand's way to the pot sweeps the table); two moka pots go
# on one burner side by side (`at`). KITCHEN_SCENE8's goal is three, the stove on too, but every one
# of its initial states has the knob on already (0.54-1.85 rad, LIBERO's `Turnon` from 0.5): its
# goals here are the two pots (turned on again, a knob near its 2.1 stop moves too little for our
# scorer, which judges a turn from where the knob started).
POT_APART = 0.045  # m from the burner's centre, along x: the pots are 8.1 cm across, LIBERO's region 15
# m from the basket's centre, along y: its box is 12.2 cm across, the cans 6.2 (the first at its centre, the
# second stood on it, 7 of 10 in)
CANS_APART = 0.03
GOALS = {
    "LIVING_ROOM_SCENE1_put_both_the_alphabet_soup_and_the_cream_cheese_box_in_the_basket": (
        "libero_10_living_room", (),
        (("pick_place", "alphabet_soup_1", {"destination": "basket_1"}),
         ("pick_place", "cream_cheese_1", {"destination": "basket_1"})),
    ),
    "LIVING_ROOM_SCENE2_put_both_the_alphabet_soup_and_the_tomato_sauce_in_the_basket": (  # two cans side by side
        "libero_10_living_room", (),
        (("pick_place", "alphabet_soup_1", {"destination": "basket_1", "at": [0.0, CANS_APART]}),
         ("pick_place", "tomato_sauce_1", {"destination": "basket_1", "at": [0.0, -CANS_APART]})),
    ),
    "LIVING_ROOM_SCENE5_put_the_white_mug_on_the_left_plate_and_put_the_yellow_and_white_mug_on_the_right_plate": (
        "libero_10_living_room", (),
        (("pick_place_on", "porcelain_mug_1", {"destination": "plate_1"}),
         ("pick_place_on", "white_yellow_mug_1", {"destination": "plate_2"})),
    ),
    "LIVING_ROOM_SCENE6_put_the_white_mug_on_the_plate_and_put_the_chocolate_pudding_to_the_right_of_the_plate": (
        "libero_10_living_room", ("plate_right",),
        (("place", "plate_right", {"object": "chocolate_pudding_1"}),
         ("pick_place_on", "porcelain_mug_1", {"destination": "plate_1"})),
    ),
    "KITCHEN_SCENE3_turn_on_the_stove_and_put_the_moka_pot_on_it": (
        "libero_10_kitchen_scene3", ("stove_knob", "stove_burner"),
        (("place", "stove_burner", {"object": "moka_pot_1"}), ("turn_on", "stove_knob", {})),
    ),
    "KITCHEN_SCENE4_put_the_black_bowl_in_the_bottom_drawer_of_the_cabinet_and_close_it": (  # the drawer starts open
        "libero_10_kitchen_scene4", ("white_bottom_drawer",),
        (("place_in", "white_bottom_drawer", {"object": "akita_black_bowl_1"}), ("close", "white_bottom_drawer", {})),
    ),
    "KITCHEN_SCENE8_put_both_moka_pots_on_the_stove": (  # the stove, on already, is LIBERO's third goal
        "libero_10_kitchen_scene8", ("stove_burner",),
        (("place", "stove_burner", {"object": "moka_pot_1", "at": [POT_APART, 0.0]}),
         ("place", "stove_burner", {"object": "moka_pot_2", "at": [-POT_APART, 0.0]})),
    ),
}  # fmt: skip
TWO_GOAL_STATES = 2


def _goals_spec(task: str, state: int, scene: Scene, setup: Setup) -> tuple[EpisodeSpec, np.ndarray]:
    """A LIBERO-10 task at one of its initial states as a spec of its goals (GOALS): its objects
    under their LIBERO names, where the state puts them, and the places on furniture it names, where
    they stand shut (the state opens a drawer); the first goal the spec's target, the others in
    `task.params["then"]`. Returns the spec and the physics state."""
    problem, (_, sites, goals) = libero.problem(SUITE, task), GOALS[task]
    (program, target, params), *rest = goals
    then = [{"program": p, "target": t, "params": a} for p, t, a in rest]
    objects = tuple(SceneObject(i, k, k, 0, (0.0, 0.0, 1.0)) for i, k in (*problem.objects.items(), *((s, s) for s in sites)))
    spec = EpisodeSpec(
        SUITE, state, 0, objects, target, libero.language(task), "", (), _inventory(task),
        task=TaskSpec(program, params={**params, THEN: then}), setup=setup, split="exam",
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
    """The bodies of a GOALS task's scene: its objects and the places it names."""
    return tuple(sorted((Counter(libero.problem(SUITE, task).objects.values()) + Counter(GOALS[task][1])).items()))


@pytest.mark.reference
def test_two_goals_done_in_turn_and_judged_each_as_libero_judges_them(tmp_path: Path) -> None:
    """The oracle does every one of each GOALS task's goals from LIBERO's own initial states (waiting
    first for what those states launch to land: the living room's milk and orange juice, 0.5 m up
    in LIBERO's simulator as in ours; taking the mugs and the moka pot by their handles), our
    scorer judges each goal, and the same actions stepped in LIBERO's environment of the task's own
    BDDL file from the same state meet LIBERO's own predicates goal for goal."""
    cases, ours, asked = [], [], []
    for task, (name, _, _) in GOALS.items():
        world = worlds.world(name)
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
    task = next(t for t in GOALS if t.startswith("KITCHEN_SCENE4"))
    world = worlds.world(GOALS[task][0])
    setup = world_setup(world)
    scene, ik = scene_for(_inventory(task), setup.profile, world.name), ArmIK(np.asarray(world.robot_home), world.name)
    spec, physics = _goals_spec(task, 0, scene, setup)
    drawer = spec.target
    assert np.linalg.norm(np.subtract(scene.object_pos(drawer), spec.object(drawer).pos)) > 0.14, "the state opens it"
    demo = demonstrate(scene, ik, spec, programs.perform, physics, setup.interface.settle_steps)
    assert demo.outcome is not None, demo.failure
    assert programs.each(spec, demo.outcome) == (True, True)
    assert len(demo.actions) <= world.episode_steps


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
