"""Worlds: where episodes happen. A world is the arena (a table, LIBERO's floor), the robot on
its mount, the cameras, the object models a scene can hold, and where objects rest; the
success predicates read its objects' geometry (core/success.py).

One module per world (`core/worlds/<name>.py`), each holding plain data: the episode spec names
its world (`Setup.world`), referents plan within the world's objects and regions, the
oracle builds the world's scene from this description (oracle/scene.py), and the writer, exam
and battery never ask which world it is. `native` is this project's own scene; the LIBERO
worlds are LIBERO's scenes as its BDDL problems define them, built from LIBERO's assets
(core/libero.py).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.catalog import Kind
from core.rotations import quat_matrix

PHYSICS_DT = 0.002  # simulation timestep, seconds; control periods are whole multiples of it
MAX_IMAGE_SIZE = 1024  # largest square frame a renderer may ask for


class UnknownWorld(ValueError):
    """A world name no module defines; the message names the known ones."""


class WorldUnavailable(RuntimeError):
    """A world whose assets are not installed; the message says how to install them."""


def _numbered(kind: str, i: int) -> str:
    return f"{kind}{i}"


def _ready() -> None:
    """Nothing to install."""


@dataclass(frozen=True)
class Camera:
    """A fixed camera's pose in the world frame: an orientation (MuJoCo's convention: it looks
    along its -z), or a point it looks at with the world's z up."""

    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] | None = None  # w, x, y, z
    lookat: tuple[float, float, float] | None = None
    fovy: float = 45.0

    def rotation(self) -> np.ndarray:
        """The camera's axes in the world frame, as the columns of a 3x3 matrix (x right, y up,
        looking along -z)."""
        if self.lookat is not None:
            z = -np.subtract(self.lookat, self.pos)
            z /= np.linalg.norm(z)
            x = np.cross([0.0, 0.0, 1.0], z)
            x /= np.linalg.norm(x)
            return np.stack([x, np.cross(z, x), z], axis=1)
        if self.quat is None:
            raise ValueError("a camera needs a quat or a lookat")
        return quat_matrix(self.quat)

    def project(self, points: np.ndarray, size: int, mirrored: bool = False) -> np.ndarray:
        """World points (n, 3) -> where they appear in this camera's upright square frame of
        `size` pixels, (n, 2) as (column, row) in pixels from the top-left corner; `mirrored` for
        frames stored mirrored left to right (core/profiles.py). What teaches a policy where, in its
        picture, the named object stands (train/fit.py)."""
        local = (np.asarray(points, float) - self.pos) @ self.rotation()
        focal = size / 2 / np.tan(np.radians(self.fovy) / 2)
        column = size / 2 + focal * local[:, 0] / -local[:, 2]
        row = size / 2 - focal * local[:, 1] / -local[:, 2]
        return np.stack([size - column if mirrored else column, row], axis=1)


@dataclass(frozen=True)
class Fixture:
    """Furniture a world's scenes stand on or beside (a cabinet, a stove): a model file (under the
    world's assets), no free joint; `joints` are its inner ones (drawers, a knob), by their names in
    the model file. `mirror` names a drawn box whose top LIBERO renders as a mirror (reflectance):
    our fast settings draw no reflections, so the scene builder lays a plate over it that looks,
    from the fixed agentview camera, as that mirror does (oracle/scene.py)."""

    kind: str
    xml: str
    joints: tuple[str, ...] = ()
    mirror: str = ""


@dataclass(frozen=True)
class Placed:
    """A fixture where a world puts it: its model name (LIBERO's instance name), its body's
    position and its turn about z."""

    fixture: Fixture
    name: str
    pos: tuple[float, float, float]
    yaw: float = 0.0


