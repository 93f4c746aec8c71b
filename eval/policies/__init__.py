"""Policies that can take an exam: observation dict + instruction in, action out.

Every policy has `name`, `needs_images` (the runner renders cameras only for those that read
them), `reset(context)` at the start of each rollout and `act(observation)`, which returns an
8-vector (joint-position targets 1-7, gripper -1 open / +1 closed) or None to end the rollout.
The observation holds `observation.images.<camera>` (H, W, 3 uint8; all zeros on the occ face;
absent when the policy reads no images), `observation.state` (16 float32) and `task` (the
instruction).

A policy that predicts where its motion will go may have `predicted()`: with the chunk its last
act() planned, a point [column, row] in the agentview frame's pixels or a heat map (H, W) over
that frame (None: no prediction); the runner logs the one made with the first chunk, which the
prediction face scores. The scripted reference policies predict the object their plan acts on.
A policy whose `predicted()` comes from a head it knows was never trained sets
`prediction_trained = False` (a tiny-policy checkpoint trained with point_weight 0): the take
records it and the report labels those rows as no prediction.

A policy that knows which features it was trained on may have `check(features)`: the battery
calls it once, before any rollout, with the exam's `{key: shape}` (`Exam.features`), and it
raises FeatureMismatch naming the first key that does not fit, so a whole exam is not spent on
a checkpoint that cannot read it.

Reference policies validate the instrument and read the answer key in the context, which a
learned policy must ignore:
* `oracle` — plans the asked-for demonstration from the spec (the positive control; it reads
  no camera, so blanking them cannot hurt it);
* `position` — does what the referent's shortcut does: by default, picks up whatever stands
  nearest the canonical slot (the shortcut a position-reading policy learns);
* `named_place` — reads the name only as where its object stood in the confounded data (in LIBERO-Object
  each grocery always stands in its own task's target region, one of two), and fetches whatever
  stands there: the shortcut of a policy that learnt the words as place codes;
* `nothing` — holds the home pose; `random` — a seeded random walk of joint targets.

eval/policies/registry.py makes them (and every other policy) by name.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

import referents.registry
from core import programs, worlds
from core.demo import DemoScript
from core.profiles import ARM_JOINTS, GRIPPER_OPEN, JOINT_HIGH, JOINT_LOW, NATIVE
from core.spec import EpisodeSpec

if TYPE_CHECKING:
    from oracle.episode import Demo


@dataclass(frozen=True)
class Context:
    """What a rollout starts from. `instruction` is all a learned policy may use; the rest is
    the answer key for reference policies."""

    spec: EpisodeSpec
    instruction: str
    target: str
    program: str
    seed: int
    initial_state: np.ndarray | None = None  # the physics state the rollout starts from (None: the spec's poses)
    switch: tuple[int, str] | None = None  # a switch row's (step, instruction from then on): the policy is shown it then
    goal: int = 0  # which goal of a task of more (LIBERO-10's) the row's ask renames (core/exam.py goal_of)


class Policy(Protocol):
    name: str
    needs_images: bool

    def reset(self, context: Context) -> None: ...

    def act(self, observation: dict) -> np.ndarray | None: ...


class PolicyError(RuntimeError):
    """A policy cannot be made or reached (e.g. its server is down); the message says why."""


class FeatureMismatch(ValueError):
    """A policy was trained on other features than the exam offers (camera names, state or
    action size, frame size); the message names the mismatch."""


def require_features(expected: dict[str, tuple[int, ...]], offered: dict[str, tuple[int, ...]], who: str) -> None:
    """Raise FeatureMismatch naming the first feature `who` expects that the exam does not offer
    in that shape."""
    for key, shape in expected.items():
        if key not in offered:
            raise FeatureMismatch(f"{who} expects {key!r}, which this exam does not have (it has {', '.join(offered)})")
        if tuple(shape) != tuple(offered[key]):
            raise FeatureMismatch(f"{who} expects {key!r} of shape {tuple(shape)}, this exam's is {tuple(offered[key])}")


class Scripted:
    """Replays an oracle demonstration planned at reset on a private copy of the scene."""

    needs_images = False

    def __init__(self, name: str) -> None:
        self.name = name
        self._actions: list[np.ndarray] = []
        self._t = 0
        self._planner: dict = {}
        self._heading: tuple[EpisodeSpec, str] | None = None  # the plan's spec and the object it acts on first

    def _actions_for(self, spec: EpisodeSpec, demo: DemoScript, context: Context) -> list[np.ndarray]:
        self._heading = (spec, spec.target)
        return list(self._demo(spec, demo, context).actions)

    def predicted(self) -> np.ndarray | None:
        """The object the plan acts on, where the agentview frame shows it at the start."""
        if self._heading is None:
            return None
        spec, target = self._heading
        where = np.asarray([spec.object(target).pos])
        return worlds.world(spec.setup.world).agentview.project(where, spec.setup.image_size, spec.setup.interface.mirrored)[0]

    def _demo(self, spec: EpisodeSpec, demo: DemoScript, context: Context) -> Demo:
        """The demonstration from where the rollout will start: the trial's initial state after
        the profile's settle steps (its `states`: the physics state before each action)."""
        return self._demonstrate(spec, demo, context.initial_state, spec.setup.interface.settle_steps)

    def _demonstrate(
        self, spec: EpisodeSpec, demo: DemoScript, state: np.ndarray | None, settle: int, prefix: Sequence[np.ndarray] = ()
    ) -> Demo:
        from oracle.episode import demonstrate
        from oracle.ik import ArmIK
        from oracle.scene import Scene

        # a private scene: the runner's stays untouched
        key = (spec.assets, spec.setup.profile, spec.setup.world)
        if key not in self._planner:
            self._planner[key] = (Scene(*key), ArmIK(np.asarray(spec.setup.robot_home), spec.setup.world))
        scene, ik = self._planner[key]
        return demonstrate(scene, ik, spec, demo, state, settle, prefix)

    def act(self, observation: dict) -> np.ndarray | None:
        if self._t >= len(self._actions):
            return None
        self._t += 1
        return self._actions[self._t - 1]


