"""Running one exam rollout in our simulator, and the log it leaves.

The log is what the scorer reads, ours or another lab's: per rollout the end-effector position
and every object's position at each control step (step 0 is the initial state), the number of
steps taken and, when the rollout broke, why. rollouts.parquet columns: row (int), steps (int),
ee (list of [x, y, z]), objects (JSON `{id: [[x, y, z], ...]}`), error (str or null), and
optionally located ([x, y, z] or null: where a policy that says so — it has `locate(observation)`
— believes the named object stands, asked on the first frame; the grounding readout),
predicted ([column, row] or null: where a policy that says so — it has `predicted()` — predicts its
motion will go, in the agentview frame's pixels, with its first action chunk; the prediction face) and
sim_success (bool: a simulator's own verdict on the row's ask at the end, where it has one: LIBERO's
predicates under `sim=libero`).
"""

from __future__ import annotations

import json
from typing import Protocol

import numpy as np
import pandas as pd

from core.exam import goal_of, switch_of
from core.profiles import IMAGE_PREFIX, NATIVE, PROFILES, STATE_KEY, TASK_KEY, Profile
from core.spec import EpisodeSpec
from eval.policies import Context, Policy
from eval.sims.log import Log
from oracle.render import Cameras, cameras_for, release
from oracle.scene import Scene, spec_scene


def observe(scene: Scene, cameras: Cameras | None, instruction: str, occluded: bool) -> dict:
    obs: dict = {STATE_KEY: scene.state().astype(np.float32), TASK_KEY: instruction}
    if cameras is not None:
        for cam, image in cameras.render().items():
            obs[IMAGE_PREFIX + cam] = np.zeros_like(image) if occluded else image.copy()
    return obs


class SimError(RuntimeError):
    """The simulator failed on a row (not the policy): that rollout breaks, the take goes on."""


class ProfileMismatch(ValueError):
    """The policy speaks another profile than the exam (e.g. joint targets on a libero exam):
    no rollout can succeed, so the whole exam stops with this one line."""


