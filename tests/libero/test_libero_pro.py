"""LIBERO-PRO's perturbed suites as canonical exams (`python -m gen.canonical suite=<name>`): the
suite's own initial states and objects in our LIBERO worlds, the perturbed instruction delivered
(LIBERO-PRO writes it only in each BDDL file's `(:language)` line, under the base task's file
name), checked against LIBERO's own render of the suite, and the reference policies' signature
across suites (`python -m eval.suites`). The figures in docs/ come from the commands they list."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core import libero, worlds
from core.exam import read
from core.spec import FAST, FULL
from eval.policies.registry import make
from eval.scoring.battery import take
from gen.planning.plan import world_setup
from gen.products.canonical import CanonicalOptions, build, suite_of, suites_of, trial_spec
from helpers import initial_state_pictures, rows_of
from jobs.cli import UserError
from referents import registry

BASES = ("libero_object", "libero_spatial", "libero_goal")
EVERY = bool(os.environ.get("LIBERO_PRO_ALL"))  # the figures in docs/: every covered suite and task
# One suite of each kind of perturbation, for the pictures: moved, recoloured and resized, added, shifted.
SAMPLED = (
    "libero_object_swap", "libero_object_object", "libero_object_with_mug", "libero_object_with_yellow_book",
    "libero_object_temp_x0.3", "libero_spatial_object", "libero_spatial_with_milk", "libero_goal_with_yellow_book",
)  # fmt: skip
# ... and in the full look, which draws everything within helpers.OBJECT_BOUND: the suites the fast look
# draws farthest from LIBERO's (the stove under the swapped bowls; the bigger bowl close to the wrist camera)
FULL_SAMPLED = ("libero_spatial_swap", "libero_goal_object")
TASKS_PICTURED = 10 if EVERY else 2
# Things the fast look cannot bring within helpers.OBJECT_BOUND (docs/LIBERO.md "Each object and fixture as
# LIBERO draws it"): the woven baskets, the mirror stove top and the bowls close to the wrist camera.
OWN_BOUNDS = {"basket": 28.0, "red_basket": 28.0, "flat_stove": 40.0, "akita_black_bowl": 21.0, "black_bowl": 21.0}


def _covered() -> list[str]:
    names = []
    for base in BASES:
        for name in libero.suites(base):
            try:
                suite_of(CanonicalOptions(suite=name))
                names.append(name)
            except UserError:
                continue
    return names


@pytest.mark.parametrize("kind", ["_lan", "_task"])
def test_the_perturbed_instruction_is_delivered(kind: str) -> None:
    """For every covered `_lan` and `_task` suite, each task row's instruction is the BDDL file's
    `(:language)` line, and differs from what LIBERO's benchmark reads from the file name."""
    suites = [name for name in _covered() if name.endswith(kind)]
    assert len(suites) >= 2, suites
    for name in suites:
        suite = suite_of(CanonicalOptions(suite=name))
        for task in suite.tasks:
            spec = trial_spec(suite, task, 0, 0, world_setup(suite.world))
            assert spec.instruction == suite.problem(task).language, (name, task)
            assert spec.instruction.lower() != libero.language(task).lower(), (name, task)


