"""One episode from design to writer input, in whichever process runs it.

Demonstrate without cameras, re-realising the poses (same roles) until the oracle's demo
succeeds or the attempts run out; then render the verified demo by restoring its recorded
physics states (no second simulation), encode each camera's frames, and hand the result to the
writer.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from core.spec import EpisodeSpec, Setup
from core.success import Outcome
from gen.lerobot.stats import image_histogram
from gen.lerobot.video import encode_episode
from gen.lerobot.writer import Episode
from gen.planning.plan import realize
from oracle.episode import Demo, demonstrate
from oracle.ik import ArmIK
from oracle.render import Cameras
from oracle.scene import Scene, scene_for
from referents.design import Design
from referents.registry import Referent


@dataclass
class Produced:
    spec: EpisodeSpec  # the realisation whose demo succeeded
    failures: list[str]  # why earlier attempts failed, in order
    episode: Episode
    initial_state: np.ndarray
    outcome: Outcome


class DemoFailed(RuntimeError):
    """Every attempt at an episode failed: the spec is unworkable (the message says why)."""


class Producer:
    """What a process keeps across episodes: compiled scene, IK and renderer."""

    def __init__(
        self, referent: Referent | None, setup: Setup, codec: str = "h264", assets: tuple[tuple[str, int], ...] | None = None
    ) -> None:
        """`referent` may be None for a producer that only records demos of given specs
        (then `assets` names the scene)."""
        self.referent = referent
        self.setup = setup
        self.codec = codec
        inventory = assets if assets is not None else referent.assets()
        self.scene: Scene = scene_for(inventory, setup.profile, setup.world, setup.look)
        self.ik = ArmIK(np.asarray(setup.robot_home), setup.world)
        self._cameras: Cameras | None = None  # made on first use: an exam draws only its first frames' object maps

    @property
    def cameras(self) -> Cameras:
        if self._cameras is None:
            self._cameras = Cameras(self.scene, self.setup.image_size, self.setup.cameras)
        return self._cameras

    def close(self) -> None:
        if self._cameras is not None:
            self._cameras.close()

    def demonstrate(
        self, design: Design, index: int, seed: int, max_attempts: int, split: str = "train"
    ) -> tuple[Demo, list[str]]:
        """The first of `max_attempts` realisations of `design` whose demo succeeds, with why the ones
        before failed. A switched design none of whose realisations the oracle can finish (its second
        ask beyond the oracle from where the first leaves the hand: a bottle held across, asked onto a
        sloping rack) keeps its first instruction: the episode is written unswitched, as an exam
        leaves out a switch row the oracle cannot finish."""
        failures: list[str] = []
        for attempt in range(max_attempts):
            spec = realize(self.referent, design, index, seed, self.setup, attempt, split)
            demo = demonstrate(self.scene, self.ik, spec, self.referent.demo)
            if demo.success:
                return demo, failures
            failures.append(demo.failure)
        if design.switch is not None:
            demo, more = self.demonstrate(replace(design, switch=None), index, seed, max_attempts, split)
            return demo, failures + more
        raise DemoFailed(f"episode {index}: all {max_attempts} oracle attempts failed ({'; '.join(failures)})")

    def produce(self, design: Design, index: int, seed: int, max_attempts: int) -> Produced:
        demo, failures = self.demonstrate(design, index, seed, max_attempts)
        return self.record(demo, failures)

    def record(self, demo: Demo, failures: list[str]) -> Produced:
        """Render a verified demo by restoring its recorded physics states, one per action."""
        spec, actions = demo.spec, demo.actions
        size = self.setup.image_size
        frames = {c: np.empty((len(actions), size, size, 3), np.uint8) for c in self.setup.cameras}
        states = np.empty((len(actions), self.setup.interface.state_size), np.float32)
        self.scene.reset(spec)  # colours and body assignment; the states below carry the rest
        for t, physics in enumerate(demo.states):
            self.scene.set_physics_state(physics)
            states[t] = self.scene.state()
            for cam, image in self.cameras.render().items():
                frames[cam][t] = image
        episode = Episode(
            task=spec.instruction,
            states=states,
            actions=actions,
            videos={c: encode_episode(f, self.setup.fps, self.codec) for c, f in frames.items()},
            histograms={c: image_histogram(f) for c, f in frames.items()},
            switch=None if demo.switch_step is None else (demo.switch_step, spec.after_switch().instruction),
        )
        assert demo.outcome is not None
        return Produced(spec, failures, episode, demo.states[0], demo.outcome)
