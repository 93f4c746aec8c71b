"""Our generator against the naive path and against the render-only floor, on the same episodes.

    python bench/compare.py [n=50] ['sizes=[10,50,200]'] [referent=object]
    python bench/compare.py world=libero_object [n=10]
    python bench/compare.py world=libero_spatial referent=color [n=10]

(a) ours: `python -m gen` (plan, oracle demos, render from the recorded states, per-episode
    encoding, LeRobot files), with 1 worker and with the machine's cores;
(b) naive: robosuite's camera observations through `env.step` (Panda, Lift scene, 2 cameras at
    128 px) and lerobot's own `LeRobotDataset.create/add_frame/save_episode/finalize`, for the
    same number of frames per episode;
(c) floor: only rendering the same frames (2 cameras, same settings) from (a)'s recorded states.

Prints seconds per episode, the ratios (b)/(a) and (a)/(c), per-worker peak memory, and how (a)'s
wall time grows with n.

With a LIBERO world (`world=libero_object`, or libero_spatial, libero_goal) it compares, side by
side in one run, (a) ours in that world's scenes (its own LIBERO type, or `referent=` another axis
it carries, 2 cameras at 256 px, 1 worker) with (d) LIBERO's own path to the same number of frames
per episode: LIBERO's `OffScreenRenderEnv.step` in the suite's first task, with both cameras'
observations at 256 px (in LIBERO's own environment, `.venv-libero`, through
eval/sims/libero_env/reference.py), the frames then written by lerobot's `LeRobotDataset` writer.
"""

from __future__ import annotations

import os
import re
import resource
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import oracle  # noqa: F401  (headless-rendering defaults)
from core import parquet, worlds
from core.profiles import ACTION_KEY, LIBERO, NATIVE, STATE_KEY
from core.spec import EpisodeSpec
from eval.sims.libero import PYTHON, in_liberos
from gen.config import parse
from gen.products import scenes
from gen.products.run import generate
from jobs.cli import UserError, main
from referents import registry

ROOT = Path(__file__).resolve().parent.parent


def ours(n: int, workers: int, referent: str, root: Path, size: int = 128, world: str | None = None) -> tuple[float, Path]:
    out = root / f"ours-{n}-{workers}-{time.perf_counter_ns()}"
    where = [f"world={world}"] if world else []
    start = time.perf_counter()
    options = [f"referent={referent}", *where, f"n={n}", f"workers={workers}", f"out={out}", f"image_size={size}"]
    generate(parse(options), progress=False)
    return time.perf_counter() - start, out


