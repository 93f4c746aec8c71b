"""The exam as a gymnasium environment, for labs that roll out in their own loop.

    import gymnasium as gym
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam="datasets/object-exam", trial=3, face="swap", variant=1)
    obs, info = env.reset()          # info["instruction"] is the rollout's instruction
    obs, reward, terminated, truncated, info = env.step(action)

Each environment is one row of the exam (`row=` or `trial=`/`face=`/`variant=`): the trial's
scene rebuilt at its recorded initial state, with its cameras (blank on the occ face). The
observation has the dataset's keys; the action is the dataset's, in the exam's profile (native:
7 joint targets + gripper; libero: a 7-d end-effector delta through OSC_POSE, and reset first
runs the settle steps lerobot's LIBERO environment runs).
`reward` is 1.0 while the asked-for program is achieved; the episode truncates at the row's
horizon. On a switch row `info["instruction"]` (and what the policy should be given) changes at
the row's switch step. `info` carries the instruction, the row, its horizon and the end-effector
and object
positions the offline scorer takes (`python -m eval.score`) — never the answer: what the row
asks for stays in the exam's answers.parquet, which only the scorer (and this reward) reads.
The id is registered by the `deconfound_exam` module (a name no lab's folder shadows).
close() hands the environment's renderer to the next one made of the same scene in the process,
which then skips the renderer's start (about 0.5 s for a LIBERO scene on a CPU).
"""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
from gymnasium import spaces

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)
from core.exam import Exam, goal_of, read, switch_of
from core.profiles import STATE_KEY
from core.programs import achieved
from core.spec import EpisodeSpec
from core.success import Outcome
from eval.sims.rollout import check_action, observe
from oracle.render import Cameras, cameras_for, release
from oracle.scene import spec_scene


class ExamEnv(gym.Env):
    metadata = {"render_modes": ["rgb_array"]}

    def __init__(
        self,
        exam: str | Path | Exam,
        row: int | None = None,
        trial: int | None = None,
        face: str = "task",
        variant: int = 0,
        render_mode: str | None = None,
    ) -> None:
        self.exam = exam if isinstance(exam, Exam) else read(exam)
        trials = self.exam.trials
        if row is None:
            match = trials[(trials.trial == trial) & (trials.face == face) & (trials.variant == variant)]
            if match.empty:
                raise ValueError(f"the exam has no rollout trial={trial} face={face} variant={variant}")
            self.row = match.iloc[0]
        else:
            match = trials[trials["row"] == row]
            if match.empty:
                raise ValueError(f"the exam has rows {trials['row'].min()}..{trials['row'].max()}, not row={row}")
            self.row = match.iloc[0]
        self.episode = EpisodeSpec.from_json(self.row["spec"])
        self.render_mode = render_mode
        size = self.episode.setup.image_size
        self.features = features = self.episode.setup.interface
        self.observation_space = spaces.Dict(
            {
                **{features.image_key(c): spaces.Box(0, 255, (size, size, 3), np.uint8) for c in self.episode.setup.cameras},
                STATE_KEY: spaces.Box(-np.inf, np.inf, (features.state_size,), np.float32),
            }
        )
        self.action_space = spaces.Box(np.array(features.action_low, np.float32), np.array(features.action_high, np.float32))
        self.scene = spec_scene(self.episode)
        self.cameras: Cameras | None = cameras_for(self.scene, size, self.episode.setup.cameras)
        self._t = 0
        self._start: dict = {}

    @property
    def instruction(self) -> str:
        """The instruction shown now: the row's, or on a switch row from its step on the new one."""
        switch = switch_of(self.row)
        return switch["instruction"] if switch and self._t >= switch["step"] else str(self.row["instruction"])

    def _obs(self) -> dict:
        obs = observe(self.scene, self.cameras, self.instruction, bool(self.row["occluded"]))
        obs.pop("task")
        return obs

    def _info(self) -> dict:
        return {
            "instruction": self.instruction,
            "row": int(self.row["row"]),
            "max_steps": int(self.row["max_steps"]),
            "ee": self.scene.ee_pos(),
            "objects": self.scene.positions(),
        }

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        super().reset(seed=seed)
        self.scene.reset(self.episode)
        self.scene.set_physics_state(np.asarray(self.row["initial_state"]))
        self._start = self.scene.positions()
        self.scene.settle(self.episode)
        self._t = 0
        return self._obs(), self._info()

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        valid, problem = check_action(action, self.features)
        if problem:
            raise ValueError(problem)
        self.scene.step(valid)
        self._t += 1
        outcome = Outcome(self._start, self.scene.positions(), tuple(self.scene.ee_pos()), self.scene.turns())
        asked = (self.row["target"], self.row["program"])
        done = achieved(self.episode, outcome, *asked, goal_of(json.loads(self.row["alternatives"]), *asked))
        info = {**self._info(), "achieved": done}
        return self._obs(), float(done), False, self._t >= int(self.row["max_steps"]), info

    def render(self) -> np.ndarray:
        return self.cameras.render()[self.episode.setup.cameras[0]].copy()

    def close(self) -> None:
        """The cameras go back to the process's spares, for the next row's environment of this scene."""
        if self.cameras is not None:
            release(self.cameras)
            self.cameras = None
