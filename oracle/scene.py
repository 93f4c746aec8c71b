"""Episode spec -> MuJoCo scene, in the spec's world (core/worlds/): robosuite's Panda, table
arena and objects (native), or LIBERO's arena, robot placement, cameras and object models.

A model is compiled once per world, asset inventory (the spec's `assets`) and profile, and every
episode re-poses it through the simulator state: objects in the episode are moved to their
poses, the rest are parked (under the table, under the floor), out of every camera's view and
out of the contact solver.
The profile's controller (oracle/drives.py) decides what an action does: in the native profile
the arm's torque motors become joint-position servos with gravity compensation, so an action is
seven joint targets and a gripper command (-1 open, +1 closed); in the libero profile they stay
torque motors, driven by robosuite's operational-space controller from end-effector deltas.
"""

from __future__ import annotations

import logging
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import mujoco
import numpy as np
from scipy.optimize import nnls

from core import catalog, profiles, worlds
from core.furniture import Spot
from core.profiles import AGENTVIEW, NATIVE, Profile
from core.rotations import IDENTITY, yaw_quat
from core.spec import FAST, EpisodeSpec, SceneObject
from core.worlds import native
from oracle import meshes, textures
from oracle.drives import SERVO_KP, SERVO_KV, Drive, JointServo, OscPose

# robosuite logs warnings about optional extras at import; they say nothing about our use.
logging.getLogger("robosuite_logs").addFilter(lambda record: record.levelno >= logging.ERROR)

from robosuite.models import objects as rs_objects  # noqa: E402
from robosuite.models.arenas import Arena, TableArena  # noqa: E402
from robosuite.models.bases import robot_base_factory  # noqa: E402
from robosuite.models.grippers import gripper_factory  # noqa: E402
from robosuite.models.robots import Panda  # noqa: E402
from robosuite.models.tasks import ManipulationTask  # noqa: E402
from robosuite.models.world import MujocoWorldBase  # noqa: E402

