"""LIBERO's own environment, driven from the project's process: the side of `sim=libero` that runs
in `.venv-libero` (LIBERO's code, its robosuite 1.4.0 and its mujoco), started by eval/sims/libero.py
as `.venv-libero/bin/python eval/sims/libero_env/server.py`. It imports numpy and LIBERO only, never the
project, whose packages live in another environment; eval/sims/libero_env/reference.py builds its
reference environments with the same functions.

The protocol is frames on stdin/stdout (`read_frame`/`write_frame`): a JSON header and the raw bytes
of the numpy arrays it lists, so the two sides' numpy versions (1.x here and 2.x there) never
exchange pickles. LIBERO's own prints go to stderr. Requests:

* `open` {key, bddl | bddl_text, size, cameras}: make (or reuse, by `key`) the environment of a BDDL
  problem, LIBERO's `OffScreenRenderEnv`, with its renderer when `cameras` are named (frames of
  `size` px are then drawn with LIBERO's settings by `sim.render`, what its camera observations
  call), and soft resets (the compiled model kept: LIBERO's hard reset would rebuild it and its
  renderer, seconds each).
* `reset` {seed, state | pose, objects, sites, fixtures}: `np.random` seeded (LIBERO draws its
  fixtures' poses at reset), `reset()`, then LIBERO's own initial-state vector (`set_init_state`),
  the fixtures standing where `fixtures` says (where the exam's scene stands them), or a pose from a
  scene record (`pose_from_record`); `objects` and `sites` name what the log follows.
* `step` {action}: one `env.step` (a control step of OSC_POSE at 20 Hz).
* `render`: the cameras' frames, LIBERO's raw ones (upside down, as its renderer gives them).
* `goal` {predicates}: LIBERO's own predicates (`_eval_predicate`) now, and `check_success()`.
Every `reset` and `step` answers with what is needed to log and observe the rollout: the grip
site's position, the hand's quaternion (wxyz), the finger joints, each followed object's and
site's position (or point on a body: `anchored`).
"""

from __future__ import annotations

import json
import os
import struct
import sys
from typing import IO, Any

import numpy as np

# LIBERO-Object's placement regions (its BDDL files' ranges), and the basket's bin
REGIONS = {
    "target_object_region": (-0.145, -0.265, -0.095, -0.215),
    "other_object_region_0": (0.025, -0.125, 0.075, -0.075),
    "other_object_region_1": (-0.175, 0.035, -0.125, 0.085),
    "other_object_region_2": (0.075, -0.225, 0.125, -0.175),
    "other_object_region_3": (0.125, 0.005, 0.175, 0.055),
    "other_object_region_4": (-0.225, -0.105, -0.175, -0.055),
    "bin_region": (-0.01, 0.25, 0.01, 0.27),
}
# floor spots out of reach (and behind the agentview camera) for the objects an episode does not use
PARK = [(1.5 + 0.3 * i, -1.0 + 0.2 * k) for i in range(3) for k in range(12)]
TABLE_PARK = [(0.42 - 0.08 * i, -0.55 + 0.1 * k) for i in range(2) for k in range(12)]  # at the table's far edge


def make_env(bddl: str, size: int, cameras: bool = True, camera_obs: bool | None = None, hard_reset: bool = True) -> Any:
    """LIBERO's `OffScreenRenderEnv` of a BDDL file, seeded and reset: with `cameras` its renderer,
    with `camera_obs` (default: `cameras`) frames in every observation (LIBERO imports only here:
    the module loads anywhere)."""
    from libero.libero.envs import OffScreenRenderEnv

    env = OffScreenRenderEnv(
        bddl_file_name=bddl,
        camera_heights=size,
        camera_widths=size,
        has_offscreen_renderer=cameras,
        use_camera_obs=cameras if camera_obs is None else camera_obs,
        hard_reset=hard_reset,
    )
    env.seed(0)
    env.reset()
    return env


