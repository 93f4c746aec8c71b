"""The libero_goal world against LIBERO's own environment (`.venv-libero`, driven by
eval/sims/libero_env/reference.py): the same physics model, the same pictures at LIBERO-Goal's own
initial states, recorded actions that LIBERO's own `check_success()` accepts, and the goal axis's
exams: LIBERO's own states (the tasks our skills can do) and displaced objects; its motions (drawers,
the knob, the push) and the verb axis in its scene."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # before any GL context (docs/GENERATE.md: why these pins)

from core import contact, libero, worlds
from core.exam import read
from core.programs import succeeded
from core.spec import FAST, LOOKS, EpisodeSpec
from core.success import Outcome
from eval.policies.registry import make
from eval.scoring.battery import take
from eval.sims.libero_env.reference import model_arrays  # the same readout on both models
from gen.planning.plan import default_setup, plan
from gen.products import scenes
from gen.products.canonical import covered
from helpers import (
    PICTURE_STATES,
    REPLAYS,
    Shared,
    canonical_reports,
    initial_state_pictures,
    liberos_own,
    liberos_replay,
    make_dataset,
    rows_of,
    same_physics,
)
from oracle.clearance import CARRY_MARGIN
from oracle.episode import demonstrate
from oracle.ik import ArmIK
from oracle.scene import scene_for
from referents import registry

SUITE = "libero_goal"
# Things the fast look (core/spec.py LOOKS) cannot draw within helpers.OBJECT_BOUND (docs/LIBERO.md): the stove's
# mirror top (16/255 agentview) and the black bowl's decimated mesh (13/255 agentview). The full look
# draws every thing within it.
OWN_BOUNDS = {"flat_stove": 17.0, "akita_black_bowl": 14.0}
ASSETS = (("akita_black_bowl", 1), ("cream_cheese", 1), ("plate", 1), ("wine_bottle", 1))


@pytest.fixture(scope="module")
def world() -> worlds.World:
    return worlds.world(SUITE)


@pytest.mark.reference
def test_the_compiled_physics_is_liberos(tmp_path: Path) -> None:
    """Every body, joint, colliding geom, actuator and camera of LIBERO-Goal's task-0 scene has its
    twin in ours: the table, the mounted Panda, the cabinet, the stove, the wine rack, the bowl,
    cream cheese, wine bottle and plate (the fixtures' poses aside: LIBERO draws them per reset)."""
    theirs = dict(np.load(liberos_own("model", {"suite": SUITE, "task": 0}, tmp_path / "model.npz")))
    ours = model_arrays(scene_for(ASSETS, "libero", SUITE).model)
    compared = same_physics(theirs, ours, ("wooden_cabinet_1", "flat_stove_1", "wine_rack_1"))
    assert any(":wine_rack_1" in k for k in compared) and len(compared) > 1500


@pytest.mark.reference
@pytest.mark.parametrize("look", LOOKS)
def test_the_same_pictures_and_poses_at_liberos_own_initial_states(look: str, tmp_path: Path) -> None:
    """LIBERO-Goal's first initial states (PICTURE_STATES) of each of its 10 tasks, the fixtures posed as LIBERO
    drew them: both cameras within 4/255 mean absolute difference, and within 12/255 inside each
    object's and fixture's own pixels (helpers.Pictures; in the fast look, OWN_BOUNDS excepted); every object within 1 mm."""
    cases = [(t, s) for t in range(10) for s in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, look)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


# the fixtures as LIBERO-Goal's motions leave them: both drawers out (open past LIBERO's 14 cm), the knob on
MOVED = {"wooden_cabinet_1_top_level": -0.16, "wooden_cabinet_1_middle_level": -0.14, "flat_stove_1_button": 1.0}


@pytest.mark.reference
def test_the_same_pictures_with_the_drawers_open_and_the_knob_turned(tmp_path: Path) -> None:
    """The first initial state of PICTURE_STATES tasks (docs/LIBERO.md: 5), the cabinet's top and
    middle drawers pulled out and the stove's knob turned on in both simulators: within the same
    bounds as the closed ones."""
    cases = [(t, 0) for t in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, FAST, joints=MOVED)
    pictures.check(OWN_BOUNDS)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


def test_a_bowl_beside_the_stove_is_taken_from_a_side_clear_of_it(world: worlds.World) -> None:
    """A bowl whose robot-facing side has the stove's burner under the outer finger: grasped
    there, the finger lands on the burner and the bowl stays (all ten attempts failed so before
    the oracle chose the side); taken from a side clear of it, the task is done. (The axis keeps
    the bowl off the places beside the stove since it pushes the plate there, `keep_off`: the bowl
    of `n=20 seed=1`'s episode 7 trades places with what stands at the stove's corner.)"""
    referent = registry.load(SUITE)
    setup = default_setup(referent)
    spec = plan(referent, 20, 1, setup)[7]
    carried = spec.task.params["object"]
    corner = (-0.1, 0.28, spec.object(carried).pos[2])  # layout slot 4, the stove's burner 8 cm to its left
    there = next((o for o in spec.objects if o.slot == 4), None)
    moved = {carried: corner} | ({there.id: (*spec.object(carried).pos[:2], there.pos[2])} if there else {})
    spec = replace(spec, objects=tuple(replace(o, pos=moved.get(o.id, o.pos)) for o in spec.objects))
    bowl = spec.object(carried)
    kind = world.kind(bowl.kind)
    assert kind.rim, f"episode 7 no longer carries the bowl but {bowl.name}"
    scene = scene_for(referent.assets(), setup.profile, SUITE)
    scene.reset(spec)
    toward = np.subtract(world.robot_base[:2], bowl.pos[:2])
    outer_finger = np.asarray(bowl.pos[:2]) + (kind.rim + 0.05) * toward / np.linalg.norm(toward)
    fingertip = contact.grasp_point(kind, np.asarray(bowl.pos))[2] - 0.01
    assert scene.surface_below(outer_finger, 1.5) > fingertip, "the scene no longer has the stove beside the bowl"
    assert demonstrate(scene, ArmIK(np.asarray(setup.robot_home), setup.world), spec, referent.demo).success


def test_the_hand_carries_the_cheese_a_margin_clear_of_the_standing_bottle() -> None:
    """The cream cheese carried to the plate past the upright wine bottle: in issue 29's scene the
    bottle stood 12.8 cm from the plate, the hand rose past it on a diagonal and came down on one,
    6 mm from it in our simulation, and in LIBERO's own struck it and dropped the cheese off the
    plate. Now, all the while the cheese is carried, the hand and the cheese keep CARRY_MARGIN from
    the bottle; here `n=20 seed=3`'s episode 10, the bottle 13.3 cm from the plate, beside the way
    (the design since the wine bottle's tasks)."""
    referent = registry.load(SUITE)
    setup = default_setup(referent)
    spec = plan(referent, 20, 3, setup)[10]
    cheese, bottle = spec.task.params["object"], next(o.id for o in spec.objects if o.kind == "wine_bottle")
    assert spec.object(cheese).kind == "cream_cheese" and spec.object(spec.target).kind == "plate"
    scene = scene_for(referent.assets(), setup.profile, SUITE)
    demo = demonstrate(scene, ArmIK(np.asarray(setup.robot_home), setup.world), spec, referent.demo)
    assert demo.success
    gaps = []
    for state in demo.states:
        scene.set_physics_state(state)
        if scene.object_pos(cheese)[2] > spec.object(cheese).pos[2] + 0.02:  # off the table: carried
            gaps.append(scene.hand_gap([scene.data.qpos[scene.arm_qpos]], cheese, [bottle], 0.1))
    print(f"closest the carrying hand came to the bottle: {min(gaps) * 1000:.1f} mm")
    assert len(gaps) > 20 and min(gaps) >= CARRY_MARGIN, f"the hand passed {min(gaps) * 1000:.1f} mm from the bottle"


@pytest.fixture(scope="module")
def goal_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp(SUITE) / "data"
    return make_dataset(root, f"referent={SUITE}", f"n={REPLAYS}", "image_size=64", "seed=1")


@pytest.mark.reference
def test_recorded_actions_succeed_in_liberos_own_environment(goal_dataset: Path, world: worlds.World, tmp_path: Path) -> None:
    """Each episode rebuilt in LIBERO-Goal's own scene from its record (the places on furniture are
    LIBERO's sites, not bodies), its recorded actions stepped there: LIBERO's own check_success()
    (`On(<object>, <place>)`, a site's or an object's) accepts them."""
    results = json.loads(liberos_own("replay", liberos_replay(goal_dataset, world), tmp_path / "replay.json").read_text())
    succeeded = sum(r["success"] for r in results)
    print(f"LIBERO's check_success() accepted {succeeded}/{len(results)}")
    assert len(results) == REPLAYS and succeeded >= 0.9 * REPLAYS, f"LIBERO's check_success() accepted {succeeded}/{REPLAYS}"


@pytest.mark.reference
def test_the_knob_turns_on_with_margin_and_the_hand_keeps_its_path_in_liberos_environment(
    world: worlds.World, tmp_path: Path
) -> None:
    """ "Turn on the stove" replayed in LIBERO's environment: its `TurnOn`, the knob's joint at 0.6 rad or
    more at the end (on from 0.5; 0.526 when the hand turned fast, its fingers slipping), and LIBERO's
    hand on the recorded path (within 1 cm on average; the fast turn's saturated moves sent it 0.5 m off)."""
    from gen.lerobot.reader import LeRobotReader

    root = make_dataset(tmp_path / "knob", f"referent={SUITE}", 'targets=["stove knob"]', "n=2", "image_size=32", "seed=2")
    results = json.loads(liberos_own("replay", liberos_replay(root, world), tmp_path / "replay.json").read_text())
    data = LeRobotReader(root).data
    for episode, replayed in enumerate(results):
        ours = np.stack(data[data.episode_index == episode]["observation.state"].to_numpy())[:, :3]
        gap = np.linalg.norm(ours[1:] - np.asarray(replayed["hand"])[:-1], axis=1)  # LIBERO's hand after each action
        knob = replayed["joints"]["flat_stove_1_button"]
        print(f"episode {episode}: knob {knob:.3f} rad, hand {gap.mean() * 100:.1f} cm from its path on average")
        assert replayed["success"] and knob >= 0.6 and gap.mean() < 0.01, (knob, gap.mean())


def test_a_libero_goal_dataset_loads_and_the_audit_finds_no_leak(goal_dataset: Path) -> None:
    ds = LeRobotDataset(f"local/{SUITE}", root=goal_dataset)
    assert ds.meta.total_episodes == REPLAYS
    audit = json.loads((goal_dataset / "meta/audit.json").read_text())["written"]
    assert not audit["leaks"], audit["verdict"]
    instructions = scenes.read(goal_dataset)["instruction"].tolist()
    assert any("stove" in i for i in instructions) and any("cabinet" in i for i in instructions)


@pytest.mark.reference
def test_the_canonical_exam_is_liberos_covered_tasks(shared: Shared) -> None:
    """The exam holds all ten of LIBERO-Goal's tasks, on LIBERO's own states; the oracle completes
    them and obeys the swaps (the same object, another place; the other drawer), the remembered
    layout (`position`) completes them and obeys none; `nothing` scores 0."""
    referent = registry.load(SUITE)
    assert [libero.language(t) for t in covered(referent, worlds.world(SUITE))] == [
        "open the middle drawer of the cabinet",
        "put the bowl on the stove",
        "put the wine bottle on top of the cabinet",
        "open the top drawer and put the bowl inside",
        "put the bowl on top of the cabinet",
        "push the plate to the front of the stove",
        "put the cream cheese in the bowl",
        "turn on the stove",
        "put the bowl on the plate",
        "put the wine bottle on the rack",
    ]
    reports = canonical_reports(shared, {"oracle": 10, "position": 4, "nothing": 1}, SUITE)  # nothing runs to the horizon
    faces = {policy: report["faces"] for policy, report in reports.items()}
    assert faces["oracle"]["task"]["k"] >= 9 and faces["oracle"]["obeyed_name"]["rate"] >= 0.7, faces["oracle"]
    assert faces["position"]["task"]["k"] >= 3 and faces["position"]["obeyed_name"]["k"] == 0  # it does the remembered task
    assert all(f["k"] == 0 for f in faces["nothing"].values())


@pytest.mark.reference
def test_the_verb_axis_in_liberos_scene_replays_in_liberos_own_environment(tmp_path: Path, world: worlds.World) -> None:
    """`referent=verb world=libero_goal`: the bowl or the cream cheese picked up or pushed, the verb
    alone saying which. LIBERO has no predicate for either program, so each episode's recorded
    actions are stepped in LIBERO-Goal's own scene and our predicate judges where LIBERO's
    simulation leaves the objects; the swap changes only the verb."""
    root = make_dataset(tmp_path / "verb", "referent=verb", "world=libero_goal", f"n={REPLAYS}", "image_size=32", "seed=1")
    request = liberos_replay(root, world)
    results = json.loads(liberos_own("replay", request, tmp_path / "replay.json").read_text())
    records = scenes.read(root)
    done = 0
    for record, result in zip(records.itertuples(), results):
        spec, instance = EpisodeSpec.from_json(record.spec), {o["id"]: o["instance"] for o in json.loads(record.scene)["objects"]}
        start = {o.id: o.pos for o in spec.objects}
        end = {o.id: next(tuple(p) for name, *p in result["objects"] if name == instance[o.id]) for o in spec.objects}
        done += succeeded(spec, Outcome(start, end, (0.0, 0.0, 0.0)))
        (swap,) = spec.counterfactuals
        assert swap.target == spec.target and swap.program != spec.task.program, swap
    print(f"in LIBERO's simulation our predicate accepts {done}/{len(results)}")
    assert done >= 0.9 * REPLAYS, f"{done}/{REPLAYS}"


def test_on_displaced_objects_the_remembered_layout_fails(tmp_path: Path) -> None:
    """LIBERO-Goal's shortcut: reaching for where LIBERO's one layout stands things. On LIBERO's
    own states it does the task (above); on a deconfounded exam of carrying, every object
    displaced, it mostly carries the wrong thing or to the wrong place. (Asked to open a drawer or
    turn the stove on it does it in any scene: only the swap to the other drawer finds it out.)"""
    carrying = "targets=[plate,stove,cabinet,bowl]"  # the furniture's motions it does anyway: the furniture never moves
    root = make_dataset(
        tmp_path / "exam", f"referent={SUITE}", "n=12", "split=exam", "image_size=32", "seed=3", "switches=0", carrying
    )
    exam = read(root)
    tasks = rows_of(exam, ["task"])  # the face read below
    report, _ = take(exam, tasks, make("position"), tmp_path / "position", policy_name="position", baseline=False)
    assert report["faces"]["task"]["rate"] <= 0.4, report["faces"]["task"]