ARM_JOINTS = tuple(f"robot0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("gripper0_finger_joint1", "gripper0_finger_joint2")
EE_SITE = "gripper0_grip_site"
HAND_BODY = "robot0_right_hand"  # robosuite's `eef_quat` is this body's orientation


HULL_POINTS = 200  # hand_gap takes a mesh of more vertices as its bounding box: a few cm of box cost less than its hull
HULL_WEIGHT = 1e3  # _hull_distance's weight on its weights summing to 1 (distances are a few cm)
HIDDEN_GROUP = 5  # geoms of parked bodies move to this group, which no camera draws (oracle/render.py)
MIRROR_GROUP = 4  # a fixture's mirror plate: drawn by the agentview camera alone (oracle/render.py)
# How LIBERO's mirror tops look from its agentview camera: the light plaster wall behind the robot,
# reflected (fitted to LIBERO's frames: the stove top from 75/255 to 16/255 mean absolute difference);
# a world whose walls differ says its own (`arena`'s "mirror_rgba" and "mirror_emission").
MIRROR_LOOK = {"rgba": "0.8 0.8 0.8 1", "emission": "0.3"}


def _robot(world: worlds.World) -> Panda:
    robot = Panda(idn=0)
    robot.add_base(robot_base_factory(world.mount or "NullMount", idn=0))
    robot.add_gripper(gripper_factory("PandaGripper", idn=0))
    robot.set_base_xpos(world.robot_base)
    return robot


def _build_object(kind: catalog.Kind, name: str) -> rs_objects.MujocoObject:
    if kind.model == "libero":  # LIBERO's model file, loaded as LIBERO's objects load it (envs/objects/*.py)
        from core import libero

        return rs_objects.MujocoXMLObject(
            str(libero.assets_root() / kind.params["xml"]),
            name=name,
            joints=[{"type": "free", "damping": "0.0005"}],
            obj_type="all",
            duplicate_collision_geoms=False,
        )
    return getattr(rs_objects, kind.model)(name, **kind.params)


def libero_folder(kind: catalog.Kind) -> Path:
    """The folder of a LIBERO kind's model file."""
    from core import libero

    return (libero.assets_root() / kind.params["xml"]).parent


def _libero_arena(world: worlds.World) -> Arena:
    """LIBERO's arena file with its floor and wall textures (LIBERO's EmptyArena, or its TableArena
    where the world has a table), its cameras set as the world's problem class sets them."""
    from core import libero

    scene = str(libero.assets_root() / world.arena["scene"])
    if world.table is None:
        arena = Arena(scene)
    else:
        size, top = world.table
        arena = TableArena(table_full_size=size, table_offset=top, table_friction=world.table_friction, xml=scene)
    for texture, file in (("texplane", world.arena["floor"]), ("tex-wall", world.arena["wall"])):
        node = arena.asset.find(f"./texture[@name='{texture}']")
        node.set("file", str(Path(node.get("file")).parent / file))
    arena.set_origin([0, 0, 0])
    cam = world.agentview
    arena.set_camera(camera_name=NATIVE.cameras[AGENTVIEW], pos=list(cam.pos), quat=list(cam.quat))
    return arena


def _fixture(placed: worlds.Placed) -> rs_objects.MujocoObject:
    """A world's fixture as LIBERO loads it (no free joint), its body where the world puts it."""
    from core import libero

    fixture = rs_objects.MujocoXMLObject(
        str(libero.assets_root() / placed.fixture.xml),
        name=placed.name,
        joints=None,
        obj_type="all",
        duplicate_collision_geoms=False,
    )
    body = fixture.get_obj()
    body.set("pos", " ".join(map(str, placed.pos)))
    body.set("quat", " ".join(map(str, yaw_quat(placed.yaw))))
    return fixture


def _mirror_plates(root: ET.Element, world: worlds.World) -> None:
    """Over each fixture's mirror box (`Fixture.mirror`), a drawn-only plate on its top face in
    MIRROR_GROUP. LIBERO renders the box's top as a mirror; with reflections off (3x the frame's
    time) it would show its own dark metal. What the mirror shows depends on the camera: from the
    fixed agentview camera the light wall behind the robot, which the plate's light material
    stands for; from the wrist camera, looking down, the robot's dark hand, which the box's own
    material already looks like: so only the agentview camera draws the plate."""
    names = {f"{p.name}_{p.fixture.mirror}" for p in world.fixtures if p.fixture.mirror}
    if not names:
        return
    look = {key: world.arena.get(f"mirror_{key}", value) for key, value in MIRROR_LOOK.items()}
    ET.SubElement(root.find("asset"), "material", {"name": "mirror_top", **look})
    for body in root.iter("body"):
        for geom in body.findall("geom"):
            if geom.get("name") in names:
                sx, sy, sz = (float(v) for v in geom.get("size", "").split())
                x, y, z = (float(v) for v in geom.get("pos", "0 0 0").split())
                plate = {"name": f"{geom.get('name')}_mirror", "type": "box", "size": f"{sx} {sy} 0.0001"}
                plate |= {"pos": f"{x} {y} {z + sz + 0.0002}", "group": str(MIRROR_GROUP), "material": "mirror_top"}
                ET.SubElement(body, "geom", {**plate, "contype": "0", "conaffinity": "0", "mass": "0"})


def _servo_and_gravcomp(root: ET.Element) -> None:
    """Arm torque motors -> position servos (torque limits kept); gravity-compensate the robot."""
    for i, motor in enumerate(root.find("actuator").findall("motor")):
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


def _configure(root: ET.Element, world: worlds.World) -> None:
    option = root.find("option")
    assert option is not None
    option.set("integrator", world.integrator)
    option.set("timestep", str(worlds.PHYSICS_DT))
    visual = root.find("visual")
    if visual is None:
        visual = ET.SubElement(root, "visual")
    quality = visual.find("quality")
    if quality is None:
        quality = ET.SubElement(visual, "quality")
    quality.set("offsamples", "0")  # no MSAA: the CPU rasteriser's main cost (docs/GENERATE.md: Performance)
    glob = visual.find("global")
    if glob is None:
        glob = ET.SubElement(visual, "global")
    glob.set("offwidth", str(worlds.MAX_IMAGE_SIZE))
    glob.set("offheight", str(worlds.MAX_IMAGE_SIZE))
    cam = world.agentview
    for node in root.iter("camera"):
        if node.get("name") == NATIVE.cameras[AGENTVIEW] and cam.lookat is not None:
            node.set("pos", " ".join(map(str, cam.pos)))
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, cam.rotation().flatten())
            node.set("quat", " ".join(f"{v:.6f}" for v in quat))
            node.set("fovy", str(cam.fovy))