def task_bddl(suite: str, task: int | str) -> tuple[str, np.ndarray]:
    """A task's BDDL file and LIBERO's initial states of it: the task by its number in LIBERO's
    benchmark order, or by name (LIBERO-PRO's suites the benchmark does not list)."""
    from libero.libero import benchmark, get_libero_path

    if isinstance(task, int):
        task = benchmark.get_benchmark_dict()[suite]().get_task(task).name
    with np.load(os.path.join(get_libero_path("init_states"), suite, f"{task}.pruned_init.npz")) as npz:
        states = np.asarray(npz["states"])
    return os.path.join(get_libero_path("bddl_files"), suite, f"{task}.bddl"), states


def positions(env: Any) -> list[list]:
    """[instance, x, y, z] of every object's body."""
    sim = env.sim
    bodies = {name: sim.model.body_name2id(obj.root_body) for name, obj in env.env.objects_dict.items()}
    return [[name, *map(float, sim.data.body_xpos[body])] for name, body in bodies.items()]


def articulations(env: Any) -> dict[str, float]:
    """{joint: position} of the fixtures' own joints (a drawer's slide, the stove knob's hinge)."""
    model, names = env.sim.model, tuple(env.env.fixtures_dict)
    joints = (model.joint_id2name(j) for j in range(model.njnt))
    return {j: float(env.sim.data.qpos[model.get_joint_qpos_addr(j)]) for j in joints if j and j.startswith(names)}


def fixtures(env: Any) -> list[list]:
    """[name, x, y, z, qw, qx, qy, qz] of every fixture body: LIBERO draws their poses anew at each reset."""
    model = env.sim.model
    bodies = {name: model.body_name2id(obj.root_body) for name, obj in env.env.fixtures_dict.items()}
    return [[name, *map(float, model.body_pos[b]), *map(float, model.body_quat[b])] for name, b in bodies.items()]


def _declared(objects: dict[str, str]) -> list[str]:
    """`:objects` lines, one per category with all its instances (`milk_1 milk_2 - milk`): LIBERO's
    parser keeps only the last line of a category."""
    by_kind: dict[str, list[str]] = {}
    for instance, kind in objects.items():
        by_kind.setdefault(kind, []).append(instance)
    return [f"    {' '.join(instances)} - {kind}" for kind, instances in by_kind.items()]


def floor_bddl(objects: dict[str, str], containers: list[str], goal: str) -> str:
    """LIBERO's floor problem holding `objects` (instance -> category), its goal `goal` (e.g.
    `(In milk_1 basket_1_contain_region)`); each object starts in a region of its own
    (LIBERO-Object's, then parking spots), which the initial state then overrides; `containers`
    (LIBERO-Object's basket) stand in the bin region, each with its contain region."""
    regions = list(REGIONS.items()) + [
        (f"park_region_{k}", (x - 0.02, y - 0.02, x + 0.02, y + 0.02)) for k, (x, y) in enumerate(PARK)
    ]
    lines = ["(define (problem LIBERO_Floor_Manipulation)", "  (:domain robosuite)", "  (:language replay)", "  (:regions"]
    lines += [f"    ({name} (:target floor) (:ranges (({x0} {y0} {x1} {y1}))))" for name, (x0, y0, x1, y1) in regions]
    lines += [f"    (contain_region (:target {c}))" for c in containers]
    lines += ["  )", "  (:fixtures floor - floor)", "  (:objects", *_declared(objects), "  )"]
    lines += ["  (:obj_of_interest", *(f"    {i}" for i in objects), "  )", "  (:init"]
    free = [name for name, _ in regions if name != "bin_region"]
    for i, instance in enumerate(objects):
        lines.append(f"    (On {instance} floor_{'bin_region' if instance in containers else free[i]})")
    lines += ["  )", f"  (:goal (And {goal}))", ")"]
    return "\n".join(lines) + "\n"


def table_bddl(suite: str, objects: dict[str, str], goal: str) -> str:
    """A suite's table (its first task's problem: table, fixtures and their regions) holding `objects`
    (instance -> category) instead of that task's, each in a region of its own at the table's far
    edge (the initial state then poses them), and the goal `goal`, e.g. `(On bowl_1 plate_1)`."""
    bddl, _ = task_bddl(suite, 0)
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
    placed_fixtures = {declared[i - 1] for i, word in enumerate(declared) if word == "-"} - {"main_table"}
    init = [line.strip() for line in text[text.index("(:init") :].splitlines() if line.strip().startswith("(On ")]
    init = [line for line in init if line.split()[1] in placed_fixtures]  # where the fixtures stand
    lines = [problem, "  (:objects", *_declared(objects), "  )"]
    lines += ["  (:obj_of_interest", *(f"    {i}" for i in objects), "  )", "  (:init", *(f"    {line}" for line in init)]
    lines += [f"    (On {instance} main_table_park_region_{k})" for k, instance in enumerate(objects)]
    lines += ["  )", f"  (:goal (And {goal}))", ")"]
    return "\n".join(lines) + "\n"


