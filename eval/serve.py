"""Serve a policy over the openpi websocket protocol, the other side of `python -m eval policy=remote:HOST:PORT`.

python -m eval.serve policy=ckpt:<dir> [host=127.0.0.1] [port=8000]

The protocol (openpi-client's): on connect the server sends its metadata (msgpack); then each
message is an observation dict (msgpack-numpy, with `prompt`) answered by `{"actions": (H, 8)}`.
docs/GPU_RECIPE.md shows the same loop around a LeRobot policy (SmolVLA, pi0) on a GPU.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)
from eval.policies import PolicyError
from eval.policies.registry import make
from jobs.cli import Failed, UserError, main


@dataclass
class ServeOptions:
    policy: str  # a policy that predicts action chunks, e.g. ckpt:PATH (eval/policies/registry.py)
    host: str = "127.0.0.1"  # address to listen on
    port: int = 8000  # port to listen on; 0 picks a free one (printed)


def serve(options: ServeOptions) -> None:
    from openpi_client import msgpack_numpy
    from websockets.sync.server import serve as ws_serve

    if not 0 <= options.port <= 65535:
        raise UserError(f"port must be in [0, 65535], got {options.port}")
    try:
        policy = make(options.policy)
    except PolicyError as exc:
        raise UserError(str(exc)) from None
    if not hasattr(policy, "chunk"):
        raise UserError(f"{options.policy} does not predict action chunks; serve a ckpt: policy")
    packer = msgpack_numpy.Packer()

    def handler(ws) -> None:  # noqa: ANN001
        ws.send(packer.pack({"policy": options.policy}))
        for message in ws:
            observation = msgpack_numpy.unpackb(message)
            observation["task"] = observation.pop("prompt", "")
            ws.send(packer.pack({"actions": np.asarray(policy.chunk(observation), np.float32)}))

    try:
        server = ws_serve(handler, options.host, options.port)
    except OSError as exc:
        raise Failed(f"cannot listen on {options.host}:{options.port}: {exc.strerror or exc}") from None
    with server:
        print(f"serving {options.policy} on ws://{options.host}:{server.socket.getsockname()[1]}", flush=True)
        server.serve_forever()


if __name__ == "__main__":
    sys.exit(main("python -m eval.serve", ServeOptions, serve, doc=__doc__))
