"""`python -m eval.serve policy=ckpt:<dir> [host=127.0.0.1] [port=8000]`: serve a policy over the
openpi websocket protocol, the other side of `python -m eval policy=remote:HOST:PORT`.

The protocol (openpi-client's): on connect the server sends its metadata (msgpack); then each
message is an observation dict (msgpack-numpy, with `prompt`) answered by `{"actions": (H, 8)}`.
docs/GPU_RECIPE.md shows the same loop around a LeRobot policy (SmolVLA, pi0) on a GPU.
"""

from __future__ import annotations

import sys

import numpy as np

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)


def serve(policy_name: str, host: str, port: int) -> None:
    from openpi_client import msgpack_numpy
    from websockets.sync.server import serve as ws_serve

    from eval.policies import make

    policy = make(policy_name)
    if not hasattr(policy, "chunk"):
        raise SystemExit(f"error: {policy_name} does not predict action chunks; serve a ckpt: policy")
    packer = msgpack_numpy.Packer()

    def handler(ws) -> None:  # noqa: ANN001
        ws.send(packer.pack({"policy": policy_name}))
        for message in ws:
            observation = msgpack_numpy.unpackb(message)
            observation["task"] = observation.pop("prompt", "")
            ws.send(packer.pack({"actions": np.asarray(policy.chunk(observation), np.float32)}))

    with ws_serve(handler, host, port) as server:
        print(f"serving {policy_name} on ws://{host}:{server.socket.getsockname()[1]}", flush=True)
        server.serve_forever()


def main(argv: list[str]) -> int:
    opts = dict(a.split("=", 1) for a in argv if "=" in a)
    if "policy" not in opts:
        print("usage: python -m eval.serve policy=ckpt:<dir> [host=127.0.0.1] [port=8000]", file=sys.stderr)
        return 2
    serve(opts["policy"], opts.get("host", "127.0.0.1"), int(opts.get("port", 8000)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
