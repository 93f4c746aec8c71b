"""A policy served over the openpi websocket protocol (`openpi-client`), so any served VLA can
take the exam.

`keys=dataset` (default): each query sends the observation dict (the dataset's keys, images as
H x W x 3 uint8) plus `prompt` (the instruction) and expects `{"actions": array (H, A)}`; the
first `replan` actions of each chunk are executed before the next query. A server whose policy
predicts where its motion will go may add `"prediction"` to the response: a point [column, row] in
the agentview frame's pixels, or a heat map (H, W) over that frame; the one sent with the first
chunk is scored by the prediction face (docs/EXAM_FORMAT.md).

`keys=libero` (a `profile=libero` exam): each query is what openpi's own LIBERO example client
(examples/libero/main.py) sends — `observation/image` and `observation/wrist_image` (the
frames as LIBERO's datasets hold them, resized with padding to 224 px, uint8),
`observation/state` (the 8-d state, float64 as robosuite reports it) and `prompt` — and the
first 5 actions of each returned chunk are executed, as that client does; so an unmodified
`serve_policy.py --env LIBERO` server can take the exam.
"""

from __future__ import annotations

import socket

import numpy as np

from core.profiles import LIBERO, STATE_KEY, TASK_KEY
from eval.policies import Context, PolicyError

KEYS = ("dataset", "libero")
LIBERO_CLIENT_SIZE, LIBERO_REPLAN = 224, 5  # openpi's examples/libero/main.py: resize_size, replan_steps


def libero_request(observation: dict) -> dict:
    """An observation of a libero-profile exam as openpi's LIBERO example client sends it."""
    from openpi_client import image_tools

    front, wrist = (observation[LIBERO.image_key(c)] for c in LIBERO.camera_names)
    size = LIBERO_CLIENT_SIZE
    return {
        "observation/image": image_tools.convert_to_uint8(image_tools.resize_with_pad(front, size, size)),
        "observation/wrist_image": image_tools.convert_to_uint8(image_tools.resize_with_pad(wrist, size, size)),
        "observation/state": np.asarray(observation[STATE_KEY], np.float64),
        "prompt": str(observation[TASK_KEY]),
    }


class RemotePolicy:
    argument = "HOST:PORT"  # written remote:HOST:PORT (eval/policies/registry.py)
    needs_images = True

    def __init__(self, address: str, keys: str = "dataset", replan: int = 5, timeout: float = 5.0) -> None:
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise PolicyError(f"remote policy address must be HOST:PORT, got {address!r}")
        if keys not in KEYS:
            raise PolicyError(f"keys must be one of {', '.join(KEYS)}, got {keys!r}")
        self.name = f"remote:{address}"
        self.keys = keys
        self.replan = LIBERO_REPLAN if keys == "libero" else replan
        try:
            socket.create_connection((host, int(port)), timeout=timeout).close()
        except OSError as exc:
            raise PolicyError(f"policy server {host}:{port} is unreachable ({exc.strerror or exc})") from None
        from openpi_client.websocket_client_policy import WebsocketClientPolicy

        try:
            self._client = WebsocketClientPolicy(host=host, port=int(port))
        except Exception as exc:  # the websocket handshake can fail in many ways
            raise PolicyError(f"policy server {host}:{port} did not complete the openpi handshake: {exc}") from None
        self._queue: list[np.ndarray] = []
        self._predicted: object = None

    def reset(self, context: Context) -> None:
        self._queue = []
        self._predicted = None
        self._client.reset()

    def predicted(self) -> object:
        """The `prediction` the server sent with its last chunk, if any."""
        return self._predicted

    def wants_observation(self) -> bool:
        """Whether the next act() reads its observation: not while it executes a chunk (the runner
        then draws no frames)."""
        return not self._queue

    def act(self, observation: dict) -> np.ndarray:
        if not self._queue:
            if self.keys == "libero":
                obs = libero_request(observation)
            else:
                obs = {k: v for k, v in observation.items() if k != TASK_KEY}
                obs["prompt"] = observation[TASK_KEY]
            response = self._client.infer(obs)
            self._predicted = response.get("prediction")
            chunk = np.asarray(response["actions"], dtype=np.float32)
            chunk = chunk.reshape(-1, chunk.shape[-1]) if chunk.ndim > 1 else chunk[None]
            self._queue = list(chunk[: self.replan])
        return self._queue.pop(0)
