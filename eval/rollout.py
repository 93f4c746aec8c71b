"""Running one exam rollout in our simulator, and the log it leaves.

The log is what the scorer reads, ours or another lab's: per rollout the end-effector position
and every object's position at each control step (step 0 is the initial state), the number of
steps taken and, when the rollout broke, why. rollouts.parquet columns: row (int), steps (int),
ee (list of [x, y, z]), objects (JSON `{id: [[x, y, z], ...]}`), error (str or null), and
optionally located ([x, y, z] or null: where a policy that says so — it has `locate(observation)`
— believes the named object stands, asked on the first frame; the grounding readout).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from core.layout import IMAGE_PREFIX, LAYOUTS, NATIVE, STATE_KEY, TASK_KEY, FeatureLayout
from core.spec import EpisodeSpec
from eval.policies import Context, Policy
from eval.registry import make
from oracle.render import Cameras
from oracle.scene import Scene, spec_scene

if TYPE_CHECKING:
    from gen.partial import Partial


@dataclass
class Log:
    row: int
    ee: list[list[float]] = field(default_factory=list)
    objects: dict[str, list[list[float]]] = field(default_factory=dict)
    error: str | None = None
    located: list[float] | None = None

    @property
    def steps(self) -> int:
        return max(len(self.ee) - 1, 0)

    def record(self, scene: Scene) -> None:
        self.ee.append([float(v) for v in scene.ee_pos()])
        for k, pos in scene.positions().items():
            self.objects.setdefault(k, []).append(list(pos))

    def to_row(self) -> dict:
        return {
            "row": self.row,
            "steps": self.steps,
            "ee": self.ee,
            "objects": json.dumps(self.objects),
            "error": self.error,
            "located": self.located,
        }


def observe(scene: Scene, cameras: Cameras | None, instruction: str, occluded: bool) -> dict:
    obs: dict = {STATE_KEY: scene.state().astype(np.float32), TASK_KEY: instruction}
    if cameras is not None:
        for cam, image in cameras.render().items():
            obs[IMAGE_PREFIX + cam] = np.zeros_like(image) if occluded else image.copy()
    return obs


class ProfileMismatch(ValueError):
    """The policy speaks another profile than the exam (e.g. joint targets on a libero exam):
    no rollout can succeed, so the whole exam stops with this one line."""


def check_action(action: object, features: FeatureLayout = NATIVE) -> tuple[np.ndarray | None, str | None]:
    """A valid action of the `features` profile, or the reason it is not one; an action of
    another profile's shape raises ProfileMismatch."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        return None, f"action is not numeric ({type(action).__name__})"
    if a.shape != (features.action_size,):
        other = [f for f in LAYOUTS.values() if (f.action_size,) == a.shape and f is not features]
        if other:
            raise ProfileMismatch(
                f"the policy returns {other[0].name}-profile actions of shape {a.shape}, but this exam is profile "
                f"{features.name}: {features.action_size}-d actions ({features.action_meaning})"
            )
        return None, f"action has shape {a.shape}, expected ({features.action_size},)"
    if not np.all(np.isfinite(a)):
        return None, "action contains NaN or inf"
    return a.astype(np.float32), None


class Runner:
    """Runs rollouts for one policy, keeping a renderer per scene when the policy needs images."""

    def __init__(self, policy: Policy) -> None:
        self.policy = policy
        self._cameras: dict[tuple, Cameras] = {}

    def cameras(self, scene: Scene, spec: EpisodeSpec) -> Cameras | None:
        if not self.policy.needs_images:
            return None
        key = (scene, spec.sim.image_size, spec.sim.cameras)  # a scene per inventory, profile, world and look
        if key not in self._cameras:
            self._cameras[key] = Cameras(scene, spec.sim.image_size, spec.sim.cameras)
        return self._cameras[key]

    def run(self, row: pd.Series) -> Log:
        spec = EpisodeSpec.from_json(row["spec"])
        log = Log(int(row["row"]))
        start = np.asarray(row["initial_state"])
        context = Context(spec, str(row["instruction"]), str(row["target"]), str(row["program"]), int(row["row"]), start)
        try:
            self.policy.reset(context)
        except Exception as exc:  # a broken policy fails its rollout, not the run
            log.error = f"policy reset failed: {type(exc).__name__}: {exc}"
            return log
        features = spec.sim.layout
        scene = spec_scene(spec)
        scene.reset(spec)
        scene.set_physics_state(start)
        cameras = self.cameras(scene, spec)
        log.record(scene)
        for _ in range(features.settle_steps):  # as the profile's own environment starts a rollout
            scene.step(features.hold_action(spec.sim.robot_home))
            log.record(scene)
        locate = getattr(self.policy, "locate", None)
        for t in range(int(row["max_steps"])):
            observation = observe(scene, cameras, context.instruction, bool(row["occluded"]))
            try:
                if t == 0 and locate is not None:
                    log.located = [float(v) for v in locate(observation)]
                action = self.policy.act(observation)
            except ProfileMismatch:
                raise
            except Exception as exc:
                log.error = f"step {t}: policy raised {type(exc).__name__}: {exc}"
                break
            if action is None:
                break
            action, problem = check_action(action, features)
            if problem:
                log.error = f"step {t}: {problem}"
                break
            scene.step(action)
            log.record(scene)
        return log

    def close(self) -> None:
        for cams in self._cameras.values():
            cams.close()


def run_chunk(policy_name: str, rows: pd.DataFrame, options: dict | None, partial: Partial) -> None:
    """A worker process's share of an exam: its own policy, scenes and renderers; each rollout is
    saved to the partial run as soon as it ends, so an interrupted take keeps it."""
    runner = Runner(make(policy_name, **(options or {})))
    for _, row in rows.iterrows():
        partial.save(int(row["row"]), runner.run(row).to_row())
    runner.close()
