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
    import torch

    from train import data
    from train.policy import load

    frames = data.load(options.dataset)
    later = frames.aim != frames.episode if frames.aim is not None else np.zeros(len(frames), bool)
    if not later.any():
        raise UserError(f"{options.dataset} has no switched episodes (python -m gen ... switched=<share>)")
    index = np.arange(len(frames))
    switches = [int(index[(frames.episode == ep) & later][0]) for ep in np.unique(frames.episode[later])]
    print(f"{len(switches)} switched episodes in {options.dataset}")
    print("| checkpoint | frame | cos(new, oracle) | cos(old, oracle) | rise: oracle | new | old | new the nearer |")
    print("|---|---|---|---|---|---|---|---|")
    for policy in options.policies:
        model, _ = load(policy.removeprefix("ckpt:"))
        model.eval()
        embedded: dict[int, torch.Tensor] = {}
        for offset in options.offsets:
            rows = []
            for s in switches:
                i = min(s + offset, int(frames.ends[frames.episode[s]]) - 1)
                images = {c: torch.from_numpy(np.array(frames.images[c][i]))[None] for c in model.cameras}
                state = torch.from_numpy(frames.state[i].astype(np.float32))[None]
                moved = {}
                for name, task in (("new", int(frames.task[i])), ("old", int(frames.task[s - 1]))):
                    if task not in embedded:
                        with torch.inference_mode():
                            embedded[task] = model.embed([frames.tasks[task]])
                    with torch.inference_mode():
                        actions, _, _ = model(images, state, embedded[task])
                    moved[name] = model.denormalise(actions)[0].numpy()[: options.replan, :3].sum(0)
                oracle = frames.action[i : i + options.replan, :3].sum(0)
                new, old = _cosine(moved["new"], oracle), _cosine(moved["old"], oracle)
                rows.append((new, old, oracle[2], moved["new"][2], moved["old"][2], new > old))
            m = np.median(np.array(rows, float), axis=0)
            nearer = np.mean([r[5] for r in rows])
            cells = f"{m[0]:.2f} | {m[1]:.2f} | {m[2]:+.2f} | {m[3]:+.2f} | {m[4]:+.2f} | {nearer:.0%}"
            print(f"| {policy} | switch+{offset} | {cells} |")


if __name__ == "__main__":
    sys.exit(main("python scripts/switch_probe.py", ProbeOptions, probe, doc=__doc__))