def liberos_own(lengths: list[int], size: int, root: Path, LeRobotDataset: type, suite: str) -> tuple[float, float]:  # noqa: N803
    """LIBERO's own path to the frames: its environment stepped with camera observations (seconds,
    measured in LIBERO's environment), then lerobot's writer on those frames (seconds)."""
    import json
    import subprocess

    request, frames = root / "libero-bench.json", root / "libero-bench.npz"
    request.write_text(json.dumps({"suite": suite, "task": 0, "size": size, "lengths": lengths}))
    if not PYTHON.is_file():
        raise UserError(f"{PYTHON} is missing: `make setup` builds LIBERO's reference environment")
    done = subprocess.run(
        in_liberos("reference", "bench", str(request), str(frames)),
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    if done.returncode and not frames.is_file():  # (its EGL teardown may complain after the frames are saved)
        lines = done.stderr.strip().splitlines() or ["no message"]
        first = next((line for line in lines if re.match(r"[\w.]+(Error|Exception)\b", line)), lines[-1])
        raise UserError(f"LIBERO's environment failed: {first}")
    recorded = np.load(frames)
    stepping = float(recorded["seconds_per_step"]) * sum(lengths)
    cameras = {feature: recorded[camera] for feature, camera in LIBERO.cameras.items()}
    features = {
        **{
            LIBERO.image_key(c): {"dtype": "video", "shape": (size, size, 3), "names": ["height", "width", "channels"]}
            for c in cameras
        },
        STATE_KEY: {"dtype": "float32", "shape": (LIBERO.state_size,), "names": None},
        ACTION_KEY: {"dtype": "float32", "shape": (LIBERO.action_size,), "names": None},
    }
    start = time.perf_counter()
    ds = LeRobotDataset.create("bench/libero", fps=20, features=features, root=root / "libero", use_videos=True)
    t = 0
    for length in lengths:
        for _ in range(length):
            ds.add_frame(
                {
                    **{LIBERO.image_key(c): frames[t][::-1, ::-1] for c, frames in cameras.items()},
                    STATE_KEY: np.zeros(LIBERO.state_size, np.float32),
                    ACTION_KEY: np.zeros(LIBERO.action_size, np.float32),
                    "task": "a LIBERO task",
                }
            )
            t += 1
        ds.save_episode()
    ds.finalize()
    return stepping, time.perf_counter() - start


def floor(dataset: Path) -> float:
    """Render every recorded frame of the dataset's episodes again, nothing else."""
    from oracle.episode import demonstrate
    from oracle.ik import ArmIK
    from oracle.render import Cameras
    from oracle.scene import scene_for
    from referents.registry import demo_of

    specs = [EpisodeSpec.from_json(s) for s in scenes.read(dataset)["spec"]]
    scene = scene_for(specs[0].assets)
    ik = ArmIK(np.asarray(specs[0].setup.robot_home))
    states = [demonstrate(scene, ik, s, demo_of(s.referent)).states for s in specs]  # not timed
    cams = Cameras(scene, 128, NATIVE.camera_names)
    start = time.perf_counter()
    for spec, episode in zip(specs, states):
        scene.reset(spec)
        for state in episode:
            scene.set_physics_state(state)
            cams.render()
    elapsed = time.perf_counter() - start
    cams.close()
    return elapsed


def naive(lengths: list[int], root: Path, LeRobotDataset: type) -> float:  # noqa: N803
    """robosuite env.step with camera observations + lerobot's own writer."""
    import robosuite as suite

    env = suite.make(
        "Lift",
        robots="Panda",
        has_renderer=False,
        has_offscreen_renderer=True,
        use_camera_obs=True,
        camera_names=list(NATIVE.cameras.values()),
        camera_heights=128,
        camera_widths=128,
        control_freq=20,
    )
    features = {
        **{
            NATIVE.image_key(c): {"dtype": "video", "shape": (128, 128, 3), "names": ["height", "width", "channels"]}
            for c in NATIVE.cameras
        },
        STATE_KEY: {"dtype": "float32", "shape": (NATIVE.state_size,), "names": None},
        ACTION_KEY: {"dtype": "float32", "shape": (env.action_dim,), "names": None},
    }
    start = time.perf_counter()
    ds = LeRobotDataset.create("bench/naive", fps=20, features=features, root=root / "naive", use_videos=True)
    for length in lengths:
        obs = env.reset()
        for _ in range(length):
            action = np.zeros(env.action_dim, np.float32)
            ds.add_frame(
                {
                    **{NATIVE.image_key(c): obs[f"{model}_image"] for c, model in NATIVE.cameras.items()},
                    STATE_KEY: np.concatenate(
                        [obs["robot0_joint_pos"], obs["robot0_gripper_qpos"], obs["robot0_eef_pos"], obs["robot0_eef_quat"]]
                    ).astype(np.float32),
                    ACTION_KEY: action,
                    "task": "pick up the cube",
                }
            )
            obs, *_ = env.step(action)
        ds.save_episode()
    ds.finalize()
    env.close()
    return time.perf_counter() - start


@dataclass
class CompareOptions:
    n: int = 50  # episodes for (a), (b) and (c)
    sizes: list[int] = field(default_factory=lambda: [10, 50, 200])  # values of n to time (a) at with every core
    referent: str | None = None  # a referent type the world carries (default: object natively, a LIBERO world's own type)
    world: str = "native"  # native, or a LIBERO world: ours in its scenes against LIBERO's own path


def compare(options: CompareOptions) -> None:
    if min(options.sizes, default=1) < 1:
        raise UserError(f"sizes must be positive numbers of episodes, got {options.sizes}")
    # Before any GL context exists: torchvision, which lerobot's writer imports, loads triton, which
    # crashes (SIGSEGV) in a process that has already made an EGL context. Imported here, not at the
    # top, so that the generator's worker processes (which re-import this module) stay lean.
    from ledataset.datasets.lerobot_dataset import LeRobotDataset

    if options.world != "native":
        return compare_libero(options, LeRobotDataset)
    n, referent = options.n, options.referent or "object"
    cores = os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        a1, dataset = ours(n, 1, referent, root)
        a_all, _ = ours(n, cores, referent, root)
        child_rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        lengths = [int(x) for x in parquet.read(dataset / "meta/episodes")["length"]]
        frames = sum(lengths)
        c = floor(dataset)
        b = naive(lengths, root, LeRobotDataset)
        main_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"{n} {referent} episodes, {frames} frames, 2 cameras at 128 px, {cores} cores")
        print(f"(a) ours, 1 worker      {a1 / n:7.3f} s/episode  {frames / a1:6.1f} frames/s")
        print(f"(a) ours, {cores} workers     {a_all / n:7.3f} s/episode  {frames / a_all:6.1f} frames/s")
        print(f"(b) naive (robosuite + lerobot writer) {b / n:7.3f} s/episode  {frames / b:6.1f} frames/s")
        print(f"(c) render-only floor   {c / n:7.3f} s/episode  {frames / c:6.1f} frames/s")
        print(f"(b)/(a): {b / a1:.2f} with 1 worker, {b / a_all:.2f} with {cores}")
        print(f"(a)/(c): {a1 / c:.3f} (1 process each)")
        print(f"peak RSS: worker processes {child_rss:.0f} MB (max over workers), this process {main_rss:.0f} MB")
        for size in options.sizes:
            seconds, _ = ours(size, cores, referent, root)
            print(f"n={size:<4} ours with {cores} workers: {seconds:7.1f} s wall, {seconds / size:.2f} s/episode")


