"""The scene builder: catalog geometry, cameras that see every object, parking out of view."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from core import worlds
from core.profiles import NATIVE, PROFILES
from core.spec import Setup
from core.worlds.native import TABLE_TOP_Z
from gen.planning.plan import default_setup, plan
from helpers import visible_bodies
from oracle.render import Cameras
from oracle.scene import Scene, _hull_distance, scene_for, spec_scene
from referents import registry


@pytest.fixture(scope="module")
def scene() -> Scene:
    return scene_for(registry.load("object").assets())


def _extent(model: mujoco.MjModel, data: mujoco.MjData, body_id: int) -> tuple[np.ndarray, np.ndarray]:
    points = []
    for g in range(model.ngeom):
        if model.geom_bodyid[g] != body_id or model.geom_group[g] != 0:
            continue
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = model.geom_dataid[g]
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            verts = model.mesh_vert[start : start + count]
        else:
            size = model.geom_size[g]
            half = {
                mujoco.mjtGeom.mjGEOM_BOX: size,
                mujoco.mjtGeom.mjGEOM_CYLINDER: (size[0], size[0], size[1]),
                mujoco.mjtGeom.mjGEOM_SPHERE: (size[0],) * 3,
            }[model.geom_type[g]]
            verts = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * half
        points.append(verts @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])
    pts = np.concatenate(points)
    return pts.min(axis=0), pts.max(axis=0)


@pytest.mark.parametrize("world", ["native", "libero_object"])
def test_catalog_extents_match_the_models(world: str) -> None:
    """Every kind's extent and the height of its origin above its lowest point, as planning reads
    them, against its compiled collision geometry in its resting orientation (LIBERO's kinds: each
    model LIBERO and LIBERO-PRO register, recoloured and resized copies included)."""
    kinds = {name: kind for name, kind in worlds.world(world).kinds.items() if not kind.is_site}
    scene = Scene(tuple((name, 1) for name in kinds), "native" if world == "native" else "libero", world)
    for i, (name, kind) in enumerate(kinds.items()):  # apart, in the air, at rest orientation
        body = scene.bodies[name][0]
        scene.data.qpos[body.qpos_adr : body.qpos_adr + 7] = [0.4 * i, 3.0, 1.0, *kind.quat]
    mujoco.mj_forward(scene.model, scene.data)
    for name, kind in kinds.items():
        body = scene.bodies[name][0]
        lo, hi = _extent(scene.model, scene.data, body.body_id)
        origin = scene.data.xpos[body.body_id]
        np.testing.assert_allclose(hi - lo, kind.size, atol=0.002, err_msg=name)
        assert abs((origin[2] - lo[2]) - kind.bottom) < 0.002, name


def test_every_object_is_in_frame_and_parked_ones_are_not(scene: Scene) -> None:
    for spec in plan(registry.load("object"), 4, seed=2, setup=Setup()):
        scene.reset(spec)
        visible = visible_bodies(scene, "agentview")
        for obj in spec.objects:
            assert visible.get(scene.placed[obj.id].body_id, 0) >= 10, f"{obj.id} not visible in episode {spec.index}"
        placed = {b.body_id for b in scene.placed.values()}
        parked = [b for bodies in scene.bodies.values() for b in bodies if b.body_id not in placed]
        assert parked, "the object scene should park some objects"
        for camera in NATIVE.cameras:
            seen = visible_bodies(scene, camera)
            assert not [b for b in parked if seen.get(b.body_id)], f"a parked object shows in {camera}"


@pytest.mark.parametrize("name", ["object", "libero_object"])
def test_each_object_projects_onto_its_own_pixels(name: str) -> None:
    """The agentview camera's projection (what the pointer loss aims at, train/fit.py) lands on
    each object's pixels in the rendered frames: a lookat camera, and LIBERO's quat camera in its
    mirrored profile."""
    referent = registry.load(name)
    setup = default_setup(referent)
    camera = PROFILES[setup.profile].agentview
    for spec in plan(referent, 2, seed=3, setup=setup):
        scene = spec_scene(spec)
        scene.reset(spec)
        cams = Cameras(scene, 128, (camera,))
        labels = cams.labels()[camera]
        cams.close()
        objects = [o for o in spec.objects if o.id in scene.placed]
        pixels = worlds.world(setup.world).agentview.project(np.array([o.pos for o in objects]), 128, setup.interface.mirrored)
        for obj, (column, row) in zip(objects, pixels):
            near = labels[int(row) - 2 : int(row) + 3, int(column) - 2 : int(column) + 3]
            assert (near == scene.model.body(scene.placed[obj.id].body_id).name.removesuffix("_main")).any(), obj.id


def test_reset_poses_objects_from_the_spec(scene: Scene) -> None:
    for spec in plan(registry.load("object"), 3, seed=4, setup=Setup()):
        scene.reset(spec)
        for obj in spec.objects:
            np.testing.assert_allclose(scene.object_pos(obj.id), obj.pos, atol=1e-9)
            assert abs(scene.object_yaw(obj.id) - obj.yaw) < 1e-6
            assert obj.pos[2] > TABLE_TOP_Z


def test_cameras_render_distinct_views(scene: Scene) -> None:
    spec = plan(registry.load("object"), 1, seed=0, setup=Setup())[0]
    scene.reset(spec)
    cams = Cameras(scene, 64, ("agentview", "wrist"))
    frames = {k: v.copy() for k, v in cams.render().items()}
    cams.close()
    assert frames["agentview"].shape == (64, 64, 3)
    assert frames["agentview"].std() > 10 and frames["wrist"].std() > 5
    assert np.abs(frames["agentview"].astype(int) - frames["wrist"]).mean() > 10


def test_robot_visual_meshes_are_light_and_collision_meshes_untouched(scene: Scene) -> None:
    from oracle.meshes import MAX_FACES
    from oracle.scene import robot_xml

    full = mujoco.MjModel.from_xml_string(robot_xml(light=False))  # the robot as robosuite ships it
    m = scene.model
    light, kept = 0, 0
    for g in range(m.ngeom):
        body = m.body(m.geom_bodyid[g]).name
        if m.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH or not body.startswith(("robot0_", "gripper0_")):
            continue
        mesh = m.mesh(m.geom_dataid[g]).name
        faces = int(m.mesh_facenum[m.geom_dataid[g]])
        original = int(full.mesh_facenum[full.mesh(mesh).id])
        if m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0:
            assert faces == original or faces <= MAX_FACES, mesh
            light += faces < original
        else:
            assert faces == original, f"collision mesh {mesh} changed"
            kept += 1
    assert light >= 5 and kept >= 5


def test_the_ik_model_keeps_the_robots_kinematics() -> None:
    """The IK model's visual meshes are lightened; its bodies, joints and sites are robosuite's."""
    from oracle.scene import robot_xml

    light, full = (mujoco.MjModel.from_xml_string(robot_xml(light=flag)) for flag in (True, False))
    assert sum(light.mesh_facenum) < sum(full.mesh_facenum) / 2
    for field in (
        "body_pos",
        "body_quat",
        "body_mass",
        "body_inertia",
        "body_ipos",
        "body_iquat",
        "jnt_axis",
        "jnt_range",
        "site_pos",
    ):
        assert np.array_equal(getattr(light, field), getattr(full, field)), field


def test_large_textures_are_halved_by_two_by_two_averages(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from PIL import Image

    from oracle.textures import halved

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # the copy goes to this test's cache

    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 256, (8, 16, 3), dtype=np.uint8)
    Image.fromarray(pixels).save(tmp_path / "big.png")
    copy = halved(str(tmp_path / "big.png"), side=4)
    assert copy.parent == tmp_path / "cache" / "deconfound" / "textures"
    small = np.asarray(Image.open(copy))
    expected = pixels.reshape(2, 4, 4, 4, 3).mean(axis=(1, 3))  # two halvings: 4 x 4 blocks
    assert small.shape == (2, 4, 3)
    assert np.abs(small - expected).max() <= 1.0  # each halving rounds once
    assert halved(str(tmp_path / "big.png"), side=16) == tmp_path / "big.png"  # small enough: the file itself


def test_hull_distance_is_between_the_hulls_not_their_points() -> None:
    """hand_gap's distance: between two crossing rods 5 cm apart it is 5 cm, though their end
    points are a metre apart; between cubes, face to face; 0 where they overlap."""
    rod = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]])
    assert _hull_distance(rod + [0.0, 0.0, 0.05], rod[:, [1, 0, 2]]) == pytest.approx(0.05, abs=1e-6)
    cube = 0.01 * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    assert _hull_distance(cube, cube + [0.05, 0.01, 0.0]) == pytest.approx(0.03, abs=1e-6)
    assert _hull_distance(cube, cube + [0.015, 0.0, 0.0]) == pytest.approx(0.0, abs=1e-6)
