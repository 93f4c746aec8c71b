"""Helpers shared by the tests (importable because pytest puts tests/ on the path)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict
from pathlib import Path

import mujoco
import numpy as np
import pandas as pd

from core import libero, programs, worlds
from core.exam import FACES, Exam, read
from core.profiles import LIBERO, NATIVE
from core.spec import FAST, EpisodeSpec, SceneObject, Setup
from core.worlds import World
from eval.sims.libero import fixture_poses, in_liberos
from eval.sims.libero_env.reference import named, object_differences  # the same readout in the tests and the pictures in docs/
from gen.config import parse
from gen.planning.plan import world_setup
from gen.products.canonical import CanonicalOptions, load_state, suite_of
from gen.products.run import generate
from jobs.lock import held
from oracle.render import Cameras
from oracle.scene import Scene, scene_for

ROOT = Path(__file__).resolve().parent.parent

LIBERO_PYTHON = ROOT / ".venv-libero" / "bin" / "python"
# LIBERO's initial states per task the picture tests compare (each a render in LIBERO's env and in
# ours): 2 in `make test`; the figures in docs/, over the first 5, with LIBERO_PICTURE_STATES=5.
PICTURE_STATES = int(os.environ.get("LIBERO_PICTURE_STATES", "2"))
# LIBERO's initial states per task each world's canonical-exam test builds: the first 10 (drawn with
# the exam's seed) in `make test`; all 50 (every state of the suite loads) with LIBERO_CANONICAL_STATES=50.
CANONICAL_STATES = int(os.environ.get("LIBERO_CANONICAL_STATES", "10"))
# Episodes each LIBERO world's replay test generates and replays in LIBERO's environment (one may
# fail): 10 in `make test`; the figures in docs/ are over 20 (LIBERO_REPLAYS=20).
REPLAYS = int(os.environ.get("LIBERO_REPLAYS", "10"))
FRAME_BOUND = 4.0  # mean absolute difference (of 255) of a whole frame from LIBERO's
OBJECT_BOUND = 12.0  # ... and inside each object's and fixture's own pixels (a whole frame's mean hides one drawn wrong)


class Pictures:
    """The picture tests' figures against LIBERO's own frames, worst over the states compared: per
    camera, the whole frame's mean absolute difference, and each object's and fixture's inside its
    own pixels (eval/sims/libero_env/reference.py's `object_differences`)."""

    def __init__(self) -> None:
        self.frame = dict.fromkeys(LIBERO.cameras, 0.0)
        self.things: dict[tuple[str, str], tuple[float, str]] = {}  # (camera, name) -> worst figure, where

    def compare(self, cameras: Cameras, theirs: Mapping[str, np.ndarray], key: str, where: str) -> None:
        """Our cameras' frames now against LIBERO's under `key` (`<task>-<state>` of its `render`
        output, `<episode>` of its `scenes`; turned 180 degrees); `where` names the case in failures."""
        frames, labels = cameras.render(), cameras.labels()
        for camera, model_camera in LIBERO.cameras.items():
            reference = theirs[f"{key}-{model_camera}"][::-1, ::-1]
            their_labels = named(theirs[f"{key}-{model_camera}-labels"][::-1, ::-1], theirs[f"{key}-things"])
            whole = float(np.abs(frames[camera].astype(int) - reference.astype(int)).mean())
            self.frame[camera] = max(self.frame[camera], whole)
            for name, figure in object_differences(frames[camera], reference, labels[camera], their_labels).items():
                if figure > self.things.get((camera, name), (-1.0, ""))[0]:
                    self.things[(camera, name)] = (figure, where)

    def worst(self, camera: str, n: int = 3) -> list[tuple[str, float, str]]:
        """The `n` objects or fixtures farthest from LIBERO's look in `camera`: (name, figure, where)."""
        rows = [(name, figure, where) for (cam, name), (figure, where) in self.things.items() if cam == camera]
        return sorted(rows, key=lambda row: -row[1])[:n]

    def check(self, bounds: Mapping[str, float] | None = None) -> None:
        """Every whole frame within FRAME_BOUND, every object and fixture within OBJECT_BOUND, or
        its kind's own bound in `bounds` (LIBERO's category: `akita_black_bowl` for
        `akita_black_bowl_2`) where our fast rendering cannot reach it (docs/LIBERO.md); a failure names
        the thing farthest over its bound."""
        for camera in LIBERO.cameras:
            worst = ", ".join(f"{name} {figure:.1f} ({where})" for name, figure, where in self.worst(camera))
            print(f"{camera}: frame {self.frame[camera]:.2f}/255; worst objects {worst}")
        assert max(self.frame.values()) <= FRAME_BOUND, f"mean absolute difference per camera (of 255): {self.frame}"
        over = [
            (figure - (bounds or {}).get(name.rsplit("_", 1)[0], OBJECT_BOUND), name, camera, figure, where)
            for (camera, name), (figure, where) in self.things.items()
        ]
        excess, name, camera, figure, where = max(over)
        assert excess <= 0, f"{name} in {camera} at {where}: {figure:.1f}/255 inside its pixels, {excess:.1f} over its bound"


def _load_by_name(
    scene: Scene, suite: str, problem: libero.Problem, state: int, setup: Setup, inventory: tuple[tuple[str, int], ...]
) -> list[str]:
    """Our scene in a LIBERO task's initial state with no design of it: each object under its LIBERO
    instance name, every joint set by name from LIBERO's state vector; returns the objects' ids."""
    objects = tuple(SceneObject(instance, kind, kind, 0, (0.0, 0.0, 1.0)) for instance, kind in problem.objects.items())
    scene.reset(EpisodeSpec("", 0, 0, objects, objects[0].id, "", "", (), inventory, setup=setup))
    scene.set_joints(*libero.split_state(libero.initial_states(suite, problem.name)[state], problem))
    return [o.id for o in objects]


_LIBEROS_RENDERS: dict[str, Path] = {}  # request -> LIBERO's frames of it: each look is compared with one render


def initial_state_pictures(
    suite: str,
    cases: list[tuple[int, int]],
    tmp_path: Path,
    look: str = FAST,
    joints: dict[str, float] | None = None,
    world: str | None = None,
) -> tuple[Pictures, float]:
    """Our frames, drawn with `look`, against LIBERO's own render at LIBERO's initial states of a
    suite (LIBERO's or LIBERO-PRO's): `cases` are (task number in the suite's order, state); the
    fixtures posed as LIBERO drew them for each, their `joints` (name -> value) set in both. With a
    `world`, the scenes are that world's and every task's objects are loaded by name (a suite whose
    canonical exam is not ours yet: LIBERO-10's scenes). Returns the pictures' figures and the
    farthest any object stands from where LIBERO puts it (m)."""
    chosen = None if world else suite_of(CanonicalOptions(suite=suite))
    names = list(libero.tasks(suite))
    problem = chosen.problem if chosen else (lambda task: libero.problem(suite, task))
    if chosen:
        the_world, inventory = chosen.world, chosen.inventory()
    else:
        most: Counter[str] = Counter()
        for t, _ in cases:  # every kind the tasks place, as many as any task places
            most |= Counter(problem(names[t]).objects.values())
        the_world, inventory = worlds.world(world), tuple(sorted(most.items()))
    request = {"suite": suite, "size": LIBERO.image_size, "cases": [list(c) for c in cases], "tasks": names}
    request |= {"joints": joints} if joints else {}
    key = json.dumps(request, sort_keys=True)
    if key not in _LIBEROS_RENDERS:
        _LIBEROS_RENDERS[key] = liberos_own("render", request, tmp_path / f"{suite}.npz")
    theirs = np.load(_LIBEROS_RENDERS[key], allow_pickle=True)
    setup = world_setup(the_world, look=look)
    scene = scene_for(inventory, setup.profile, the_world.name, look)
    cameras, m = Cameras(scene, LIBERO.image_size, LIBERO.camera_names), scene.model
    kept = {f.name: (m.body(f"{f.name}_main").id,) for f in the_world.fixtures}
    kept = {name: (b, m.body_pos[b].copy(), m.body_quat[b].copy()) for name, (b,) in kept.items()}
    pictures, farthest = Pictures(), 0.0
    try:
        for t, s in cases:
            for name, *pose in theirs[f"{t}-{s}-fixtures"].tolist():  # LIBERO draws its fixtures anew at each reset
                body = m.body(f"{name}_main").id
                m.body_pos[body], m.body_quat[body] = pose[:3], pose[3:]
            if chosen and names[t] in chosen.tasks:
                ids = [o.id for o in load_state(scene, chosen, names[t], s, setup).objects]
            else:  # a task our skills cannot do (LIBERO-Goal's wine bottle's), or of no exam yet: objects by LIBERO's names
                ids = _load_by_name(scene, suite, problem(names[t]), s, setup, inventory)
            if joints:
                scene.set_joints({j: np.array([v]) for j, v in joints.items()}, {j: np.zeros(1) for j in joints})
            pictures.compare(cameras, theirs, f"{t}-{s}", f"{suite} task {t} state {s}")
            ours = {instance: scene.object_pos(i) for i, instance in zip(ids, problem(names[t]).objects)}
            for instance, *pos in theirs[f"{t}-{s}-objects"]:
                farthest = max(farthest, float(np.abs(ours[instance] - np.asarray(pos, float)).max()))
    finally:
        for body, pos, quat in kept.values():
            m.body_pos[body], m.body_quat[body] = pos, quat
        cameras.close()
    print(f"{suite}: farthest object {farthest * 1000:.3f} mm")
    return pictures, farthest


# robosuite 1.5 calls the mount's bodies fixed_mount0_*; robosuite 1.4's empty mount0_base and the
# cameras no recorded frame comes from are left out of the physics compared
NOT_COMPARED = ("mount0_base", "frontview", "birdview", "sideview", "galleryview", "robotview", "canonical_agentview")
NOT_COMPARED += ("paperview",)  # LIBERO's kitchen, living room and study problems add it


def same_physics(theirs: Mapping[str, np.ndarray], ours: Mapping[str, np.ndarray], fixtures: Iterable[str]) -> list[str]:
    """Assert that every array of LIBERO's compiled scene (eval/sims/libero_env/reference.py
    `model_arrays`) has its twin in ours with the same values, the poses of the `fixtures` (their
    instance names) aside: LIBERO draws them anew at each reset, within their regions. Returns the
    names compared."""
    moved = tuple(f"{name}_main" for name in fixtures)
    compared = [
        k
        for k in theirs
        if not k.endswith(NOT_COMPARED) and not (k.startswith(("body_pos", "body_quat", "body_ipos")) and k.endswith(moved))
    ]
    named_ = {k: k.replace(":mount0_", ":fixed_mount0_") for k in compared}
    missing = [k for k in compared if named_[k] not in ours]
    assert not missing, f"LIBERO's scene has what ours does not: {missing[:5]}"
    differ = [k for k in compared if not np.allclose(ours[named_[k]], theirs[k], rtol=1e-5, atol=1e-6)]
    assert not differ, {k: (theirs[k].tolist(), ours[named_[k]].tolist()) for k in differ[:5]}
    return compared


def liberos_own(command: str, request: dict, out: Path) -> Path:
    """Run a command of eval/sims/libero_env/reference.py in LIBERO's own environment (`.venv-libero`)."""
    assert LIBERO_PYTHON.is_file(), f"{LIBERO_PYTHON} is missing: `make setup` builds LIBERO's reference environment"
    request_file = out.with_name(out.name + ".request.json")
    request_file.write_text(json.dumps(request))
    done = subprocess.run(
        in_liberos("reference", command, str(request_file), str(out)),
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return out


# The 2-trial exams at 32 px (seed 5) that several files read, each as `shared.dataset(f"{referent}-exam",
# f"referent={referent}", *SMALL_EXAM)`: one product per referent in a run.
SMALL_EXAM = ("n=2", "split=exam", "seed=5", "image_size=32", "workers=1")
# The one-trial exam of the object type, at 32 px (`shared.dataset("exam", *ONE_TRIAL)`) and at 64 px
# (`shared.dataset("exam", *ONE_TRIAL_64)`), that tests only read or take.
ONE_TRIAL = ("n=1", "split=exam", "image_size=32")
ONE_TRIAL_64 = ("n=1", "split=exam", "image_size=64")


class Shared:
    """Products built once per pytest run and shared by every test that reads the same one, on
    either of xdist's workers: each is built under `root` (one folder per run, seen by both
    workers) in a folder named by its recipe (what builds it), under a file lock, so a worker that
    asks for a product the other is building waits for it and reuses it. Tests only read a shared
    product; one that changes its product builds its own."""

    def __init__(self, root: Path) -> None:
        self.root = root

    def product(self, recipe: Sequence[str], build: Callable[[Path], object]) -> Path:
        """The folder holding the product of `recipe`, made by `build(folder)` the first time any worker asks."""
        name = hashlib.sha256(json.dumps(list(recipe)).encode()).hexdigest()[:16]
        folder, done = self.root / name, self.root / f"{name}.done"
        with held(self.root / f"{name}.lock"):
            if not done.exists():
                shutil.rmtree(folder, ignore_errors=True)  # what a failed build left
                folder.mkdir(parents=True)
                build(folder)
                done.write_text(json.dumps(list(recipe)))
        return folder

    def dataset(self, name: str, *overrides: str) -> Path:
        """The dataset or exam the CLI's `overrides` generate (make_dataset), in any order, in a folder called `name`."""
        return self.product(("gen", name, *sorted(overrides)), lambda folder: make_dataset(folder / name, *overrides)) / name

    def canonical(self, world: str = "libero_object") -> Path:
        """`world`'s canonical exam (gen.canonical) on the first of LIBERO's initial states of each task, at
        32 px, without switch rows (the switch face has its own tests)."""
        from gen.products.canonical import CanonicalOptions, build

        def made(folder: Path) -> None:
            build(CanonicalOptions(world=world, states=1, image_size=32, out=str(folder / "canonical"), switches=0))

        return self.product(("gen.canonical", world, "states=1", "image_size=32", "switches=0"), made) / "canonical"

    def take(self, exam: Path, policy: str, trials: int, faces: Sequence[str] = ()) -> dict:
        """`policy`'s report on the first `trials` trials of a shared exam, their rows of `faces` (default
        every row), with no shortcut baseline."""
        from eval.policies.registry import make
        from eval.scoring.battery import take

        def taken(folder: Path) -> None:
            whole = read(exam)
            rows = rows_of(whole, faces or FACES, trials)
            take(whole, rows, make(policy), folder / "take", workers=2, policy_name=policy, baseline=False)

        folder = self.product(("take", str(exam), policy, f"trials={trials}", *sorted(faces)), taken)
        return json.loads((folder / "take" / "report.json").read_text())


def rows_of(exam: Exam, faces: Iterable[str], trials: int | None = None) -> pd.DataFrame:
    """The exam's rows of `faces` (of its first `trials` trials): what a take needs where a test reads only
    those faces of its report. A trial's rows share one initial state, so its init-value check loses nothing."""
    rows = exam.trials[exam.trials["face"].isin(list(faces))]
    return rows if trials is None else rows[rows["trial"] < trials]


def canonical_reports(shared: Shared, trials: dict[str, int], world: str = "libero_object") -> dict[str, dict]:
    """The shared canonical exam of `world` (Shared.canonical), each policy taken on its first
    `trials[policy]` trials: the policies' reports. The tests read `nothing`'s every face and only
    the task and swap faces of the others, which take only those rows (rows_of)."""
    exam = shared.canonical(world)
    return {policy: shared.take(exam, policy, n, () if policy == "nothing" else ("task", "swap")) for policy, n in trials.items()}


def _contained(instance: dict[str, str], goal: EpisodeSpec) -> list[str]:
    """A goal carrying a thing into a container, as LIBERO's BDDL says it."""
    return ["In", instance[goal.target], f"{instance[goal.task.params['destination']]}_contain_region"]


def _holding(world: World, instances: set[str]) -> str:
    """A task of the world's scenes whose scene holds every instance (LIBERO-10's living room:
    LIVING_ROOM_SCENE2, its seven groceries and the basket)."""
    suite = world.suite
    return next(t for t in libero.tasks(suite) if world.stands(t) and instances <= set(libero.problem(suite, t).objects))


def liberos_replay(dataset: Path, world: World) -> dict:
    """A dataset's episodes as eval/sims/libero_env/reference.py's `replay` takes them, rebuilt from
    their records alone: LIBERO's instance names (a place on furniture: its site's), poses, robot
    joints and recorded actions; `target` is what moves and `container` where it goes. A world
    with fixtures replays in its suite's own scene, the fixtures where the records stand them. A
    dataset mixing worlds (gen/planning/mix.py) gives the episodes of `world`."""
    from core.profiles import ACTION_KEY
    from gen.lerobot.reader import LeRobotReader
    from gen.products import scenes

    reader, sites = LeRobotReader(dataset), {k.name: k.anchor for k in world.kinds.values() if k.is_site}
    records = scenes.read(dataset)
    if "world" in records:
        records = records[records["world"] == world.name]
    episodes = []
    for record in records.itertuples():
        final = EpisodeSpec.from_json(record.spec).after_switch()  # a switched episode is judged by its second ask
        scene, task, target = json.loads(record.scene), asdict(final.task), final.target
        params = task["params"]
        instance = {o["id"]: sites.get(o["kind"], o["instance"]) for o in scene["objects"]}
        kinds = {o["id"]: o["kind"] for o in scene["objects"]}
        moved, goal = (params.get("object"), target) if "destination" not in params else (target, params["destination"])
        rows = reader.data[reader.data.episode_index == record.episode_index]
        episode = {
            "objects": [
                {k: o[k] for k in ("instance", "kind", "pos", "quat")} for o in scene["objects"] if o["kind"] not in sites
            ],
            "target": instance[moved] if moved else None,
            "container": instance[goal],
            "arm": scene["robot"]["arm"],
            "fingers": scene["robot"]["fingers"],
            "actions": np.stack(rows[ACTION_KEY].to_numpy()).astype(float).tolist(),
        }
        if world.scenes:  # a world of LIBERO-10's: every goal, as LIBERO's In of the container judges it
            episode["goals"] = [_contained(instance, g) for g in final.goals()]
        own = programs.named(task["program"]).libero
        if own is not None:  # a motion of LIBERO-Goal's (a drawer, the knob, a push)
            place = libero.place_name(world.kind(kinds[goal]), instance[goal])
            episode["goal"] = libero.goal(own, place, instance[moved] if moved else None)
        elif moved is None and "destination" not in params:  # pick, push: LIBERO has none; judged by positions
            episode["goal"] = ["Up", instance[goal]]
        episodes.append(episode)
    if world.scenes:
        held = {o["instance"] for e in episodes for o in e["objects"]}
        return {"suite": world.suite, "task": _holding(world, held), "episodes": episodes}
    if not world.fixtures:
        return {"episodes": episodes}
    fixtures = {tuple(pose) for r in records.scene for pose in fixture_poses(json.loads(r))}
    assert len(fixtures) == len(world.fixtures), "every record names every fixture, at one pose"
    return {"suite": world.suite, "fixtures": [list(f) for f in sorted(fixtures)], "episodes": episodes}


def make_dataset(out: Path, *overrides: str) -> Path:
    """Generate a dataset through the real CLI config and pipeline, in this process unless `overrides`
    name workers: the test processes already keep every core busy, and a worker pool's start (imports,
    scenes compiled again) costs a small set more than its episodes (test_dataset: the same bytes)."""
    # Before this process makes a GL context: triton, which a later training here loads (the text
    # tower's transformers), crashes (SIGSEGV) after one (train/stages.py generate_once).
    import torch._dynamo  # noqa: F401

    workers = () if any(o.startswith("workers=") for o in overrides) else ("workers=1",)
    generate(parse([f"out={out}", *workers, *overrides]), progress=False)
    return out


def body_image(scene: Scene, camera: str, size: int = 128) -> np.ndarray:
    """The body id seen at each pixel of an upright render of `camera` (-1: none; collision geoms hidden)."""
    renderer = mujoco.Renderer(scene.model, size, size)
    renderer.enable_segmentation_rendering()
    option = mujoco.MjvOption()
    option.geomgroup[0] = False
    renderer.update_scene(scene.data, camera=NATIVE.cameras[camera], scene_option=option)
    seg = renderer.render()
    renderer.close()
    is_geom = seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM
    return np.where(is_geom, scene.model.geom_bodyid[np.where(is_geom, seg[..., 0], 0)], -1)


def visible_bodies(scene: Scene, camera: str, size: int = 128) -> dict[int, int]:
    """Pixels per body id in a segmentation render of `camera`."""
    image = body_image(scene, camera, size)
    bodies, counts = np.unique(image[image >= 0], return_counts=True)
    return dict(zip(bodies.tolist(), counts.tolist()))


# Runs `python -m <module> <args>` with Ctrl-C delivered as a terminal delivers it (a test runner's
# worker may ignore SIGINT, and a child inherits that), set in the child itself: a preexec_fn would
# make subprocess fork the whole worker, which a worker holding gigabytes can fail to (ENOMEM).
_WITH_SIGINT = (
    "import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "sys.argv = sys.argv[1:]; runpy.run_module(sys.argv[0], run_name='__main__', alter_sys=True)"
)


def interruptible(module: str, *args: str) -> list[str]:
    """The command line of `python -m module args` that Ctrl-C interrupts."""
    return [sys.executable, "-c", _WITH_SIGINT, module, *args]


def lerobot_train(out: Path, dataset: Path, **policy: object) -> Path:
    """`lerobot-train` offline on CPU for 2 steps; the pretrained_model folder it saves."""
    args = {
        "dataset.repo_id": f"local/{dataset.name}",
        "dataset.root": dataset,
        **{f"policy.{k}": v for k, v in policy.items()},
        "policy.device": "cpu",
        "policy.push_to_hub": "false",
        "steps": 2,
        "batch_size": 2,
        "num_workers": 0,
        "save_freq": 2,
        "eval_freq": 0,
        "wandb.enable": "false",
        "output_dir": out,
    }
    env = {**os.environ, "HF_HUB_OFFLINE": "1"}
    train = [str(Path(sys.executable).parent / "lerobot-train"), *(f"--{k}={v}" for k, v in args.items())]
    peft = ["--peft.method_type=LORA", "--peft.r=8", '--peft.target_modules=["linear1","linear2"]'] if "path" in policy else []
    done = subprocess.run([*train, *peft], capture_output=True, text=True, env=env, cwd=out.parent)
    assert done.returncode == 0, done.stderr[-3000:]
    return out / "checkpoints" / "000002" / "pretrained_model"