@pytest.mark.parametrize("kind", ["_lan", "_task"])
def test_each_swap_changes_only_the_name_in_the_delivered_instruction(kind: str) -> None:
    """A swap is the task row's own words with what names the target changed (the suite's wording
    kept, not LIBERO's file-name template), or it is left out, saying why; in a `_task` suite no swap
    names the base task's own target, where the layout alone leads a policy that ignores the words."""
    import os.path

    articles = {"the", "a", "an"}
    kept = 0
    for name in [n for n in _covered() if n.endswith(kind)]:
        suite = suite_of(CanonicalOptions(suite=name))
        for task in suite.tasks:
            spec = trial_spec(suite, task, 0, 0, world_setup(suite.world))
            base = libero.problem(suite.world.suite, libero.base_task(name, task))
            for cf in spec.counterfactuals:
                said, swapped = spec.instruction.split(), cf.instruction.split()
                head = len(os.path.commonprefix([said, swapped]))
                tail = len(os.path.commonprefix([said[head:][::-1], swapped[head:][::-1]]))
                old, new = set(said[head : len(said) - tail]), set(swapped[head : len(swapped) - tail])
                assert old <= set(cf.changed[0].split()) | articles, (name, task, spec.instruction, cf.instruction)
                assert new <= set(cf.changed[1].split()) | articles, (name, task, spec.instruction, cf.instruction)
                assert kind != "_task" or cf.target not in (base.goal[0][1], base.objects[base.goal[0][1]]), (name, task, cf)
                kept += 1
            design = suite.referent.code.canonical(suite.referent.config, suite.problem(task))
            left = suite.swaps(task, design, spec.instruction)[1]
            assert len(left) + len(spec.counterfactuals) == len(design.counterfactuals)
            assert all(reason for reason in left.values())
    assert kept > 0