def stand_fixtures(env: Any, fixtures: list[list]) -> None:
    """Stand the fixtures ([name, x, y, z, qw, qx, qy, qz]) where given, not where LIBERO's reset drew them."""
    model = env.sim.model
    for name, *where in fixtures:
        body = model.body_name2id(env.env.fixtures_dict[name].root_body)
        model.body_pos[body], model.body_quat[body] = where[:3], where[3:]


def pose_from_record(env: Any, pose: dict) -> dict:
    """Set LIBERO's environment to a scene record's initial state: the fixtures where `pose["fixtures"]`
    ([name, x, y, z, qw, qx, qy, qz]) stands them, the robot's joints (`arm`, `fingers`), each object
    of `pose["objects"]` ({instance, pos, quat}) at its pose and every other object of the problem
    parked out of reach; returns the observation there."""
    model = env.sim.model
    stand_fixtures(env, pose.get("fixtures", []))
    qpos = np.array(env.sim.data.qpos)
    for j, value in enumerate([*pose["arm"], *pose["fingers"]]):
        qpos[model.get_joint_qpos_addr(model.joint_id2name(j))] = value
    placed = {o["instance"]: o for o in pose["objects"]}
    for k, instance in enumerate(env.env.objects_dict):
        start, end = model.get_joint_qpos_addr(f"{instance}_joint0")
        if instance in placed:
            qpos[start:end] = [*placed[instance]["pos"], *placed[instance]["quat"]]
        else:  # standing as LIBERO's reset put it, far off
            qpos[start : start + 2] = PARK[k]
    return env.set_init_state(np.concatenate([[0.0], qpos, np.zeros(model.nv)]))


# --- the protocol -------------------------------------------------------------------------------


def write_frame(stream: IO[bytes], header: dict, arrays: dict[str, np.ndarray] | None = None) -> None:
    """One message: the header's length, the header (JSON, listing the arrays), the arrays' bytes."""
    arrays = {k: np.ascontiguousarray(v) for k, v in (arrays or {}).items()}
    header = {**header, "arrays": [[k, v.dtype.str, list(v.shape)] for k, v in arrays.items()]}
    head = json.dumps(header).encode()
    stream.write(struct.pack("<Q", len(head)) + head)
    for v in arrays.values():
        stream.write(v.tobytes())
    stream.flush()


def read_frame(stream: IO[bytes]) -> tuple[dict, dict[str, np.ndarray]] | None:
    """The next message (header, arrays), or None at the end of the stream."""
    size = stream.read(8)
    if len(size) < 8:
        return None
    header = json.loads(_exactly(stream, struct.unpack("<Q", size)[0]))
    arrays = {}
    for name, dtype, shape in header.pop("arrays"):
        dt = np.dtype(dtype)
        count = int(np.prod(shape, dtype=np.int64))
        arrays[name] = np.frombuffer(_exactly(stream, count * dt.itemsize), dt).reshape(shape)
    return header, arrays


def _exactly(stream: IO[bytes], n: int) -> bytes:
    data = stream.read(n)
    if len(data) != n:
        raise EOFError(f"the stream ended {n - len(data)} bytes short of a message")
    return data


