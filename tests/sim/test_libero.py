"""The libero profile: LIBERO's features, actions that are end-effector deltas through
robosuite's OSC_POSE controller, frames oriented as lerobot's LIBERO datasets store them, and
exams that take (and check) actions of that shape."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset

from core.exam import read
from core.profiles import ACTION_KEY, AGENTVIEW, LIBERO, NATIVE, OSC_POS_LIMIT, STATE_KEY
from core.programs import succeeded
from core.spec import EpisodeSpec, Setup
from eval.env import ExamEnv
from eval.policies.registry import make
from eval.scoring.battery import take
from eval.sims.rollout import ProfileMismatch, Runner
from gen.lerobot.reader import LeRobotReader
from gen.planning.plan import plan
from gen.products import scenes
from helpers import ONE_TRIAL, Shared, body_image, make_dataset, rows_of
from oracle.episode import replay
from oracle.render import Cameras
from oracle.scene import scene_for
from referents import registry


@pytest.fixture(scope="module")
def libero_dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_dataset(tmp_path_factory.mktemp("libero") / "object", "n=4", "profile=libero", "image_size=64", "seed=5")


def test_lerobot_loads_exactly_the_libero_features(libero_dataset: Path) -> None:
    ds = LeRobotDataset("local/libero", root=libero_dataset)
    features = ds.meta.features
    assert set(LIBERO.image_keys) | {STATE_KEY, ACTION_KEY} <= set(features)
    assert not set(NATIVE.image_keys) & set(features)
    assert features[STATE_KEY]["shape"] in ([8], (8,)) and features[ACTION_KEY]["shape"] in ([7], (7,))
    assert ds.meta.fps == 20
    item = ds[0]
    assert tuple(item[STATE_KEY].shape) == (8,) and tuple(item[ACTION_KEY].shape) == (7,)
    assert tuple(item[LIBERO.image_key("image")].shape) == (3, 64, 64)
    actions = np.stack(LeRobotReader(libero_dataset).data[ACTION_KEY].to_numpy())
    assert np.all(np.abs(actions) <= 1.0) and set(np.unique(actions[:, 6])) <= {-1.0, 1.0}
    card = (libero_dataset / "README.md").read_text()
    assert "Profile `libero`" in card and "20 Hz" in card
    generation = json.loads((libero_dataset / "meta/generation.json").read_text())
    assert generation["config"]["profile"] == "libero" and "profile=libero" in card


def test_recorded_deltas_replay_through_the_controller_to_the_same_success(libero_dataset: Path) -> None:
    reader = LeRobotReader(libero_dataset)
    records = scenes.read(libero_dataset)
    for rec in records.itertuples():
        spec = EpisodeSpec.from_json(rec.spec)
        rows = reader.data[reader.data.episode_index == rec.episode_index]
        actions, states = np.stack(rows[ACTION_KEY].to_numpy()), np.stack(rows[STATE_KEY].to_numpy())
        scene = scene_for(spec.assets, spec.setup.profile)
        seen: list[np.ndarray] = []
        outcome = replay(scene, spec, actions, observe=lambda t: seen.append(scene.state().astype(np.float32)))
        assert np.array_equal(np.stack(seen), states), f"episode {rec.episode_index}: states differ on replay"
        assert succeeded(spec, outcome), f"episode {rec.episode_index}: replay misses the success predicate"
        # the state's end-effector position is the grip site's, and the deltas moved it
        assert np.abs(np.diff(states[:, :3], axis=0)).max() <= 2 * OSC_POS_LIMIT


def test_the_drive_moves_the_arm_as_robosuites_own_controller(libero_dataset: Path) -> None:
    """OscPose computes robosuite's OSC_POSE with robosuite's functions on state it reads itself;
    robosuite's OperationalSpaceController object, stepped the same way on the same recorded
    actions, moves every joint the same to within 1e-9."""
    from robosuite.controllers.parts.arm.osc import OperationalSpaceController
    from robosuite.utils.binding_utils import MjSim

    from oracle import drives
    from oracle.scene import ARM_JOINTS, EE_SITE

    class Robosuites(drives.OscPose):  # the controller object in place of OscPose's own equations
        def __init__(self, model, data) -> None:  # noqa: ANN001
            super().__init__(model, data, ARM_JOINTS, EE_SITE)
            sim = MjSim(model)
            sim.data._data = data
            ids = [model.joint(j).id for j in ARM_JOINTS]
            self.osc = OperationalSpaceController(
                sim, ref_name=EE_SITE, joint_indexes={"joints": ids, "qpos": list(self.qpos_index), "qvel": list(self.dof)},
                actuator_range=(self.low, self.high), output_max=(OSC_POS_LIMIT,) * 3 + (0.5,) * 3,
                output_min=(-OSC_POS_LIMIT,) * 3 + (-0.5,) * 3, kp=drives.OSC_KP, damping_ratio=drives.OSC_DAMPING_RATIO,
                input_ref_frame="world", uncouple_pos_ori=True, lite_physics=True, part_name="right", naming_prefix="robot0_",
            )  # fmt: skip

        def reset(self, home: np.ndarray) -> None:
            super().reset(home)
            self.osc.update_initial_joints(np.asarray(home, float))

        def _update(self) -> None:
            super()._update()
            self.osc.new_update = True

        def _set_goal(self, action: np.ndarray) -> None:
            self.osc.set_goal(action)

        def _torques(self) -> np.ndarray:
            return self.osc.run_controller()

    record = scenes.read(libero_dataset).iloc[0]
    spec = EpisodeSpec.from_json(record["spec"])
    actions = np.stack(LeRobotReader(libero_dataset).data.query("episode_index == 0")[ACTION_KEY].to_numpy())
    paths = []
    for drive in (None, Robosuites):
        scene = scene_for(spec.assets, spec.setup.profile)
        if drive is not None:
            scene = type(scene)(spec.assets, spec.setup.profile)
            scene.drive = drive(scene.model, scene.data)
        scene.reset(spec)
        path = []
        for action in actions:
            scene.step(action)
            path.append(scene.data.qpos[scene.arm_qpos].copy())
        paths.append(np.array(path))
    assert np.abs(paths[0] - paths[1]).max() < 1e-9


def test_frames_are_mirrored_as_in_lerobots_libero_datasets() -> None:
    """lerobot's LIBERO datasets hold robosuite's (upside-down, OpenGL) frames turned 180
    degrees: upright, mirrored left to right. An object on the robot's left (+y), which an
    upright agentview shows on the right, must be on the left of a libero frame."""
    ref = registry.load("object")
    spec = plan(ref, 1, seed=0, setup=Setup(image_size=64))[0]
    left = max(spec.objects, key=lambda o: o.pos[1])
    frames = {}
    for profile, cams in (("native", NATIVE.camera_names), ("libero", LIBERO.camera_names)):
        scene = scene_for(spec.assets, profile)
        scene.reset(spec)
        cameras = Cameras(scene, 64, cams)
        frames[profile] = {c: f.copy() for c, f in cameras.render().items()}
        cameras.close()
    for native_cam, libero_cam in zip(NATIVE.camera_names, LIBERO.camera_names):
        assert np.array_equal(frames["libero"][libero_cam], frames["native"][native_cam][:, ::-1])
    assert left.pos[1] > 0
    scene = scene_for(spec.assets, "native")
    scene.reset(spec)
    _, columns = np.nonzero(body_image(scene, AGENTVIEW, 64) == scene.placed[left.id].body_id)
    assert columns.mean() > 32, "upright agentview: the robot's left is on the image's right"
    mirrored = frames["libero"][LIBERO.camera_names[0]]
    assert np.array_equal(mirrored[:, 64 - 1 - int(columns.mean())], frames["native"][AGENTVIEW][:, int(columns.mean())])


def test_a_libero_exam_ranks_the_reference_policies(tmp_path_factory: pytest.TempPathFactory) -> None:
    args = ("n=8", "split=exam", "seed=3", "profile=libero", "image_size=32", "switches=0")  # the switch face: its own tests
    root = make_dataset(tmp_path_factory.mktemp("exam") / "x", *args)
    exam = read(root)
    assert json.loads((root / "exam.json").read_text())["profile"] == "libero"
    out = tmp_path_factory.mktemp("runs")
    oracle = take(exam, rows_of(exam, ["task", "swap"]), make("oracle"), out / "oracle", baseline=False)[0]["faces"]
    first = exam.trials[exam.trials["trial"] < 2]  # doing nothing runs every row to its horizon: two trials say it
    nothing = take(exam, first, make("nothing"), out / "nothing", baseline=False)[0]["faces"]
    assert oracle["obeyed_name"]["rate"] >= 0.95 and oracle["task"]["rate"] >= 0.95
    assert all(f["k"] == 0 for f in nothing.values())


def libero_exam(shared: Shared) -> Path:
    """A one-trial exam of the libero profile, at 32 px."""
    return shared.dataset("libero-exam", "n=1", "split=exam", "seed=3", "profile=libero", "image_size=32")


def test_an_action_of_the_other_profile_is_refused_naming_it(shared: Shared) -> None:
    root = libero_exam(shared)
    env = ExamEnv(root, row=0)
    env.reset()
    with pytest.raises(ProfileMismatch, match=r"native-profile actions of shape \(8,\), but this exam is profile libero"):
        env.step(np.zeros(NATIVE.action_size, np.float32))
    obs, *_ = env.step(np.zeros(LIBERO.action_size, np.float32))
    assert set(obs) == {*LIBERO.image_keys, STATE_KEY}
    env.close()
    joint_targets = make("nothing")
    joint_targets.reset = lambda context: None
    joint_targets.act = lambda observation: np.zeros(NATIVE.action_size, np.float32)
    with pytest.raises(ProfileMismatch):
        Runner(joint_targets).run(read(root).trials.iloc[0])


def test_an_openpi_libero_server_takes_a_keys_libero_exam(shared: Shared, tmp_path: Path) -> None:
    """A loopback server speaking openpi's protocol checks each request is exactly what openpi's
    LIBERO example client sends (keys, dtypes, shapes) and answers with 7-d action chunks."""
    import threading

    from openpi_client import msgpack_numpy
    from websockets.sync.server import serve

    root = libero_exam(shared)
    seen: list[dict] = []
    packer = msgpack_numpy.Packer()

    def handler(ws) -> None:  # noqa: ANN001
        ws.send(packer.pack({"server": "libero-check"}))
        for message in ws:
            request = msgpack_numpy.unpackb(message)
            seen.append({k: (type(v).__name__, getattr(v, "dtype", None), getattr(v, "shape", None)) for k, v in request.items()})
            ws.send(packer.pack({"actions": np.tile([0, 0, 0, 0, 0, 0, -1.0], (10, 1))}))

    with serve(handler, "127.0.0.1", 0) as server:
        threading.Thread(target=server.serve_forever, daemon=True).start()
        address = f"127.0.0.1:{server.socket.getsockname()[1]}"
        exam = read(root)
        rows = exam.trials.head(1)
        report, _ = take(exam, rows, make(f"remote:{address}", keys="libero"), tmp_path / "report", baseline=False)
        server.shutdown()
    assert not report["errors"], report["errors"]
    steps = int(rows["max_steps"].iloc[0])
    assert len(seen) == -(-steps // 5)  # a query every 5 actions, as the example's replan_steps
    assert seen[0] == {
        "observation/image": ("ndarray", np.dtype(np.uint8), (224, 224, 3)),
        "observation/wrist_image": ("ndarray", np.dtype(np.uint8), (224, 224, 3)),
        "observation/state": ("ndarray", np.dtype(np.float64), (8,)),
        "prompt": ("str", None, None),
    }
    bad = subprocess.run(
        [sys.executable, "-m", "eval", f"policy=remote:{address}", "keys=libero", f"exam={shared.dataset('exam', *ONE_TRIAL)}"],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "this exam is profile native" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
