"""The reference study's Figure 9 as a measurement's illustration: one switch row of an exam (the
same state, the same instruction changed at the same step) taken by each checkpoint in our
simulator, its camera frames side by side, a row of frames per checkpoint.

    python scripts/switch_picture.py exam=<exam> 'policies=[ckpt:A,ckpt:B]' 'names=[without,with]' \
        [row=<exam row>] [replan=5] [out=docs/switch_course.png]

`row` is a switch row of the exam (default: the first). The frames are the first, the switch's,
and three evenly spaced after it, up to where the longer rollout ended. Each rollout is judged as
the exam judges a switch row (where it landed: the newly named object, or on to the original) and
says so beside its row.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.exam import SWITCH, read
from core.spec import EpisodeSpec
from eval.policies import Context, Policy
from eval.policies.registry import make
from eval.scoring.score import judge, landed
from eval.sims.rollout import Runner
from jobs.cli import UserError, main

AFTER = 3  # frames shown after the switch's


@dataclass
class PictureOptions:
    exam: str = ""
    policies: list[str] = field(default_factory=list)  # two or more: ckpt:<folder>, or any policy the exam takes
    names: list[str] = field(default_factory=list)  # a label per policy (default: the policies)
    row: int | None = None  # the switch row shown (default: the exam's first)
    replan: int = 5  # a checkpoint's actions executed from each predicted chunk
    out: str = "docs/switch_course.png"


class Watched:
    """A policy shown every frame (its chunks unchanged: a chunk being executed ignores the frame),
    keeping the first camera's picture at each step."""

    def __init__(self, policy: Policy, key: str) -> None:
        self.policy, self.key, self.frames = policy, key, []
        self.name, self.needs_images = policy.name, True

    def reset(self, context: Context) -> None:
        self.frames = []
        self.policy.reset(context)

    def act(self, observation: dict) -> np.ndarray | None:
        self.frames.append(observation[self.key])
        return self.policy.act(observation)


def picture(options: PictureOptions) -> None:
    if len(options.policies) < 2 or (options.names and len(options.names) != len(options.policies)):
        raise UserError(f"policies must name two or more policies (and names one label each), got {options.policies}")
    exam = read(options.exam)
    switches = exam.trials[exam.trials["face"] == "switch"]
    if switches.empty:
        raise UserError(f"exam={options.exam} has no switch rows")
    if options.row is not None and options.row not in set(switches["row"]):
        raise UserError(f"row={options.row} is not a switch row of exam={options.exam}")
    row = switches.iloc[0] if options.row is None else switches[switches["row"] == options.row].iloc[0]
    spec = EpisodeSpec.from_json(row["spec"])
    key = spec.setup.interface.image_key(spec.setup.cameras[0])
    switch = json.loads(row[SWITCH])
    taken = []
    for name in options.policies:
        options_ = {"replan": options.replan} if name.startswith("ckpt:") else {}
        watched = Watched(make(name, **options_), key)
        runner = Runner(watched)
        log = runner.run(row)
        runner.close()
        objects = {k: np.asarray(v) for k, v in log.objects.items()}
        turns = {k: np.asarray(v) for k, v in log.turns.items()}
        on = landed(judge(exam, row, np.asarray(log.ee), objects, turns=turns))
        taken.append((watched.frames, on, log.error))
    _draw(options, row, switch, taken)
    print(f"wrote {options.out}")


def _draw(options: PictureOptions, row, switch: dict, taken: list) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    longest, at = max(len(frames) for frames, _, _ in taken), int(switch["step"])
    steps = [0, at, *np.linspace(at, longest - 1, AFTER + 1)[1:].round().astype(int).tolist()]
    names = options.names or options.policies
    fig, axes = plt.subplots(len(taken), len(steps), figsize=(2.2 * len(steps), 2.5 * len(taken)), squeeze=False)
    asked, original = (row["target"], row["program"]), (row["original_target"], row["original_program"])
    for i, ((frames, on, error), name) in enumerate(zip(taken, names)):
        for j, t in enumerate(steps):
            ax = axes[i][j]
            ax.imshow(frames[min(t, len(frames) - 1)])
            ax.set_xticks([]), ax.set_yticks([])
            if i == 0:
                ax.set_title(f"step {t}" + (": switch" if t == at else ""), fontsize=9)
        verdict = {asked: "obeyed the switch", original: "went on to the original"}.get(on, error or "landed on neither")
        axes[i][0].set_ylabel(f"{name}\n{verdict}", fontsize=9)
    fig.suptitle(f"\u201c{row['instruction']}\u201d \u2192 at step {at}: \u201c{switch['instruction']}\u201d", fontsize=10)
    fig.tight_layout()
    Path(options.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(options.out, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main("python scripts/switch_picture.py", PictureOptions, picture, doc=__doc__))