def check_action(action: object, features: Profile = NATIVE) -> tuple[np.ndarray | None, str | None]:
    """A valid action of the `features` profile, or the reason it is not one; an action of
    another profile's shape raises ProfileMismatch."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        return None, f"action is not numeric ({type(action).__name__})"
    if a.shape != (features.action_size,):
        other = [f for f in PROFILES.values() if (f.action_size,) == a.shape and f is not features]
        if other:
            raise ProfileMismatch(
                f"the policy returns {other[0].name}-profile actions of shape {a.shape}, but this exam is profile "
                f"{features.name}: {features.action_size}-d actions ({features.action_meaning})"
            )
        return None, f"action has shape {a.shape}, expected ({features.action_size},)"
    if not np.all(np.isfinite(a)):
        return None, "action contains NaN or inf"
    return a.astype(np.float32), None


def check_prediction(predicted: object, size: int) -> tuple[list[float] | None, str | None]:
    """A prediction as the log records it — the point [column, row] in the agentview frame's
    pixels (a heat map (size, size) gives its peak's centre) — or the reason it is not one."""
    try:
        p = np.asarray(predicted, dtype=np.float64)
    except (TypeError, ValueError):
        return None, f"prediction is not numeric ({type(predicted).__name__})"
    if p.shape == (size, size):
        if not np.all(np.isfinite(p)):
            return None, "prediction heat map contains NaN or inf"
        row, column = np.unravel_index(int(np.argmax(p)), p.shape)
        return [column + 0.5, row + 0.5], None
    if p.shape != (2,):
        return None, (
            f"prediction has shape {p.shape}: expected a point [column, row] (2,) or a heat map ({size}, {size}) "
            "over the agentview frame"
        )
    if not np.all(np.isfinite(p)):
        return None, f"prediction {p.tolist()} is not a finite point"
    # a point off the frame is a prediction, not a broken one: an object at the frame's edge has its
    # centre outside it (scored by the nearest object pixel, eval/scoring/score.py), a far one misses
    return [float(v) for v in p], None


class Simulator(Protocol):
    """Where a rollout runs: it starts a row, steps an action, says where the hand and the objects
    are, observes as the exam's profile records, and may judge the row's ask itself."""

    name: str

    def begin(self, row: pd.Series, spec: EpisodeSpec, render: bool) -> None: ...

    def step(self, action: np.ndarray) -> None: ...

    def ee_pos(self) -> np.ndarray: ...

    def positions(self) -> dict[str, tuple[float, ...]]: ...

    def turns(self) -> dict[str, tuple[float, ...]]: ...

    def observe(self, instruction: str, occluded: bool, images: bool) -> dict: ...

    def verdict(self, row: pd.Series) -> bool | None: ...

    def close(self) -> None: ...


class OurSim:
    """Our rebuild of the exam's world (oracle/scene.py): where exams run unless `sim=libero` says
    LIBERO's own simulator (eval/sims/libero.py, the same methods). A renderer is kept per scene."""

    name = "ours"

    def __init__(self) -> None:
        self._cameras: dict[tuple, Cameras] = {}
        self.scene: Scene | None = None
        self.cameras: Cameras | None = None

    def begin(self, row: pd.Series, spec: EpisodeSpec, render: bool) -> None:
        """Put the row's scene in its trial's recorded initial state."""
        self.scene = scene = spec_scene(spec)
        scene.reset(spec)
        scene.set_physics_state(np.asarray(row["initial_state"]))
        self.cameras = None
        if render:
            key = (scene, spec.setup.image_size, spec.setup.cameras)  # a scene per inventory, profile, world and look
            if key not in self._cameras:
                self._cameras[key] = cameras_for(scene, spec.setup.image_size, spec.setup.cameras)
            self.cameras = self._cameras[key]

    def step(self, action: np.ndarray) -> None:
        self._scene.step(action)

    def ee_pos(self) -> np.ndarray:
        return self._scene.ee_pos()

    def positions(self) -> dict[str, tuple[float, float, float]]:
        return self._scene.positions()

    def turns(self) -> dict[str, tuple[float, ...]]:
        return self._scene.turns()

    def observe(self, instruction: str, occluded: bool, images: bool) -> dict:
        return observe(self._scene, self.cameras if images else None, instruction, occluded)

    def verdict(self, row: pd.Series) -> bool | None:
        """The simulator's own judgement of the row's ask: ours is the scorer's, from the log."""
        return None

    @property
    def _scene(self) -> Scene:
        assert self.scene is not None, "begin() a row first"
        return self.scene

    def close(self) -> None:
        for cams in self._cameras.values():
            release(cams)
        self._cameras.clear()
        self.cameras = None


class Runner:
    """Runs rollouts for one policy in one simulator. A policy that says its next action will not
    read the observation (`wants_observation()` false: it is executing a chunk) is handed one without
    frames, which are then not drawn."""

    def __init__(self, policy: Policy, sim: Simulator | None = None) -> None:
        self.policy = policy
        self.sim = sim or OurSim()

    def run(self, row: pd.Series) -> Log:
        spec = EpisodeSpec.from_json(row["spec"])
        log = Log(int(row["row"]))
        start = np.asarray(row["initial_state"])
        switch = switch_of(row)
        at = (int(switch["step"]), str(switch["instruction"])) if switch else None
        target, program = str(row["target"]), str(row["program"])
        goal = goal_of(json.loads(row["alternatives"]), target, program)
        context = Context(spec, str(row["instruction"]), target, program, int(row["row"]), start, at, goal)
        try:
            self.policy.reset(context)
        except Exception as exc:  # a broken policy fails its rollout, not the run
            log.error = f"policy reset failed: {type(exc).__name__}: {exc}"
            return log
        features, sim, render = spec.setup.interface, self.sim, self.policy.needs_images
        try:
            sim.begin(row, spec, render)
            log.record(sim)
            for _ in range(features.settle_steps):  # as the profile's own environment starts a rollout
                sim.step(features.hold_action(spec.setup.robot_home))
                log.record(sim)
        except SimError as exc:
            log.error = f"the simulator could not start the row: {exc}"
            return log
        locate = getattr(self.policy, "locate", None)
        predicted = getattr(self.policy, "predicted", None)
        wants = getattr(self.policy, "wants_observation", None)
        instruction = context.instruction
        for t in range(int(row["max_steps"])):
            if at is not None and t == at[0]:  # a switch row: from here on the policy is shown the new instruction
                instruction = at[1]
            images = render and (wants is None or wants() or (t == 0 and locate is not None))
            observation = sim.observe(instruction, bool(row["occluded"]), images)
            try:
                if t == 0 and locate is not None:
                    log.located = [float(v) for v in locate(observation)]
                action = self.policy.act(observation)
                if t == 0 and predicted is not None:  # the prediction made with the first chunk
                    made = predicted()
                    if made is not None:
                        log.predicted, problem = check_prediction(made, spec.setup.image_size)
                        if problem:
                            log.error = f"step 0: {problem}"
                            break
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
            try:
                sim.step(action)
            except SimError as exc:
                log.error = f"step {t}: the simulator failed: {exc}"
                break
            log.record(sim)
        if not log.error:
            log.sim_success = sim.verdict(row)
        return log

    def close(self) -> None:
        self.sim.close()
