"""Checkpoints of the tiny policy, and the policy that takes exams from one (`ckpt:<dir>`).

A checkpoint folder holds `model.pt`: the model config, the dataset stats and the weights that
training changed (the pretrained text tower is rebuilt from its package, then patched).

`CheckpointPolicy` is the `ckpt` entry point of the `deconfound.policies` group (pyproject.toml),
so eval finds it by name without importing train; torch loads only when a checkpoint is read.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from core.profiles import ACTION_KEY, STATE_KEY
from eval.policies import Context, PolicyError, require_features

if TYPE_CHECKING:
    from train.model import TinyPolicy

MODEL_FILE = "model.pt"


class CheckpointError(ValueError):
    pass


def save(path: Path, model: TinyPolicy, extra: dict | None = None) -> None:
    """Atomically write a checkpoint file."""
    import torch

    tmp = path.with_suffix(".tmp")
    torch.save({"config": model.config.to_dict(), "weights": model.trainable_state(), **(extra or {})}, tmp)
    tmp.replace(path)


def load(path: Path | str) -> tuple[TinyPolicy, dict]:
    """A model from a checkpoint folder (or file); returns the model and the whole record."""
    import torch

    from train.model import ModelConfig, TinyPolicy

    path = Path(path)
    file = path / MODEL_FILE if path.is_dir() else path
    if not file.is_file():
        raise CheckpointError(f"no checkpoint at {file}")
    try:
        record = torch.load(file, map_location="cpu", weights_only=False)
        config = ModelConfig(**record["config"])
    except Exception as exc:
        raise CheckpointError(f"{file} is not a tiny-policy checkpoint: {exc}") from None
    weights = record["weights"]
    stats = {
        key: {"mean": weights[f"{name}_mean"].numpy(), "std": weights[f"{name}_std"].numpy()}
        for key, name in ((STATE_KEY, "state"), (ACTION_KEY, "action"))
    }
    model = TinyPolicy(config, stats)
    try:
        missing, unexpected = model.load_state_dict(weights, strict=False)
    except RuntimeError as exc:  # shapes from another version of the model
        raise CheckpointError(f"{file} does not fit the model: {str(exc).splitlines()[-1].strip()}") from None
    if unexpected:
        raise CheckpointError(f"{file} does not fit the model: unexpected weights {unexpected[:3]}")
    model.eval()
    return model, record


class CheckpointPolicy:
    """Runs a checkpoint in the battery: embeds each instruction once, predicts a chunk of
    actions and executes the first `replan` of them before looking again."""

    argument = "PATH"  # written ckpt:PATH (eval/policies/registry.py)
    needs_images = True

    def __init__(self, path: str, replan: int = 5) -> None:
        import torch

        try:
            self.model, record = load(path)
        except CheckpointError as exc:
            raise PolicyError(str(exc)) from None
        # the pointer is a prediction only where training taught it (point_weight > 0; runs before
        # point_weight existed had none); a record without its training config (a resume state) does not say
        train = record.get("train")
        self.prediction_trained = float(train.get("point_weight") or 0) > 0 if isinstance(train, dict) else None
        torch.set_num_threads(1)
        self.name = f"ckpt:{path}"
        self.replan = min(replan, self.model.config.chunk)
        self._embeddings: dict[str, object] = {}
        self._queue: list[np.ndarray] = []
        self._predicted: np.ndarray | None = None

    def check(self, features: dict[str, tuple[int, ...]]) -> None:
        """Refuse an exam whose cameras, frame size, state or action are not this checkpoint's."""
        size, profile = self.model.config.image_size, self.model.config.features
        expected = {profile.image_key(c): (size, size, 3) for c in self.model.cameras}
        expected |= {STATE_KEY: tuple(self.model.state_mean.shape), ACTION_KEY: tuple(self.model.action_mean.shape)}
        require_features(expected, features, f"checkpoint {self.name.removeprefix('ckpt:')}")

    def reset(self, context: Context) -> None:
        self._queue = []
        self._predicted = None

    def chunk(self, observation: dict) -> np.ndarray:
        """The next `chunk` actions (chunk, action size) for an observation dict."""
        actions, _, self._predicted = self._forward(observation)
        return actions

    def _forward(self, observation: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the action chunk, the located target in world coordinates, the pointer's peak as a
        point [column, row] in the agentview frame's pixels) for an observation."""
        import torch

        size, features = self.model.config.image_size, self.model.config.features
        for cam in self.model.cameras:
            shape = observation[features.image_key(cam)].shape
            if shape != (size, size, 3):
                raise ValueError(f"{cam} frames are {shape}, the checkpoint was trained on {size} px")
        text = observation["task"]
        with torch.inference_mode():
            if text not in self._embeddings:
                self._embeddings[text] = self.model.embed([text])
            frames = {c: np.ascontiguousarray(observation[features.image_key(c)]) for c in self.model.cameras}
            images = {c: torch.from_numpy(frame)[None] for c, frame in frames.items()}
            state = torch.from_numpy(np.asarray(observation[STATE_KEY], np.float32))[None]
            actions, located, pointer = self.model(images, state, self._embeddings[text])
        h, w = pointer.shape[1:]
        row, column = np.unravel_index(int(pointer[0].argmax()), (h, w))
        point = np.array([(column + 0.5) * size / w, (row + 0.5) * size / h])  # the cell's centre (train/fit.py point_loss)
        return self.model.denormalise(actions)[0].numpy(), self.model.world_position(located)[0].numpy(), point

    def locate(self, observation: dict) -> np.ndarray:
        """Where the auxiliary head believes the named object stands (world x, y, z): the
        battery's grounding readout, which does not depend on the motor."""
        return self._forward(observation)[1]

    def predicted(self) -> np.ndarray | None:
        """Where the pointer (train/fit.py `point_weight`) says the motion will go, from the
        observation the last chunk was predicted from: the prediction face's readout."""
        return self._predicted

    def wants_observation(self) -> bool:
        """Whether the next act() reads its observation: not while it executes a chunk (the runner
        then draws no frames)."""
        return not self._queue

    def act(self, observation: dict) -> np.ndarray:
        if not self._queue:
            self._queue = list(self.chunk(observation)[: self.replan])
        return self._queue.pop(0)
