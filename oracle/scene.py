"""Episode spec -> MuJoCo scene: robosuite's Panda, table arena and objects.

A model is compiled once per asset inventory (the spec's `assets`) and profile, and every
episode re-poses it through the simulator state: objects in the episode are moved onto the
table, the rest are parked under it, out of every camera's view and out of the contact solver.
The profile's controller (oracle/drives.py) decides what an action does: in the native profile
the arm's torque motors become joint-position servos with gravity compensation, so an action is
seven joint targets and a gripper command (-1 open, +1 closed); in the libero profile they stay
torque motors, driven by robosuite's operational-space controller from end-effector deltas.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache

import mujoco
import numpy as np

from core import catalog, world
from core.layout import AGENTVIEW, NATIVE, FeatureLayout, layout
from core.spec import EpisodeSpec, SceneObject
from oracle import meshes
from oracle.drives import FINGER_OPEN, SERVO_KP, SERVO_KV, Drive, JointServo, OscPose

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
HAND_BODY = "robot0_right_hand"  # robosuite's `eef_quat` is this body's orientation


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


def scene_xml(assets: tuple[tuple[str, int], ...], controller: str = NATIVE.controller) -> str:
    """The MJCF of a scene holding `count` bodies of each catalog kind, for a profile's controller."""
    arena = TableArena(table_full_size=world.TABLE_SIZE, table_offset=(0, 0, world.TABLE_TOP_Z))
    objects = [_build_object(catalog.kind(kind), f"{kind}{i}") for kind, count in sorted(assets) for i in range(count)]
    task = ManipulationTask(mujoco_arena=arena, mujoco_robots=[_robot()], mujoco_objects=objects)
    root = ET.fromstring(task.get_xml())
    if controller == NATIVE.controller:
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

    def __init__(self, assets: tuple[tuple[str, int], ...], profile: str = NATIVE.name) -> None:
        self.assets = tuple(sorted(assets))
        self.layout: FeatureLayout = layout(profile)
        self.model = mujoco.MjModel.from_xml_string(scene_xml(self.assets, self.layout.controller))
        m = self.model
        self.drive: Drive
        if self.layout.controller == NATIVE.controller:
            self.data = mujoco.MjData(m)
            self.drive = JointServo(m, self.data)
        else:
            from robosuite.utils.binding_utils import MjSim

            sim = MjSim(m)
            self.data = sim.data._data
            self.drive = OscPose(sim, ARM_JOINTS, EE_SITE)
        self.arm_qpos = np.array([m.joint(j).qposadr[0] for j in ARM_JOINTS])
        self.finger_qpos = np.array([m.joint(j).qposadr[0] for j in FINGER_JOINTS])
        self.ee_site = m.site(EE_SITE).id
        self.hand = m.body(HAND_BODY).id
        self.home = np.zeros(len(ARM_JOINTS))  # the episode's, from reset()
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
        d.ctrl[:7] = home if self.layout.controller == NATIVE.controller else 0.0  # servo targets, or torques
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
        self.home = home
        self.drive.reset(home)

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
        """Execute one control period (`substeps` physics steps) of an action of the profile."""
        self.drive.step(action, self.substeps)

    def state(self) -> np.ndarray:
        """observation.state of the profile. native: joint positions, finger positions,
        end-effector pose (xyz, wxyz); libero: end-effector position, axis-angle of the hand
        body's orientation (robosuite's `eef_quat`, through its `quat2axisangle`), finger positions.

        Poses are recomputed from the current joints first: after a step MuJoCo's derived
        positions still describe the state before it (a recorded frame's, restored, are fresh)."""
        d = self.data
        mujoco.mj_kinematics(self.model, d)
        fingers = d.qpos[self.finger_qpos]
        if self.layout.controller == NATIVE.controller:
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, d.site_xmat[self.ee_site])
            return np.concatenate([d.qpos[self.arm_qpos], fingers, d.site_xpos[self.ee_site], quat])
        return np.concatenate([d.site_xpos[self.ee_site], axis_angle(d.xquat[self.hand]), fingers])

    def ee_rot(self) -> np.ndarray:
        """The grip site's orientation, a 3x3 rotation matrix in the world frame."""
        return self.data.site_xmat[self.ee_site].reshape(3, 3).copy()

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
        """Restore a state `physics_state` returned; the controller restarts from it."""
        mujoco.mj_setState(self.model, self.data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(self.model, self.data)
        self.drive.reset(self.home)


def axis_angle(wxyz: np.ndarray) -> np.ndarray:
    """robosuite's `quat2axisangle` (of the xyzw quaternion), as LIBERO's state uses it."""
    w = float(np.clip(wxyz[0], -1.0, 1.0))
    den = np.sqrt(1.0 - w * w)
    if np.isclose(den, 0.0):
        return np.zeros(3)
    return np.asarray(wxyz[1:]) * 2.0 * np.arccos(w) / den


@lru_cache(maxsize=4)
def scene_for(assets: tuple[tuple[str, int], ...], profile: str = NATIVE.name) -> Scene:
    """One compiled scene per inventory, profile and process."""
    return Scene(assets, profile)
