"""Switches from a policy's own states: the oracle's course to the second instruction, begun where a
checkpoint's hand actually is when an exam's switch row reaches it (issue 52).

python -m train.turns policy=ckpt:<folder> dataset=<a switched set> out=<folder>

A switched training episode (`gen ... switched=`) changes course from the oracle's own approach.
An exam's switch row changes it from the policy's: at the step where the oracle's hand came within
SWITCH_DISTANCE, the policy's hand is elsewhere (most often over the original grocery and coming
down), and a checkpoint that turns on its training switches did not turn there
(docs/RESULTS_FACES.md). Here, for each switched episode of `dataset`, the policy runs the first
instruction from the episode's scene as an exam rollout does (the profile's settle steps, a chunk
every `replan` actions), up to where it would first read a switch row's new instruction — and,
with `later`, that many chunks beyond — and the oracle, replanning from that very state
(oracle/episode.py `demonstrate` with the policy's actions as its prefix), does the second ask.
Each such course the oracle finishes is one episode: the policy's last action before the switch
(first instruction), then the oracle's (second instruction from frame 1), recorded as a switched
episode (meta/scenes.parquet `switch`), so `python -m train dataset=[<set>,<this>] switched_share=…`
draws its turns as it draws the set's. With `after`, the policy also goes on that many chunks under
the second instruction, as it does in the exam, and the oracle takes over from where that leaves
it (hovering between the two groceries, say): an episode of the second ask alone, begun in that
state, every action in it the oracle's. A DAgger step (Ross et al. 2011) on the switch: the states
the policy visits, the oracle's actions from them.

Resumable (`resume=true`): each episode is kept as it is made (jobs/partial.py), the set appears at
`out` in one rename once all are made, and the same command on a finished set does nothing. `out`
is never a folder of someone else's files; `overwrite=true` replaces only a set this project wrote.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from core.exam import SWITCH_DISTANCE
from core.products import GENERATION_PATH, SCENES_PATH
from core.spec import EpisodeSpec
from eval.policies import Context, PolicyError, registry
from eval.sims.rollout import observe
from gen.lerobot.writer import LeRobotWriter, Recording
from gen.products import scenes
from gen.products.produce import Produced, Producer
from jobs.cli import UserError, main
from jobs.output import check_output
from jobs.partial import Partial, completed
from oracle.episode import Demo, approach_step, demonstrate, joined
from referents import registry as referents

MADE_BY = "python -m train.turns"  # meta/generation.json: which command wrote the set


@dataclass
class TurnsOptions:
    policy: str  # the checkpoint whose states the turns begin from (ckpt:<folder>)
    dataset: str  # a switched set (gen ... switched=<share>): its switched episodes' scenes and second asks
    out: str  # the set of turns it writes
    replan: int | None = None  # a chunking policy's actions executed per predicted chunk, as the exam takes it; default its own
    later: list[int] = field(default_factory=lambda: [0, 1])  # chunks after the exam's switch at which the switch comes
    after: list[int] = field(default_factory=lambda: [0])  # chunks the policy acts under the second instruction before the oracle
    n: int = 0  # the first this many switched scenes (0: all)
    resume: bool = False  # continue an interrupted run with the same options
    overwrite: bool = False  # discard an interrupted run's episodes and begin again


def read_at(step: int, replan: int, later: int) -> int:
    """The step at which a policy that reads its observation every `replan` actions first sees a
    switch made at `step`, `later` chunks on."""
    return (-(-step // replan) + later) * replan


class Turner:
    """What one process keeps across episodes: the source set's producer (scene, IK, cameras) and the policy."""

    def __init__(self, options: TurnsOptions, spec: EpisodeSpec) -> None:
        self.options = options
        chunked = {} if options.replan is None else {"replan": options.replan}
        self.policy = registry.make(options.policy, **chunked)  # torch before any GL context
        self.replan = int(getattr(self.policy, "replan", 1))  # a policy that plans no chunks reads every step
        self.referent = referents.load(spec.referent, world=spec.setup.world)
        self.producer = Producer(self.referent, spec.setup)

    def turns(self, spec: EpisodeSpec) -> list[Produced | str]:
        """Per `later` and `after`, the episode that turns there, or why there is none."""
        p, settle, asked = self.producer, spec.setup.interface.settle_steps, len(self.options.later) * len(self.options.after)
        first, then = replace(spec, switch=None), spec.after_switch()
        oracle = demonstrate(p.scene, p.ik, first, self.referent.demo, None, settle)
        if not oracle.success:
            return [f"the oracle does not finish the first ask ({oracle.failure})"] * asked
        step = approach_step(p.scene, oracle, SWITCH_DISTANCE)
        if not step:
            return ["no approach to switch in"] * asked
        made: list[Produced | str] = []
        for later in self.options.later:
            switched = read_at(step, self.replan, later)
            takeovers = [switched + after * self.replan for after in self.options.after]
            actions, states = self._rollout(first, then.instruction, settle, switched, max(takeovers))
            for at in takeovers:
                course = demonstrate(p.scene, p.ik, then, self.referent.demo, None, settle, actions[:at])
                if not course.success:
                    made.append(f"from the policy's state at step {at} the oracle fails ({course.failure})")
                elif at == switched:  # the switch itself: the policy's last action under the first name, then the turn
                    last = Demo(spec, actions[at - 1 : at], states[at - 1 : at], None, True)
                    made.append(p.record(replace(joined(last, 1, course), spec=spec), []))
                else:  # the policy went on under the second name: from there, the oracle's course alone
                    made.append(p.record(course, []))
        return made

    def _rollout(self, spec: EpisodeSpec, then: str, settle: int, switched: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
        """The policy's first `steps` actions from `spec`'s scene after `settle` held steps, shown
        `spec`'s instruction and from step `switched` on `then`, and the physics state before each."""
        scene, cameras = self.producer.scene, self.producer.cameras
        scene.reset(spec)
        for _ in range(settle):
            scene.step(spec.setup.interface.hold_action(spec.setup.robot_home))
        self.policy.reset(Context(spec, spec.instruction, spec.target, spec.task.program, spec.seed))
        actions, states = [], []
        for t in range(steps):
            states.append(scene.physics_state())
            reads = getattr(self.policy, "wants_observation", lambda: True)()
            shown = spec.instruction if t < switched else then
            action = np.asarray(self.policy.act(observe(scene, cameras if reads else None, shown, False)), np.float32)
            scene.step(action)
            actions.append(action)
        return np.asarray(actions), np.asarray(states)

    def close(self) -> None:
        self.producer.close()


def _check(options: TurnsOptions) -> list[EpisodeSpec]:
    """The source set's switched episodes, or one line saying why there are none to turn."""
    if options.replan is not None and options.replan < 1:
        raise UserError(f"replan must be at least 1, got {options.replan}")
    for name in ("later", "after"):
        counts = getattr(options, name)
        if not counts or min(counts) < 0 or len(set(counts)) != len(counts):
            raise UserError(f"{name} must be distinct chunk counts >= 0, got {counts}")
    root = Path(options.dataset)
    if completed(root) is None or not (root / SCENES_PATH).is_file():
        raise UserError(f"dataset={root} is no finished generated dataset (python -m gen ... switched=<share>)")
    records = scenes.read(root)
    if "switch" not in records:
        raise UserError(f"dataset={root} has no switched episodes: make it with python -m gen ... switched=<share>")
    switched = [EpisodeSpec.from_json(s) for s, w in zip(records["spec"], records["switch"]) if isinstance(w, str)]
    if not switched:
        raise UserError(f"dataset={root} has no switched episodes")
    if options.n < 0:
        raise UserError(f"n must be >= 0, got {options.n}")
    return switched[: options.n or None]


def run(options: TurnsOptions) -> None:
    from tqdm import tqdm

    specs = _check(options)
    out, started = Path(options.out), time.perf_counter()
    record = {k: v for k, v in asdict(options).items() if k not in ("out", "resume", "overwrite")}
    finished = completed(out) if options.resume and not options.overwrite else None
    if finished is not None:  # the same command again: the set is there, nothing is redone or replaced
        if finished.get("made_by") != MADE_BY or finished.get("config") != json.loads(json.dumps(record)):
            raise UserError(f"resume=true, but out={out} holds a finished set made otherwise; pass overwrite=true to replace it")
        print(f"{out} is already complete ({finished['episodes']} episodes, same options); nothing to do")
        return
    check_output(out, options.overwrite)  # never a folder of someone else's files
    try:
        turner = Turner(options, specs[0])  # a policy that cannot be made is refused before anything is written
    except PolicyError as exc:
        raise UserError(str(exc)) from None
    with Partial(out) as partial:
        failures: list[str] = []
        try:
            done = partial.start(record, options.resume, discard=options.overwrite)
            for index in tqdm(range(done, len(specs)), initial=done, total=len(specs), desc="turns", unit="scene"):
                partial.save(index, turner.turns(specs[index]))
        finally:
            turner.close()
        setup = specs[0].setup
        root = partial.fresh_dataset()
        features = setup.interface
        writer = LeRobotWriter(
            root, Recording(setup.fps, setup.image_size, setup.cameras, features.state_names, features.action_names)
        )
        rows = []
        for made in partial.episodes(len(specs)):
            for one in made:
                if isinstance(one, str):
                    failures.append(one)
                    continue
                rows.append(scenes.row(writer.add(one.episode), one.spec, one, switched=True))
        writer.finalize()
        if not rows:
            raise UserError(f"no turn was finished: {'; '.join(sorted(set(failures)))}")
        scenes.write(root, rows)
        seconds = time.perf_counter() - started
        generation = {
            "generator": "deconfound",  # a dataset this project wrote (jobs/output.py): overwrite=true may replace it
            "made_by": MADE_BY,
            "config": record,
            "complete": True,
            "episodes": len(rows),
            "switched_episodes": sum(isinstance(row["switch"], str) for row in rows),
            "failed": len(failures),
            "seconds": round(seconds, 2),
        }
        (root / GENERATION_PATH).write_text(json.dumps(generation, indent=2))
        partial.publish()
    print(f"wrote {len(rows)} turns from {len(specs)} switched scenes to {out} ({len(failures)} not finished) in {seconds:.0f} s")


if __name__ == "__main__":
    sys.exit(main("python -m train.turns", TurnsOptions, run, doc=__doc__))