def scene_xml(
    assets: tuple[tuple[str, int], ...], controller: str = NATIVE.controller, world_name: str = "native", look: str = FAST
) -> str:
    """The MJCF of a world's scene holding `count` bodies of each of its kinds, for a profile's
    controller, drawn with `look` (core/spec.py): the fast look's meshes lightened and mirror tops
    stood in for by plates, the full look's as their files have them."""
    world = worlds.world(world_name)
    if world.builder == "table":
        arena = TableArena(table_full_size=native.TABLE_SIZE, table_offset=(0, 0, native.TABLE_TOP_Z))
    else:
        arena = _libero_arena(world)
    bodies = [(kind, count) for kind, count in sorted(assets) if not world.kind(kind).is_site]
    objects = [_build_object(world.kind(kind), world.body_name(kind, i)) for kind, count in bodies for i in range(count)]
    objects += [_fixture(placed) for placed in world.fixtures]
    task = ManipulationTask(mujoco_arena=arena, mujoco_robots=[_robot(world)], mujoco_objects=objects)
    root = ET.fromstring(task.get_xml())
    if controller == NATIVE.controller:
        _servo_and_gravcomp(root)
    _configure(root, world)
    if look == FAST:
        faces = {str(libero_folder(k)): k.params["faces"] for k in world.kinds.values() if "faces" in k.params}
        meshes.lighten(root, objects=world.builder != "table", faces=faces, robot_faces=world.robot_faces)
    if world.builder != "table":  # robosuite's own textures are small; the native scene's bytes stay as they are
        textures.shrink(root)  # only texels no camera samples at our frame sizes: the same look
        if look == FAST:
            _mirror_plates(root, world)
    return ET.tostring(root, encoding="unicode")


def robot_xml(world_name: str = "native", light: bool = True) -> str:
    """The world's robot alone, at the same base pose: the IK model. Its visual meshes are the
    lightened ones (`light`) too: the links' inertias are given, so kinematics are the same, and
    the model compiles in a tenth of the time."""
    world = worlds.world(world_name)
    arena_free = MujocoWorldBase()
    arena_free.merge(_robot(world))
    if not light:
        return arena_free.get_xml()
    root = ET.fromstring(arena_free.get_xml())
    meshes.lighten(root, robot_faces=world.robot_faces)
    return ET.tostring(root, encoding="unicode")


@dataclass
class Body:
    """One object body in the compiled model."""

    kind: catalog.Kind
    body_id: int
    qpos_adr: int
    geom_ids: tuple[int, ...]
    park: np.ndarray  # free-joint qpos when not in the episode
    collision: tuple[tuple[int, int, int], ...]  # compiled (contype, conaffinity, group) of each geom
    site: int = -1  # a fixture's site standing in for an object (a `site` kind): never moved, never parked
    offset: np.ndarray | None = None  # or a point on the fixture's body (a `site` kind's `offset`), in its frame

    @property
    def fixed(self) -> bool:
        """A place on a fixture (a `site` kind): the scene never poses or parks it."""
        return self.site >= 0 or self.offset is not None


