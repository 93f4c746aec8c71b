"""The oracle: IK accuracy, demos that succeed, success predicates that cannot be gamed, and
replay of recorded actions from recorded initial states."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import mujoco
import numpy as np
import pytest

from core import parquet
from core.programs import succeeded
from core.rotations import yaw_matrix
from core.spec import EpisodeSpec, Setup
from core.success import lifted
from gen.planning.plan import designs, plan, realize
from gen.products import scenes
from gen.products.produce import Producer
from oracle.episode import demonstrate, replay
from oracle.ik import DOWN, ArmIK
from oracle.scene import EE_SITE, Scene, scene_for
from oracle.skills import Skills
from referents import registry


@pytest.fixture(scope="module")
def scene() -> Scene:
    return scene_for(registry.load("object").assets())


@pytest.fixture(scope="module")
def ik() -> ArmIK:
    return ArmIK(np.asarray(Setup().robot_home))


def test_ik_reaches_top_down_poses(ik: ArmIK) -> None:
    data = mujoco.MjData(ik.model)
    site = ik.model.site(EE_SITE).id
    for pos, yaw in [((0.1, 0.2, 0.85), 0.3), ((-0.1, -0.22, 0.95), -1.2), ((0.0, 0.0, 1.1), 1.5)]:
        q = ik.solve(np.array(pos), yaw, seed=np.asarray(Setup().robot_home))
        data.qpos[:7] = q
        mujoco.mj_forward(ik.model, data)
        assert np.linalg.norm(data.site_xpos[site] - pos) < 2e-3
        rot_err = data.site_xmat[site].reshape(3, 3).T @ (yaw_matrix(yaw) @ DOWN)
        assert np.arccos(np.clip((np.trace(rot_err) - 1) / 2, -1, 1)) < 2e-3


def test_demos_succeed(scene: Scene, ik: ArmIK) -> None:
    ref = registry.load("object")
    setup = Setup()
    ok = 0
    for i, d in enumerate(designs(ref, 8, seed=21)):
        demo = demonstrate(scene, ik, realize(ref, d, i, 21, setup), ref.demo)
        ok += demo.success
        if demo.success:
            assert lifted(demo.spec, demo.outcome, demo.spec.target)
    assert ok >= 7, f"only {ok}/8 first-attempt demos succeeded"


def _hold_home(spec: EpisodeSpec, steps: int = 40) -> np.ndarray:
    return np.tile(np.array([*spec.setup.robot_home, -1.0], np.float32), (steps, 1))


def test_do_nothing_never_succeeds(scene: Scene) -> None:
    for spec in plan(registry.load("object"), 4, seed=8, setup=Setup()):
        outcome = replay(scene, spec, _hold_home(spec))
        assert not succeeded(spec, outcome)
        assert abs(outcome.rise(spec.target)) < 0.005


def test_a_target_that_starts_high_does_not_pass(scene: Scene) -> None:
    spec = plan(registry.load("object"), 1, seed=8, setup=Setup())[0]
    raised = tuple(
        dataclasses.replace(o, pos=(o.pos[0], o.pos[1], o.pos[2] + 0.12)) if o.id == spec.target else o for o in spec.objects
    )
    high = dataclasses.replace(spec, objects=raised)
    assert not succeeded(high, replay(scene, high, _hold_home(high)))


def test_grasping_the_wrong_object_fails(scene: Scene, ik: ArmIK) -> None:
    spec = plan(registry.load("object"), 1, seed=8, setup=Setup())[0]
    decoy = spec.counterfactuals[0].target

    def wrong(skills: Skills, s: EpisodeSpec) -> None:
        skills.grasp(decoy)
        skills.lift()

    demo = demonstrate(scene, ik, spec, wrong)
    assert demo.outcome is not None and demo.outcome.rise(decoy) > 0.05
    assert not demo.success


def test_replay_from_recorded_state_lifts_the_same_target(object_dataset: Path) -> None:
    records = scenes.read(object_dataset)
    data = parquet.read(object_dataset / "data")
    for _, rec in records.iterrows():
        spec = EpisodeSpec.from_json(rec["spec"])
        actions = np.stack(data[data.episode_index == rec["episode_index"]]["action"].to_numpy())
        scene = scene_for(spec.assets)
        scene.reset(spec)
        scene.set_physics_state(np.asarray(rec["initial_state"]))
        start = {o.id: scene.object_pos(o.id) for o in spec.objects}
        for action in actions:
            scene.step(action)
        rise = {k: scene.object_pos(k)[2] - v[2] for k, v in start.items()}
        assert rise[spec.target] >= spec.task.lift_margin
        assert all(r < spec.task.lift_margin for k, r in rise.items() if k != spec.target)


def test_failed_demos_are_resampled_with_the_same_roles(ik: ArmIK) -> None:
    ref = registry.load("object")
    design = designs(ref, 1, seed=0)[0]
    a = realize(ref, design, 0, 0, Setup(), attempt=0)
    b = realize(ref, design, 0, 0, Setup(), attempt=1)
    assert [(o.id, o.slot) for o in a.objects] == [(o.id, o.slot) for o in b.objects]
    assert a.target == b.target and a.instruction == b.instruction
    assert a.scene_hash != b.scene_hash


def test_producer_records_what_it_verified() -> None:
    ref = registry.load("object")
    setup = Setup(image_size=32)
    producer = Producer(ref, setup)
    produced = producer.produce(designs(ref, 1, seed=5)[0], 0, 5, max_attempts=3)
    ep = produced.episode
    assert ep.states.shape == (ep.length, 16) and ep.actions.shape == (ep.length, 8)
    assert set(ep.videos) == {"agentview", "wrist"}
    assert produced.outcome.rise(produced.spec.target) >= 0.05
    # the first recorded state is the robot at home
    np.testing.assert_allclose(ep.states[0, :7], setup.robot_home, atol=1e-6)
    producer.close()
