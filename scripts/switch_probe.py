"""Whether a checkpoint turns where its training set's switched episodes turn: at each switched
episode's switch frame (and a few frames on), the displacement of the first `replan` actions it
predicts under the new instruction and under the old, beside the oracle's recorded actions. A
policy that fails the switch face may not have reached the exam's state, or may not have learnt
the turn at all; on its own training frames only the second remains.

    python scripts/switch_probe.py dataset=<switched set> 'policies=[ckpt:A,ckpt:B]' [offsets=[0,5]]

Per checkpoint and offset: the median cosine between the predicted and the oracle's displacement
(under the new instruction, under the old), the median rise (the actions' z summed, in the action's units; the
oracle rises over the objects first where the hand is low), and the share of switches where the
new instruction's prediction is the nearer the oracle's.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np

from jobs.cli import UserError, main


@dataclass
class ProbeOptions:
    dataset: str = ""
    policies: list[str] = field(default_factory=list)  # ckpt:<folder>, one or more
    offsets: list[int] = field(default_factory=lambda: [0, 5])  # frames after each switch probed
    replan: int = 5  # the actions summed: what the exam executes of each chunk


def _cosine(u: np.ndarray, v: np.ndarray) -> float:
    return float(u @ v / (np.linalg.norm(u) * np.linalg.norm(v) + 1e-9))


def probe(options: ProbeOptions) -> None:
    if not options.dataset or not options.policies or any(not p.startswith("ckpt:") for p in options.policies):
        raise UserError("needs dataset=<a switched set> and 'policies=[ckpt:<folder>,...]'")
    from core.profiles import STATE_KEY
    from train import data
    from train.policy import CheckpointPolicy

    frames = data.load(options.dataset)
    at = data.switch_frames(frames)
    switches = at[at < len(frames)]
    if not len(switches):
        raise UserError(f"{options.dataset} has no switched episodes (python -m gen ... switched=<share>)")
    print(f"{len(switches)} switched episodes in {options.dataset}")
    print("| checkpoint | frame | cos(new, oracle) | cos(old, oracle) | rise: oracle | new | old | new the nearer |")
    print("|---|---|---|---|---|---|---|---|")
    for name in options.policies:
        policy = CheckpointPolicy(name.removeprefix("ckpt:"))  # the exam's own forward pass
        features = policy.model.config.features
        for offset in options.offsets:
            rows = []
            for s in switches:
                i = min(s + offset, int(frames.ends[frames.episode[s]]) - 1)
                seen = {features.image_key(c): frames.images[c][i] for c in policy.model.cameras} | {STATE_KEY: frames.state[i]}
                new, old = (policy.chunk(seen | {"task": frames.tasks[t]})[: options.replan, :3].sum(0)
                            for t in (frames.task[i], frames.task[s - 1]))  # fmt: skip
                oracle = frames.action[i : i + options.replan, :3].sum(0)
                rows.append((_cosine(new, oracle), _cosine(old, oracle), oracle[2], new[2], old[2]))
            m = np.median(np.array(rows), axis=0)
            nearer = np.mean([r[0] > r[1] for r in rows])
            cells = f"{m[0]:.2f} | {m[1]:.2f} | {m[2]:+.2f} | {m[3]:+.2f} | {m[4]:+.2f} | {nearer:.0%}"
            print(f"| {name} | switch+{offset} | {cells} |")


if __name__ == "__main__":
    sys.exit(main("python scripts/switch_probe.py", ProbeOptions, probe, doc=__doc__))