@dataclass(frozen=True)
class World:
    """Everything that makes one family of scenes, as data.

    `builder` names how oracle/scene.py assembles the model (`table`: robosuite's table arena,
    this project's native scenes; `libero`: LIBERO's scene files and object models). `park`
    spots hold the bodies a scene compiles but an episode does not use: out of every camera's
    view and out of the contact solver. `profiles` are the profiles (core/profiles.py) the
    world can be recorded in, the first being its default.
    """

    name: str
    kinds: Mapping[str, Kind]
    surface_z: float  # the height objects rest on (table top, floor)
    reach: tuple[float, float, float, float]  # x min, x max, y min, y max where an object may stand
    robot_base: tuple[float, float, float]
    robot_home: tuple[float, ...]  # arm joints at the start of an episode
    finger_home: float  # finger joint opening at the start of an episode, metres
    finger_target: float  # the finger actuators' target then (robosuite's gripper at rest: half open)
    profiles: tuple[str, ...]
    agentview: Camera
    park: tuple[tuple[float, float], ...]  # (x, y) spots for the bodies an episode does not use
    park_z: float  # the surface they rest on there (under the table, under the floor)
    builder: str
    mount: str | None = "RethinkMount"  # robosuite mount under the robot (None: none, the robot stands on the floor)
    integrator: str = "implicitfast"
    arena: Mapping[str, str] = field(default_factory=dict)  # builder-specific: scene file, floor and wall styles
    table: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None  # a table arena's (size, top centre)
    # the table's sliding, torsional and rolling friction: LIBERO's BDDL table arena sets 0.6; its kitchen table keeps 1
    table_friction: tuple[float, float, float] = (0.6, 0.005, 0.0001)
    fixtures: tuple[Placed, ...] = ()  # furniture in every scene of the world, never moved
    suite: str = ""  # the LIBERO benchmark suite whose BDDL problems lay the world's scenes out
    # LIBERO's scenes the world stands, by the start of their tasks' names, where one suite's tasks span
    # several worlds (LIBERO-10's kitchens, living room and study: `standing`)
    scenes: tuple[str, ...] = ()
    # the LIBERO-PRO suite whose layout of `scenes` this world stands, where that suite moves the
    # furniture ('' for LIBERO's own): its canonical exam only, never the scene's world (`standing`)
    pro_suite: str = ""
    robot_faces: int = 2000  # the robot's visual meshes are decimated to this many triangles each (oracle/meshes.py)
    episode_steps: int = 0  # the steps an evaluation of the suite allows (lerobot's LIBERO env), after its settle steps
    body_name: Callable[[str, int], str] = _numbered  # the model's name for the i-th (from 0) body of a kind
    requires: Callable[[], None] = _ready  # raises WorldUnavailable when the world's assets are missing

    def stands(self, task: str) -> bool:
        """Whether a task of the world's suite is set in this world (every one, unless `scenes` says which)."""
        return not self.scenes or task.startswith(self.scenes)

    def kind(self, name: str) -> Kind:
        try:
            return self.kinds[name]
        except KeyError:
            raise KeyError(f"unknown object kind {name!r} in world {self.name}; known: {', '.join(sorted(self.kinds))}") from None


HERE = Path(__file__).parent
FIRST = "native"  # this project's own scene, listed first


def names() -> list[str]:
    """Every world: one module of data each in this folder (adding a world is adding its module)."""
    return sorted((p.stem for p in HERE.glob("*.py") if p.stem != "__init__"), key=lambda n: (n != FIRST, n))


def _worlds() -> dict[str, World]:
    """The worlds by name, each module imported by its name (this package's `__init__` imports none
    of them: they import it)."""
    return {name: importlib.import_module(f"{__name__}.{name}").WORLD for name in names()}


def world(name: str) -> World:
    """The world called `name`, or UnknownWorld naming the known ones."""
    worlds = _worlds()
    try:
        return worlds[name]
    except KeyError:
        raise UnknownWorld(f"unknown world {name!r}; known: {', '.join(worlds)}") from None


def standing(task: str) -> World:
    """The world that stands a LIBERO task's scene, where a world says which scenes it stands (`scenes`)."""
    found = [w for w in _worlds().values() if w.scenes and not w.pro_suite and w.stands(task)] if task else []
    if len(found) != 1:
        raise UnknownWorld(f"{len(found) or 'no'} world(s) stand the scene of task {task!r}")
    return found[0]


def kind(name: str, world_name: str = "native") -> Kind:
    """The object kind `name` of a world (a KeyError names the world's kinds)."""
    return world(world_name).kind(name)
