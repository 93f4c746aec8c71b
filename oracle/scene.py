"""Episode spec -> MuJoCo scene: robosuite's Panda, table arena and objects.

A model is compiled once per asset inventory (the spec's `assets`) and every episode re-poses
it through the simulator state: objects in the episode are moved onto the table, the rest are
parked under it, out of every camera's view and out of the contact solver. The arm's torque
motors become joint-position servos with gravity compensation, so an action is exactly what a
joint-position controller executes: seven joint targets and a gripper command (-1 open,
+1 closed).
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache

import mujoco
import numpy as np

from core import catalog, world
from core.layout import AGENTVIEW, NATIVE
from core.spec import EpisodeSpec, SceneObject
from oracle import meshes

# robosuite logs warnings about optional extras at import; they say nothing about our use.
logging.getLogger("robosuite_logs").addFilter(lambda record: record.levelno >= logging.ERROR)

from robosuite.models import objects as rs_objects  # noqa: E402
from robosuite.models.arenas import TableArena  # noqa: E402
from robosuite.models.bases import robot_base_factory  # noqa: E402
from robosuite.models.grippers import gripper_factory  # noqa: E402
from robosuite.models.robots import Panda  # noqa: E402
from robosuite.models.tasks import ManipulationTask  # noqa: E402
from robosuite.models.world import MujocoWorldBase  # noqa: E402

ARM_JOINTS = tuple(f"robot0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("gripper0_finger_joint1", "gripper0_finger_joint2")
EE_SITE = "gripper0_grip_site"
FINGER_OPEN = 0.04  # finger joint travel, metres

# Joint-position servo gains (N m / rad, N m s / rad), joints 1..7.
SERVO_KP = (1500.0, 1500.0, 1500.0, 1500.0, 600.0, 400.0, 200.0)
SERVO_KV = (120.0, 120.0, 120.0, 120.0, 40.0, 25.0, 12.0)


def _robot():
    robot = Panda(idn=0)
    robot.add_base(robot_base_factory("RethinkMount", idn=0))
    robot.add_gripper(gripper_factory("PandaGripper", idn=0))
    robot.set_base_xpos(world.ROBOT_BASE)
    return robot


def _build_object(kind: catalog.Kind, name: str) -> rs_objects.MujocoObject:
    return getattr(rs_objects, kind.model)(name, **kind.params)


def _lookat_quat(pos: tuple[float, ...], target: tuple[float, ...]) -> np.ndarray:
    forward = np.subtract(target, pos)
    z = -forward / np.linalg.norm(forward)  # MuJoCo cameras look along their -z axis
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    rot = np.stack([x, np.cross(z, x), z], axis=1)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rot.flatten())
    return quat


def _servo_and_gravcomp(root: ET.Element) -> None:
    """Arm torque motors -> position servos (torque limits kept); gravity-compensate the robot."""
    for i, motor in enumerate(root.find("actuator").findall("motor")):  # type: ignore[union-attr]
        torque = motor.attrib.pop("ctrlrange")
        motor.tag = "position"
        motor.set("ctrllimited", "false")
        motor.set("forcelimited", "true")
        motor.set("forcerange", torque)
        motor.set("kp", str(SERVO_KP[i]))
        motor.set("kv", str(SERVO_KV[i]))
    for body in root.iter("body"):
        if body.get("name", "").startswith(("robot0_", "gripper0_")):
            body.set("gravcomp", "1")


def _configure(root: ET.Element) -> None:
    option = root.find("option")
    assert option is not None
    option.set("integrator", "implicitfast")
    option.set("timestep", str(world.PHYSICS_DT))
    visual = root.find("visual")
    if visual is None:
        visual = ET.SubElement(root, "visual")
    quality = visual.find("quality")
    if quality is None:
        quality = ET.SubElement(visual, "quality")
    quality.set("offsamples", "0")  # no MSAA: the CPU rasteriser's main cost (README)
    glob = visual.find("global")
    if glob is None:
        glob = ET.SubElement(visual, "global")
    glob.set("offwidth", str(world.MAX_IMAGE_SIZE))
    glob.set("offheight", str(world.MAX_IMAGE_SIZE))
    for cam in root.iter("camera"):
        if cam.get("name") == NATIVE.cameras[AGENTVIEW]:
            cam.set("pos", " ".join(map(str, world.AGENTVIEW_POS)))
            cam.set("quat", " ".join(f"{v:.6f}" for v in _lookat_quat(world.AGENTVIEW_POS, world.AGENTVIEW_LOOKAT)))
            cam.set("fovy", str(world.AGENTVIEW_FOVY))


def scene_xml(assets: tuple[tuple[str, int], ...]) -> str:
    """The MJCF of a scene holding `count` bodies of each catalog kind."""
    arena = TableArena(table_full_size=world.TABLE_SIZE, table_offset=(0, 0, world.TABLE_TOP_Z))
    objects = [_build_object(catalog.kind(kind), f"{kind}{i}") for kind, count in sorted(assets) for i in range(count)]
    task = ManipulationTask(mujoco_arena=arena, mujoco_robots=[_robot()], mujoco_objects=objects)
    root = ET.fromstring(task.get_xml())
    _servo_and_gravcomp(root)
    _configure(root)
    meshes.lighten(root)
    return ET.tostring(root, encoding="unicode")


def robot_xml() -> str:
    """The robot alone, at the same base pose: the IK model."""
    arena_free = MujocoWorldBase()
    arena_free.merge(_robot())
    return arena_free.get_xml()


@dataclass
class Body:
    """One object body in the compiled model."""

    kind: catalog.Kind
    body_id: int
    qpos_adr: int
    geom_ids: tuple[int, ...]
    park: np.ndarray  # free-joint qpos when not in the episode
    collision: tuple[tuple[int, int], ...]  # compiled (contype, conaffinity) of each geom


class Scene:
    """A compiled scene that episodes re-pose by state, never by re-parsing."""

    def __init__(self, assets: tuple[tuple[str, int], ...]) -> None:
        self.assets = tuple(sorted(assets))
        self.model = mujoco.MjModel.from_xml_string(scene_xml(self.assets))
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.arm_qpos = np.array([m.joint(j).qposadr[0] for j in ARM_JOINTS])
        self.finger_qpos = np.array([m.joint(j).qposadr[0] for j in FINGER_JOINTS])
        self.ee_site = m.site(EE_SITE).id
        self.substeps = 1  # set per spec from its fps
        self.bodies: dict[str, list[Body]] = {}
        spots = [(x, y) for x in world.PARK_X for y in world.PARK_Y]
        index = 0
        for kind_name, count in self.assets:
            kind = catalog.kind(kind_name)
            for i in range(count):
                name = f"{kind_name}{i}"
                joint = m.joint(f"{name}_joint0")
                body_id = int(m.jnt_bodyid[joint.id])
                geoms = tuple(g for g in range(m.ngeom) if m.geom_bodyid[g] == body_id)
                x, y = spots[index % len(spots)]
                park = np.array([x, y, kind.rest_z(0.0) + 0.001 * (index // len(spots)), 1, 0, 0, 0])
                collision = tuple((int(m.geom_contype[g]), int(m.geom_conaffinity[g])) for g in geoms)
                body = Body(kind, body_id, joint.qposadr[0], geoms, park, collision)
                self.bodies.setdefault(kind_name, []).append(body)
                index += 1
        if index > len(spots):
            raise ValueError(f"scene holds {index} objects but only {len(spots)} parking spots")
        self.placed: dict[str, Body] = {}

    def reset(self, spec: EpisodeSpec) -> None:
        """Put the robot at home and the episode's objects at their poses; park the rest."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        self.substeps = int(round(1.0 / (spec.sim.fps * m.opt.timestep)))
        home = np.asarray(spec.sim.robot_home)
        d.qpos[self.arm_qpos] = home
        d.qpos[self.finger_qpos] = (FINGER_OPEN, -FINGER_OPEN)
        d.ctrl[:7] = home
        d.ctrl[7:9] = (FINGER_OPEN, -FINGER_OPEN)
        free = {kind: list(bodies) for kind, bodies in self.bodies.items()}
        self.placed = {}
        for obj in spec.objects:
            if not free.get(obj.kind):
                raise ValueError(f"episode {spec.index} needs another {obj.kind!r} but the scene holds {self.assets}")
            body = free[obj.kind].pop(0)
            self.placed[obj.id] = body
            self._pose(body, obj)
            self._park(body, False)
        for bodies in free.values():
            for body in bodies:
                d.qpos[body.qpos_adr : body.qpos_adr + 7] = body.park
                self._park(body, True)
        mujoco.mj_forward(m, d)

    def _park(self, body: Body, parked: bool) -> None:
        """A parked body floats where it is (gravity-compensated) and touches nothing, so it
        costs the contact solver nothing; a placed one gets its compiled collisions back."""
        m = self.model
        m.body_gravcomp[body.body_id] = 1.0 if parked else 0.0
        for g, (contype, conaffinity) in zip(body.geom_ids, body.collision):
            m.geom_contype[g] = 0 if parked else contype
            m.geom_conaffinity[g] = 0 if parked else conaffinity

    def _pose(self, body: Body, obj: SceneObject) -> None:
        half = obj.yaw / 2
        self.data.qpos[body.qpos_adr : body.qpos_adr + 7] = (*obj.pos, np.cos(half), 0.0, 0.0, np.sin(half))
        if body.kind.colorable:
            rgba = catalog.COLORS[obj.attributes.get("color", "white")]
            for g in body.geom_ids:
                self.model.geom_rgba[g] = rgba

    def step(self, action: np.ndarray) -> None:
        """Execute one control period: joint targets and gripper command held for `substeps`."""
        d = self.data
        d.ctrl[:7] = action[:7]
        opening = FINGER_OPEN * (1.0 - float(np.clip(action[7], -1.0, 1.0))) / 2.0
        d.ctrl[7:9] = (opening, -opening)
        mujoco.mj_step(self.model, d, nstep=self.substeps)

    def state(self) -> np.ndarray:
        """observation.state: joint positions, finger positions, end-effector pose (xyz, wxyz)."""
        d = self.data
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, d.site_xmat[self.ee_site])
        return np.concatenate([d.qpos[self.arm_qpos], d.qpos[self.finger_qpos], d.site_xpos[self.ee_site], quat])

    def ee_pos(self) -> np.ndarray:
        return self.data.site_xpos[self.ee_site].copy()

    def object_pos(self, object_id: str) -> np.ndarray:
        return self.data.xpos[self.placed[object_id].body_id].copy()

    def positions(self) -> dict[str, tuple[float, float, float]]:
        """Where every object of the episode is now."""
        return {k: tuple(float(v) for v in self.data.xpos[b.body_id]) for k, b in self.placed.items()}  # type: ignore[misc]

    def object_yaw(self, object_id: str) -> float:
        mat = self.data.xmat[self.placed[object_id].body_id].reshape(3, 3)
        return float(np.arctan2(mat[1, 0], mat[0, 0]))

    def physics_state(self) -> np.ndarray:
        """The full physics state (mjSTATE_INTEGRATION): what an exam stores to restart a trial."""
        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        state = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, state, spec)
        return state

    def set_physics_state(self, state: np.ndarray) -> None:
        mujoco.mj_setState(self.model, self.data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(self.model, self.data)


@lru_cache(maxsize=4)
def scene_for(assets: tuple[tuple[str, int], ...]) -> Scene:
    """One compiled scene per inventory and process."""
    return Scene(assets)