def compare_libero(options: CompareOptions, LeRobotDataset: type) -> None:  # noqa: N803
    try:
        world = worlds.world(options.world)
    except worlds.UnknownWorld as exc:
        raise UserError(str(exc)) from None
    if not world.suite:
        raise UserError(f"world must be native or a LIBERO world, got {options.world!r}")
    referent = options.referent or registry.of_world(world.name)[0]
    n, size = options.n, LIBERO.image_size
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        a, dataset = ours(n, 1, referent, root, size, world.name)
        lengths = [int(x) for x in parquet.read(dataset / "meta/episodes")["length"]]
        stepping, writing = liberos_own(lengths, size, root, LeRobotDataset, world.suite)
        d, frames = stepping + writing, sum(lengths)
        per = frames / n
        print(f"{n} {referent} episodes in {world.name}, {frames} frames ({per:.1f}/episode), 2 cameras at {size} px, 1 worker")
        print(f"(a) ours ({referent}, world={world.name})  {a / n:7.3f} s/episode  {frames / a:6.1f} frames/s")
        print(f"(d) LIBERO's own path           {d / n:7.3f} s/episode  {frames / d:6.1f} frames/s")
        step_ms, write_ms = stepping / frames * 1000, writing / frames * 1000
        print(f"    OffScreenRenderEnv.step {step_ms:.0f} ms/step, lerobot's writer {write_ms:.0f} ms/frame")
        print(f"(d)/(a): {d / a:.1f}")


if __name__ == "__main__":
    sys.exit(main("python bench/compare.py", CompareOptions, compare, doc=__doc__))