def test_suites_that_change_no_words_deliver_the_base_tasks_instruction() -> None:
    """A suite that moves, recolours or adds objects keeps the base task's words (LIBERO's file-name
    instruction, what LIBERO-trained policies were trained on)."""
    for name in ("libero_object_swap", "libero_object_object", "libero_object_with_mug", "libero_spatial_with_milk"):
        suite = suite_of(CanonicalOptions(suite=name))
        for task in suite.tasks:
            spec = trial_spec(suite, task, 0, 0, world_setup(suite.world))
            assert spec.instruction == libero.language(libero.base_task(name, task)), (name, task)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["suite=libero_object_upside_down"], "unknown suite 'libero_object_upside_down'; LIBERO's and LIBERO-PRO's suites"),
        (["suite=libero_object_with_red_box"], "no model of red_box is installed"),
        (["suite=libero_goal_task"], "our skills cannot do it"),
        (["suite=libero_object_swap", "world=libero_spatial"], "suite=libero_object_swap perturbs libero_object"),
        (["suite=libero_spatial_with_milk", "states=11"], "states must be between 1 and 10"),
        (["suite=libero_10_lan", "world=libero_10_kitchen_scene6_swap"], "suite=libero_10_swap only"),
    ],
)
def test_bad_suites_are_refused_in_one_line(argv: list[str], needle: str, tmp_path: Path) -> None:
    out = tmp_path / "exam"
    done = subprocess.run([sys.executable, "-m", "gen.canonical", *argv, f"out={out}"], capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and needle in lines[0], done.stderr
    assert not out.exists()


@pytest.mark.reference
def test_every_covered_suites_initial_states_load_and_its_tasks_are_recorded(tmp_path: Path) -> None:
    """Every covered suite builds its exam from its own initial states (one per task here), and
    exam.json says, per task, the BDDL file, its language line, the file-name instruction and the
    one delivered."""
    covered = _covered()
    assert len(covered) >= 20, covered
    for name in covered:
        options = CanonicalOptions(suite=name, states=1, image_size=32, out=str(tmp_path / name), switches=0)  # no oracle runs
        build(options)
        meta = read(tmp_path / name).meta["canonical"]
        assert meta["suite"] == name and set(meta["tasks"]) == set(meta["states"])
        for task, record in meta["tasks"].items():
            assert record["bddl"] == f"bddl_files/{name}/{task}.bddl"
            assert record["file_name_instruction"] == libero.language(task)
            assert record["language_line"] == libero.problem(name, task).language


def test_a_task_whose_fixtures_the_suite_moves_is_left_out_saying_so() -> None:
    """libero_goal_swap stands the stove where the cream cheese stood (and the cheese on the stove's
    place): our scenes keep LIBERO's fixtures where its own suite stands them, so the task is left out."""
    left = suite_of(CanonicalOptions(suite="libero_goal_swap")).left_out
    assert "LIBERO-PRO moves its flat_stove_1" in left["put_the_cream_cheese_in_the_bowl"]
    unmoved = suite_of(CanonicalOptions(suite="libero_goal_with_mug"))  # its fixtures stand as LIBERO's: every task kept
    assert len(unmoved.tasks) == len(libero.tasks("libero_goal_with_mug")) and not unmoved.left_out


def test_a_scene_whose_furniture_the_suite_moves_is_stood_by_its_twin_world() -> None:
    """libero_10_swap trades KITCHEN_SCENE6's microwave and white mug: the suite's exam stands that scene in
    its twin world (`World.pro_suite`), the microwave at the centre of the region PRO's BDDL file names for
    it and the places in it moved as far, so the suite covers 8 of its 10 tasks; LIBERO-10's own exam, and
    every world lookup by task, keep the scene's own world."""
    task = "KITCHEN_SCENE6_put_the_yellow_and_white_mug_in_the_microwave_and_close_it"
    suites, left = suites_of(CanonicalOptions(suite="libero_10_swap"))
    assert sum(len(s.tasks) for s in suites) >= 8 and task not in left
    twin = next(s.world for s in suites if task in s.tasks)
    own = worlds.standing(task)
    assert (twin.name, twin.pro_suite, own.name) == (
        "libero_10_kitchen_scene6_swap",
        "libero_10_swap",
        "libero_10_kitchen_scene6",
    )
    assert next(s.world for s in suites_of(CanonicalOptions(world="libero_10"))[0] if task in s.tasks) == own
    problem, moved = libero.problem("libero_10_swap", task), {}
    for placed, before in zip(twin.fixtures, own.fixtures):
        assert np.allclose(placed.pos[:2], problem.centre(problem.region_of(placed.name)), atol=1e-9), placed.name
        moved[placed.name] = np.subtract(placed.pos, before.pos)
    theirs, ours = (registry.load("libero_10", world=w.name).config for w in (own, twin))
    for place, slot in theirs.extra["sites"].items():  # the places in it: its inside and its door
        was, now = theirs.layout.slots[slot], ours.layout.slots[ours.extra["sites"][place]]
        assert np.allclose(np.subtract(now, was), moved["microwave_1"]), (place, was, now)


def test_no_swap_names_an_object_the_suite_parked_off_the_scene(tmp_path: Path) -> None:
    """LIBERO-PRO's shifted layouts park a grocery metres away (x = 10 m in libero_object_temp_x0.3):
    no policy could fetch it, so no swap row names it."""
    suite = "libero_object_temp_x0.3"
    build(CanonicalOptions(suite=suite, states=1, image_size=32, out=str(tmp_path / "e"), tasks=3, switches=0))
    trials = read(tmp_path / "e").trials
    parked = 0
    for _, row in trials[trials["face"] == "swap"].iterrows():
        where = {o["id"]: o["pos"] for o in json.loads(row["spec"])["objects"]}
        parked += sum(abs(x) > 1 for x, *_ in where.values())
        assert abs(where[row["target"]][0]) < 1, f"a swap names {row['target']}, parked at {where[row['target']]}"
    assert parked, "the suite no longer parks a grocery: pick a suite that does"


@pytest.mark.parametrize(
    ("name", "look"),
    [(name, FAST) for name in (_covered() if EVERY else SAMPLED)]
    + [(name, FULL) for name in (_covered() if EVERY else FULL_SAMPLED)],
)
@pytest.mark.reference
def test_the_same_pictures_and_poses_as_liberos_own_render_of_the_suite(name: str, look: str, tmp_path: Path) -> None:
    """The first state of the suite's first tasks (its added, moved and recoloured objects
    included): both cameras within 4/255 of LIBERO's own frames, every object and fixture within
    12/255 inside its own pixels (helpers.Pictures; in the fast look, OWN_BOUNDS excepted), every
    object within 1 mm."""
    tasks = suite_of(CanonicalOptions(suite=name)).tasks
    numbers = [libero.tasks(name).index(t) for t in tasks[:TASKS_PICTURED]]
    pictures, farthest = initial_state_pictures(name, [(t, 0) for t in numbers], tmp_path, look)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"


@pytest.mark.parametrize("name", ["libero_object_object", "libero_spatial_object"])
def test_the_oracle_does_the_perturbed_tasks_and_obeys_their_swaps(name: str, tmp_path: Path) -> None:
    """On the suite's own states (the first state of its first two tasks here; the figures in docs/:
    every covered suite, 5 states a task) the oracle does every task row and obeys every swap."""
    build(CanonicalOptions(suite=name, states=1, image_size=32, out=str(tmp_path / name), tasks=2, switches=0))
    exam = read(tmp_path / name)
    rows = rows_of(exam, ["task", "swap"])  # the faces read below
    faces = take(exam, rows, make("oracle"), tmp_path / "oracle", 2, "oracle", baseline=False)[0]["faces"]
    assert faces["task"]["rate"] == 1.0 and faces["obeyed_name"]["rate"] == 1.0, faces


@pytest.mark.reference
def test_one_command_reports_a_row_per_suite(tmp_path: Path) -> None:
    """`python -m eval.suites` refuses an unknown suite in one line before any work."""
    done = subprocess.run(
        [sys.executable, "-m", "eval.suites", "policy=nothing", "suites=[libero_object,libero_nowhere]", f"out={tmp_path}/r"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2 and "unknown suite 'libero_nowhere'" in done.stderr and not (tmp_path / "r").exists()


def test_a_policy_through_several_suites_gets_one_report(tmp_path: Path) -> None:
    """`position`, the layout LIBERO-Object's tasks reward, through two suites in one command: one
    report row per suite, and the blind policy's signature: LIBERO-Object's tasks done and no swap
    obeyed, libero_object_swap's tasks failed (the target no longer stands where it remembers)."""
    out = tmp_path / "report"
    args = ["policy=position", "suites=[libero_object,libero_object_swap]", "states=1", "tasks=1", "image_size=32", "switches=0"]
    done = subprocess.run(
        [sys.executable, "-m", "eval.suites", *args, f"exams={tmp_path / 'exams'}", f"out={out}"], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads((out / "report.json").read_text())
    assert [r["suite"] for r in report["suites"]] == ["libero_object", "libero_object_swap"]
    assert all(r["faces"]["task"]["n"] == 1 for r in report["suites"])
    assert (out / "suites.png").is_file() and "| libero_object_swap |" in (out / "report.md").read_text()
    base, swap = (r["faces"] for r in report["suites"])
    assert base["task"]["rate"] == 1.0 and base["obeyed_name"]["rate"] == 0.0 and base["true_target"]["rate"] == 1.0
    assert swap["task"]["rate"] == 0.0 and base["switch_obeyed"]["n"] == 0  # switches=0: exams without the face


def test_liberos_ten_objects_are_kinds_and_its_pro_tasks_find_their_base() -> None:
    """LIBERO-10's first pieces (issue 53): every object its ten problems name is one of our kinds
    (the moka pots, the frying pan, the mugs and the book measured as the others are: test_scene's
    extents), and every task of LIBERO-PRO's libero_10 suites finds the task it perturbs, the
    added-object suites' renamed files included."""
    named = {kind for task in libero.tasks("libero_10") for kind in libero.problem("libero_10", task).objects.values()}
    assert len(named) > 15 and named <= set(libero.KINDS), sorted(named - set(libero.KINDS))
    perturbed = libero.suites("libero_10")[1:]
    assert {"libero_10_swap", "libero_10_lan", "libero_10_with_mug"} <= set(perturbed)
    for suite in perturbed:
        assert {libero.base_task(suite, task) for task in libero.tasks(suite)} <= set(libero.tasks("libero_10")), suite
