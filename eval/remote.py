"""A policy served over the openpi websocket protocol (`openpi-client`), so any served VLA can
take the exam.

Each query sends the observation dict (the dataset's keys, images as H x W x 3 uint8) plus
`prompt` (the instruction) and expects `{"actions": array (H, 8)}`; the first `replan` actions
of each chunk are executed before the next query. Adapt key names in the server's input
transform (openpi's LIBERO example uses the same pattern).
"""

from __future__ import annotations

import socket

import numpy as np

from eval.policies import Context, PolicyError


class RemotePolicy:
    argument = "HOST:PORT"  # written remote:HOST:PORT (eval/registry.py)
    needs_images = True

    def __init__(self, address: str, replan: int = 5, timeout: float = 5.0) -> None:
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise PolicyError(f"remote policy address must be HOST:PORT, got {address!r}")
        self.name = f"remote:{address}"
        self.replan = replan
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

    def reset(self, context: Context) -> None:
        self._queue = []
        self._client.reset()

    def act(self, observation: dict) -> np.ndarray:
        if not self._queue:
            obs = {k: v for k, v in observation.items() if k != "task"}
            obs["prompt"] = observation["task"]
            chunk = np.asarray(self._client.infer(obs)["actions"], dtype=np.float32)
            chunk = chunk.reshape(-1, chunk.shape[-1]) if chunk.ndim > 1 else chunk[None]
            self._queue = list(chunk[: self.replan])
        return self._queue.pop(0)