class Server:
    """The environments of one `sim=libero` worker, one per BDDL problem it was asked to open."""

    def __init__(self) -> None:
        self.envs: dict[str, Any] = {}
        self.env: Any = None
        self.size = 0
        self.cameras: list[str] = []
        self.follow: tuple[list[str], list[str]] = ([], [])

    def open(self, request: dict, arrays: dict) -> tuple[dict, dict]:
        key = request["key"]
        for other in [k for k in self.envs if k != key]:  # a worker's rows come task by task: one environment at a time
            self.envs.pop(other).close()
        if key not in self.envs:
            bddl = request.get("bddl")
            if bddl is None:  # a problem written from a scene record
                import tempfile

                with tempfile.NamedTemporaryFile("w", suffix=".bddl", delete=False) as f:
                    f.write(request["bddl_text"])
                bddl = f.name
            self.envs[key] = make_env(bddl, request["size"], bool(request["cameras"]), camera_obs=False, hard_reset=False)
        self.env, self.size, self.cameras = self.envs[key], request["size"], request["cameras"]
        env = self.env.env
        sites = sorted(env.object_sites_dict) if hasattr(env, "object_sites_dict") else []
        return {"objects": list(env.objects_dict), "fixtures": list(env.fixtures_dict), "sites": sites}, {}

    def reset(self, request: dict, arrays: dict) -> tuple[dict, dict]:
        np.random.seed(request["seed"])
        self.env.reset()
        if "state" in arrays:  # LIBERO's own initial state, its fixtures where the exam stands them
            stand_fixtures(self.env, request.get("fixtures", []))
            self.env.set_init_state(arrays["state"])
        else:
            pose_from_record(self.env, request["pose"])
        self.follow = (request["objects"], request["sites"])
        return self._now()

    def step(self, request: dict, arrays: dict) -> tuple[dict, dict]:
        self.env.step(arrays["action"].astype(np.float64))
        return self._now()

    def render(self, request: dict, arrays: dict) -> tuple[dict, dict]:
        """The cameras' frames now, drawn as LIBERO's camera observations draw them."""
        sim = self.env.sim
        return {}, {cam: sim.render(camera_name=cam, width=self.size, height=self.size) for cam in self.cameras}

    def goal(self, request: dict, arrays: dict) -> tuple[dict, dict]:
        env = self.env.env
        return {
            "predicates": [bool(env._eval_predicate([p[0].lower(), *p[1:]])) for p in request["predicates"]],
            "check_success": bool(self.env.check_success()),
        }, {}

    def _now(self) -> tuple[dict, dict]:
        """Where things are, read after refreshing MuJoCo's derived positions (robosuite's step leaves
        them one substep behind the state, which our recordings never are)."""
        sim = self.env.sim
        sim.forward()
        model, data = sim.model, sim.data
        objects, sites = self.follow
        fingers = [model.get_joint_qpos_addr(j) for j in ("gripper0_finger_joint1", "gripper0_finger_joint2")]
        out = {
            "ee": np.array(data.site_xpos[model.site_name2id("gripper0_grip_site")]),
            "hand_quat": np.array(data.body_xquat[model.body_name2id("robot0_right_hand")]),
            "fingers": np.array(data.qpos[fingers]),
            "objects": np.array(
                [data.body_xpos[model.body_name2id(self.env.env.objects_dict[o].root_body)] for o in objects]
                + [anchored(model, data, s) for s in sites]
            ).reshape(-1, 3),
            "quats": np.array(
                [data.body_xquat[model.body_name2id(self.env.env.objects_dict[o].root_body)] for o in objects]
            ).reshape(-1, 4),
        }
        return {}, out


def anchored(model: Any, data: Any, anchor: str) -> np.ndarray:
    """Where a place is: a site's position, or for `<body>@<x>,<y>,<z>` that point of the body's frame
    (a point on the stove's knob, which LIBERO's model marks with no site)."""
    if "@" not in anchor:
        return np.array(data.site_xpos[model.site_name2id(anchor)])
    body, offset = anchor.split("@")
    b = model.body_name2id(body)
    return data.body_xpos[b] + data.body_xmat[b].reshape(3, 3) @ np.array([float(v) for v in offset.split(",")])


def serve(stdin: IO[bytes], stdout: IO[bytes]) -> None:
    server = Server()
    while (message := read_frame(stdin)) is not None:
        request, arrays = message
        try:
            header, out = getattr(server, request["op"])(request, arrays)
            write_frame(stdout, {"ok": True, **header}, out)
        except Exception as exc:  # reported to the caller, who names the row it broke
            write_frame(stdout, {"ok": False, "error": f"{type(exc).__name__}: {exc}"})


if __name__ == "__main__":
    protocol = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # LIBERO prints; only frames go to the caller
    serve(sys.stdin.buffer, protocol)