class Oracle(Scripted):
    def __init__(self) -> None:
        super().__init__("oracle")

    def reset(self, context: Context) -> None:
        """The demonstration of what the row asks for; on a switch row, the original ask's until the
        switch, then a new plan of the newly named one from where the arm is then."""
        spec, script = context.spec, referents.registry.demo_of(context.spec.referent)
        asked = spec.asking(context.target, context.program, context.goal)
        if context.switch is None:
            self._actions, self._t = self._actions_for(asked, script, context), 0
            return
        step = context.switch[0]
        self._heading = (spec, spec.target)  # the original ask, until the switch
        before = list(self._demo(spec, script, context).actions[:step])
        then = self._demonstrate(asked, script, context.initial_state, spec.setup.interface.settle_steps, before)
        self._actions, self._t = [*before, *then.actions], 0


class Position(Scripted):
    def __init__(self, name: str = "position") -> None:
        super().__init__(name)

    def _chosen(self, referent: referents.registry.Referent, context: Context) -> EpisodeSpec:
        return referent.shortcut(context.spec)

    def reset(self, context: Context) -> None:
        referent = referents.registry.load(context.spec.referent, world=context.spec.setup.world)
        chosen = self._chosen(referent, context)
        self._actions, self._t = self._actions_for(chosen, programs.perform, context), 0


class NamedPlace(Position):
    """The name read only as a place: fetches whatever stands where the named object always
    stood in the confounded data (the referent's `named_place`; the shortcut where every name shares
    one place)."""

    def __init__(self) -> None:
        super().__init__("named_place")

    def _chosen(self, referent: referents.registry.Referent, context: Context) -> EpisodeSpec:
        placed = referent.named_place(context.spec, context.target)
        return referent.shortcut(context.spec) if placed is None else placed


class Nothing:
    name = "nothing"
    needs_images = False

    def reset(self, context: Context) -> None:
        self._hold = context.spec.setup.interface.hold_action(context.spec.setup.robot_home)

    def act(self, observation: dict) -> np.ndarray:
        return self._hold


class Random:
    """Joint targets (or, under end-effector deltas, small random deltas) wander by a seeded
    random walk; the gripper toggles at random."""

    name = "random"
    needs_images = False

    def reset(self, context: Context) -> None:
        self._rng = np.random.default_rng(context.seed)
        self._deltas = context.spec.setup.interface.controller != NATIVE.controller
        self._q = np.asarray(context.spec.setup.robot_home, float).copy()
        self._gripper = GRIPPER_OPEN

    def act(self, observation: dict) -> np.ndarray:
        if self._deltas:
            arm = np.clip(self._rng.normal(0.0, 0.3, 6), -1.0, 1.0)
        else:
            arm = self._q = np.clip(self._q + self._rng.normal(0.0, 0.05, ARM_JOINTS), JOINT_LOW, JOINT_HIGH)
        if self._rng.random() < 0.05:
            self._gripper = -self._gripper
        return np.array([*arm, self._gripper], np.float32)