class Scene:
    """A compiled scene that episodes re-pose by state, never by re-parsing."""

    def __init__(
        self, assets: tuple[tuple[str, int], ...], profile: str = NATIVE.name, world: str = "native", look: str = FAST
    ) -> None:
        self.assets = tuple(sorted(assets))
        self.interface: Profile = profiles.named(profile)
        self.world = worlds.world(world)
        self.look = look  # how its cameras draw it (core/spec.py LOOKS; oracle/render.py)
        self.model = mujoco.MjModel.from_xml_string(scene_xml(self.assets, self.interface.controller, world, look))
        m = self.model
        self.data = mujoco.MjData(m)
        servo = self.interface.controller == NATIVE.controller
        self.drive: Drive = JointServo(m, self.data) if servo else OscPose(m, self.data, ARM_JOINTS, EE_SITE)
        self.arm_qpos = np.array([m.joint(j).qposadr[0] for j in ARM_JOINTS])
        self.finger_qpos = np.array([m.joint(j).qposadr[0] for j in FINGER_JOINTS])
        self.ee_site = m.site(EE_SITE).id
        self.hand = m.body(HAND_BODY).id
        # the hand's colliding geoms (fingers and pads included), and a second state to pose it in
        self.hand_geoms = tuple(g for g in range(m.ngeom) if _colliding(m, g) and _descends(m, m.geom_bodyid[g], self.hand))
        self._probe = mujoco.MjData(m)
        self.home = np.zeros(len(ARM_JOINTS))  # the episode's, from reset()
        self.substeps = 1  # set per spec from its fps
        self.bodies: dict[str, list[Body]] = {}
        spots = self.world.park
        index = 0
        for kind_name, count in self.assets:
            kind = self.world.kind(kind_name)
            if kind.is_site:  # the fixture's site, or a point on its body: where it is, the scene's positions read
                spot = kind.part(Spot)
                site = m.site(spot.site).id if spot.site else -1
                body_id = int(m.site_bodyid[site]) if site >= 0 else m.body(spot.body).id
                offset = None if site >= 0 else np.asarray(spot.offset, float)
                geoms = tuple(g for g in range(m.ngeom) if _descends(m, m.geom_bodyid[g], body_id))
                self.bodies[kind_name] = [Body(kind, body_id, -1, geoms, np.zeros(7), (), site, offset)]
                continue
            for i in range(count):
                name = self.world.body_name(kind_name, i)
                joint = m.joint(f"{name}_joint0")
                body_id = int(m.jnt_bodyid[joint.id])
                geoms = tuple(g for g in range(m.ngeom) if m.geom_bodyid[g] == body_id or _descends(m, m.geom_bodyid[g], body_id))
                x, y = spots[index % len(spots)]  # parked bodies touch nothing: more of them may share a spot
                park = np.array([x, y, kind.rest_z(self.world.park_z) + 0.001 * (index // len(spots)), *kind.quat])
                collision = tuple((int(m.geom_contype[g]), int(m.geom_conaffinity[g]), int(m.geom_group[g])) for g in geoms)
                body = Body(kind, body_id, joint.qposadr[0], geoms, park, collision)
                self.bodies.setdefault(kind_name, []).append(body)
                index += 1
        self.placed: dict[str, Body] = {}

    def reset(self, spec: EpisodeSpec) -> None:
        """Put the robot at home and the episode's objects at their poses; park the rest."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        self.substeps = int(round(1.0 / (spec.setup.fps * m.opt.timestep)))
        home, world = np.asarray(spec.setup.robot_home), self.world
        d.qpos[self.arm_qpos] = home
        d.qpos[self.finger_qpos] = (world.finger_home, -world.finger_home)
        d.ctrl[:7] = home if self.interface.controller == NATIVE.controller else 0.0  # servo targets, or torques
        d.ctrl[7:9] = (world.finger_target, -world.finger_target)
        free = {kind: list(bodies) for kind, bodies in self.bodies.items()}
        self.placed = {}
        for obj in spec.objects:
            if not free.get(obj.kind):
                raise ValueError(f"episode {spec.index} needs another {obj.kind!r} but the scene holds {self.assets}")
            body = free[obj.kind].pop(0)
            self.placed[obj.id] = body
            if not body.fixed:
                self._pose(body, obj)
                self._park(body, False)
        for bodies in free.values():
            for body in (b for b in bodies if not b.fixed):
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
        for g, (contype, conaffinity, group) in zip(body.geom_ids, body.collision):
            m.geom_contype[g] = 0 if parked else contype
            m.geom_conaffinity[g] = 0 if parked else conaffinity
            m.geom_group[g] = HIDDEN_GROUP if parked else group

    def _pose(self, body: Body, obj: SceneObject) -> None:
        self.data.qpos[body.qpos_adr : body.qpos_adr + 7] = (*obj.pos, *yaw_quat(obj.yaw, body.kind.quat))
        if body.kind.colorable:
            rgba = catalog.COLORS[obj.attributes.get("color", "white")]
            for g in body.geom_ids:
                self.model.geom_rgba[g] = rgba

    def step(self, action: np.ndarray) -> None:
        """Execute one control period (`substeps` physics steps) of an action of the profile."""
        self.drive.step(action, self.substeps)

    def settle(self, spec: EpisodeSpec) -> None:
        """The actions holding the robot that the profile's own environment runs before a policy
        acts (lerobot's LIBERO env: 10; none natively): an exam rollout's first observation follows them."""
        features = spec.setup.interface
        for _ in range(features.settle_steps):
            self.step(features.hold_action(spec.setup.robot_home))

    def settled(self, spec: EpisodeSpec) -> dict[str, list] | None:
        """Settle, then where the end effector and every object stand: a rollout's step 0 when
        its loop logs from the observation `reset()` returns (exam answers' `settled_start`);
        None where the profile has no settle steps (`reset()` leaves the initial state)."""
        if not spec.setup.interface.settle_steps:
            return None
        self.settle(spec)
        return {"ee": [float(v) for v in self.ee_pos()], "objects": {k: list(v) for k, v in self.positions().items()}}

    def state(self) -> np.ndarray:
        """observation.state of the profile. native: joint positions, finger positions,
        end-effector pose (xyz, wxyz); libero: end-effector position, axis-angle of the hand
        body's orientation (robosuite's `eef_quat`, through its `quat2axisangle`), finger positions.

        Poses are recomputed from the current joints first: after a step MuJoCo's derived
        positions still describe the state before it (a recorded frame's, restored, are fresh)."""
        d = self.data
        mujoco.mj_kinematics(self.model, d)
        fingers = d.qpos[self.finger_qpos]
        if self.interface.controller == NATIVE.controller:
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
        body, d = self.placed[object_id], self.data
        if body.offset is not None:
            return d.xpos[body.body_id] + d.xmat[body.body_id].reshape(3, 3) @ body.offset
        return (d.site_xpos[body.site] if body.site >= 0 else d.xpos[body.body_id]).copy()

    def fastest(self) -> float:
        """The speed (m/s) of the fastest-moving free object of the episode (its free joint's linear velocity)."""
        model, qvel = self.model, self.data.qvel
        joints = (model.body_jntadr[b.body_id] for b in self.placed.values() if not b.fixed)
        dofs = [model.jnt_dofadr[j] for j in joints if j >= 0]
        return max((float(np.linalg.norm(qvel[d : d + 3])) for d in dofs), default=0.0)

    def body_pose(self, object_id: str) -> tuple[np.ndarray, np.ndarray]:
        """The position and rotation matrix of the body an object is (or, a place, is on: a drawer, a knob)."""
        body = self.placed[object_id].body_id
        return self.data.xpos[body].copy(), self.data.xmat[body].reshape(3, 3).copy()

    def surface_below(self, xy: np.ndarray, z: float) -> float:
        """Height of the first surface straight below (x, y, z) that is not the robot's: where a
        fingertip lowered there would land (-inf over nothing)."""
        return self._first_surface(xy, z, -1.0)

    def ceiling_above(self, xy: np.ndarray, z: float, besides: str | None = None) -> float:
        """Height of the first surface straight above (x, y, z) that is neither the robot's nor the
        object `besides`'s: what a thing lifted there, or a hand come down there, would meet (inf
        under nothing)."""
        return self._first_surface(xy, z, 1.0, self.placed[besides].body_id if besides is not None else -1)

    def _first_surface(self, xy: np.ndarray, z: float, sign: float, skip: int = -1) -> float:
        """The height of the first surface along z from (x, y, z), up (`sign` 1) or down (-1), that is
        neither the robot's (rays pass through its geoms) nor body `skip`'s; sign * inf if none."""
        m, geom, direction = self.model, np.zeros(1, np.int32), np.array([0.0, 0.0, sign])
        while (distance := mujoco.mj_ray(m, self.data, np.array([xy[0], xy[1], z], float), direction, None, 1, skip, geom)) >= 0:
            z += sign * distance
            if m.body_rootid[m.geom_bodyid[geom[0]]] != m.body_rootid[self.hand]:
                return z
            z += sign * 1e-4  # through the robot's geom, on
        return sign * np.inf

    def hand_gap(self, path: Sequence[np.ndarray], held: str | None, among: Sequence[str], within: float) -> float:
        """The smallest distance, up to `within`, between the hand with the object `held` (carried
        rigidly with it) and the objects `among`, the arm at each joint angles of `path`: how close a
        planned move passes what stands beside it. Each colliding geom counts as the convex hull of
        its `_outline` (MuJoCo 3.9's mj_geomDistance gave 0 for the hand 13 mm from a bottle's box, as
        google-deepmind/mujoco#3383 reports of meshes); the simulation is untouched."""
        m, probe = self.model, self._probe
        probe.qpos[:] = self.data.qpos
        mujoco.mj_kinematics(m, probe)
        moving, carried = list(self.hand_geoms), self.placed[held] if held is not None else None
        if carried is not None:  # its pose in the hand's frame
            hand_rot = probe.xmat[self.hand].reshape(3, 3)
            offset = hand_rot.T @ (probe.xpos[carried.body_id] - probe.xpos[self.hand])
            turn = hand_rot.T @ probe.xmat[carried.body_id].reshape(3, 3)
            moving += [g for g in carried.geom_ids if _colliding(m, g)]
        standing = [g for o in among for g in self.placed[o].geom_ids if _colliding(m, g)]
        outlines = {g: self._outline(g) for g in moving + standing}
        radius = {g: float(np.linalg.norm(points, axis=1).max()) for g, points in outlines.items()}
        gap, quat = within, np.zeros(4)

        def placed(g: int) -> np.ndarray:
            return probe.geom_xpos[g] + outlines[g] @ probe.geom_xmat[g].reshape(3, 3).T

        for q in path:
            probe.qpos[self.arm_qpos] = q
            mujoco.mj_kinematics(m, probe)
            if carried is not None:
                hand_rot = probe.xmat[self.hand].reshape(3, 3)
                mujoco.mju_mat2Quat(quat, (hand_rot @ turn).flatten())
                probe.qpos[carried.qpos_adr : carried.qpos_adr + 7] = (*(probe.xpos[self.hand] + hand_rot @ offset), *quat)
                mujoco.mj_kinematics(m, probe)
            for a in moving:
                for b in standing:  # bounding spheres first: most pairs are far apart
                    if np.linalg.norm(probe.geom_xpos[a] - probe.geom_xpos[b]) - radius[a] - radius[b] < gap:
                        gap = min(gap, _hull_distance(placed(a), placed(b)))
        return gap

    def _outline(self, geom: int) -> np.ndarray:
        """Points (geom frame) whose convex hull holds the geom: a mesh's vertices (its collision
        shape is their hull), else its bounding box's corners (a box's own; a larger mesh's or a
        round geom's, a little more than it)."""
        m = self.model
        if m.geom_type[geom] == mujoco.mjtGeom.mjGEOM_MESH and m.mesh_vertnum[m.geom_dataid[geom]] <= HULL_POINTS:
            start = m.mesh_vertadr[m.geom_dataid[geom]]
            return m.mesh_vert[start : start + m.mesh_vertnum[m.geom_dataid[geom]]].astype(float)
        centre, half = m.geom_aabb[geom, :3], m.geom_aabb[geom, 3:]
        return centre + half * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)

    def positions(self) -> dict[str, tuple[float, float, float]]:
        """Where every object of the episode is now."""
        return {k: tuple(float(v) for v in self.object_pos(k)) for k in self.placed}

    def turns(self) -> dict[str, tuple[float, ...]]:
        """How each container that can move (a basket) is turned now (w, x, y, z): LIBERO's `In`
        turns its box with it (core/success.py)."""
        movable = (k for k, b in self.placed.items() if b.kind.contain is not None and not b.fixed)
        return {k: tuple(float(v) for v in self.data.xquat[self.placed[k].body_id]) for k in movable}

    def object_yaw(self, object_id: str) -> float:
        """How far the object is turned about the world's z from its resting orientation."""
        body = self.placed[object_id]
        if body.fixed:
            return 0.0
        mat = self.data.xmat[body.body_id].reshape(3, 3)
        if body.kind.quat != IDENTITY:
            rest = np.zeros(9)
            mujoco.mju_quat2Mat(rest, np.asarray(body.kind.quat, float))
            mat = mat @ rest.reshape(3, 3).T
        return float(np.arctan2(mat[1, 0], mat[0, 0]))

    def physics_state(self) -> np.ndarray:
        """The full physics state (mjSTATE_INTEGRATION): what an exam stores to restart a trial."""
        spec = mujoco.mjtState.mjSTATE_INTEGRATION
        state = np.empty(mujoco.mj_stateSize(self.model, spec))
        mujoco.mj_getState(self.model, self.data, state, spec)
        return state

    def set_joints(self, qpos: dict[str, np.ndarray], qvel: dict[str, np.ndarray]) -> None:
        """Set joints by name (another simulator's state of the same bodies, e.g. LIBERO's), as
        LIBERO's `set_init_state` does: the controller keeps what it read at the reset (drives.py)."""
        m, d = self.model, self.data
        for name, value in qpos.items():
            start = m.joint(name).qposadr[0]
            d.qpos[start : start + len(value)] = value
        for name, value in qvel.items():
            start = m.joint(name).dofadr[0]
            d.qvel[start : start + len(value)] = value
        mujoco.mj_forward(m, d)
        self.drive.restored()

    def set_physics_state(self, state: np.ndarray) -> None:
        """Restore a state `physics_state` returned; the controller keeps what it read at the reset,
        as robosuite 1.4's does after LIBERO's `set_init_state` (drives.py)."""
        mujoco.mj_setState(self.model, self.data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
        mujoco.mj_forward(self.model, self.data)
        self.drive.restored()


def axis_angle(wxyz: np.ndarray) -> np.ndarray:
    """robosuite's `quat2axisangle` (of the xyzw quaternion), as LIBERO's state uses it."""
    w = float(np.clip(wxyz[0], -1.0, 1.0))
    den = np.sqrt(1.0 - w * w)
    if np.isclose(den, 0.0):
        return np.zeros(3)
    return np.asarray(wxyz[1:]) * 2.0 * np.arccos(w) / den


def _colliding(model: mujoco.MjModel, geom: int) -> bool:
    return bool(model.geom_contype[geom] or model.geom_conaffinity[geom])


def _hull_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between the convex hulls of two point sets (0 where they meet): the origin's from
    the hull of their differences, its nearest point a convex weighting of them, found by
    non-negative least squares with the weights' sum to 1 as a heavily weighted extra row."""
    differences = (a[:, None, :] - b[None, :, :]).reshape(-1, 3).T
    rows = np.vstack([differences, np.full(differences.shape[1], HULL_WEIGHT)])
    weights, _ = nnls(rows, np.array([0.0, 0.0, 0.0, HULL_WEIGHT]))
    return float(np.linalg.norm(differences @ weights) / max(weights.sum(), 1e-12))


def _descends(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """Whether `body` is `ancestor` or inside it (LIBERO's objects nest their geoms in a child body)."""
    while body > 0:
        if body == ancestor:
            return True
        body = int(model.body_parentid[body])
    return False


@lru_cache(maxsize=4)
def scene_for(assets: tuple[tuple[str, int], ...], profile: str = NATIVE.name, world: str = "native", look: str = FAST) -> Scene:
    """One compiled scene per inventory, profile, world, look and process."""
    return Scene(assets, profile, world, look)


def spec_scene(spec: EpisodeSpec) -> Scene:
    """The compiled scene an episode plays in, drawn as its settings say."""
    return scene_for(spec.assets, spec.setup.profile, spec.setup.world, spec.setup.look)
