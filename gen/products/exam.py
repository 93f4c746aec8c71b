"""The exam builder (`split=exam`): an audited plan on the held-out random stream -> an exam
(`exam.json`, `trials.parquet`, `answers.parquet`; format in core/exam.py) of trials the oracle
has solved.

Every trial is demonstrated once (resampling poses as for datasets) to prove it solvable and to
record its initial state, rollout horizon and which object each pixel of its first frame shows;
no video is written, so the exam is built in a
throwaway folder and published whole.
"""

from __future__ import annotations

import shlex
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from core import exam
from core.profiles import NATIVE, STATE_KEY, TASK_KEY
from gen.config import GenConfig
from gen.planning.plan import Planned
from gen.products import card
from gen.products.provenance import Provenance
from jobs.cli import UserError
from jobs.partial import staging
from referents.registry import Referent

if TYPE_CHECKING:
    from core.spec import EpisodeSpec
    from gen.products.produce import Producer
    from oracle.episode import Demo
    from oracle.ik import ArmIK
    from oracle.render import Cameras
    from oracle.scene import Scene

HORIZON_FACTOR, HORIZON_SLACK = 1.5, 20  # rollout steps allowed: 1.5x the longest oracle demo of the trial, plus 20


@dataclass
class ExamSummary:
    out: Path
    trials: int
    seconds: float
    verdict: str

    def __str__(self) -> str:
        return (
            f"wrote an exam of {self.trials} oracle-solvable trials to {self.out} in {self.seconds:.1f} s\n"
            f"confound audit of its plan: {self.verdict}\n"
            f"{take_hint(self.out)}"
        )


def take_hint(out: Path) -> str:
    """The line that says how to take the exam at `out`, its path quoted for a shell (spaces and all)."""
    return f"take it with: python -m eval policy=<policy> exam={shlex.quote(str(out))}"


def build(cfg: GenConfig, planned: Planned, provenance: Provenance, out: Path, started: float, progress: bool) -> ExamSummary:
    with staging(out) as root:
        root.mkdir(parents=True)
        rows, without = _trials(cfg, planned, progress)
        exam.write(root, rows, {**_header(cfg, planned, provenance), **({exam.NO_SWITCH: without} if without else {})})
        summary = ExamSummary(out, len(planned.designs), time.perf_counter() - started, planned.only.audit["verdict"])
        card.write_exam(root, planned.only.referent, provenance, planned.only.audit, summary.trials)
    return summary


def _trials(cfg: GenConfig, planned: Planned, progress: bool) -> tuple[list[dict], dict[str, str]]:
    """Every trial's rollouts, each trial demonstrated by the oracle first, and why each trial
    without the switch rows asked for lacks them."""
    from tqdm import tqdm

    from gen.products.produce import DemoFailed, Producer

    referent = planned.only.referent
    producer = Producer(referent, planned.only.setup)
    switches = 1 if cfg.switches is None else cfg.switches
    rows: list[dict] = []
    without: dict[str, str] = {}
    for i, design in enumerate(tqdm(planned.designs, desc=f"{referent.name} exam", unit="trial", disable=not progress)):
        try:
            demo, _ = producer.demonstrate(design, i, cfg.seed, cfg.max_attempts, split="exam")
        except DemoFailed as exc:
            raise UserError(f"{exc}; the referent spec may place objects out of reach") from None
        horizon = int(np.ceil(HORIZON_FACTOR * _longest(producer, referent, demo))) + HORIZON_SLACK
        producer.scene.reset(demo.spec)
        state = producer.scene.physics_state().astype(np.float64).tolist()
        ee = [float(v) for v in producer.scene.ee_pos()]
        values = {a.id: a.value for a in referent.alternatives(demo.spec)}
        settled = producer.scene.settled(demo.spec)
        seen = first_frame(producer.cameras, demo.spec)
        switched, why = switch_rows(producer.scene, producer.ik, referent, demo.spec, state, i, switches)
        if why:
            without[str(i)] = why
        rows += exam.trial_rows(i, demo.spec, values, state, horizon, ee, settled, switched, seen)
    producer.close()
    return rows, without


def first_frame(cameras: Cameras, spec: EpisodeSpec) -> bytes:
    """Which object each pixel of the agentview frame a rollout first sees shows (the scene as
    its rollouts start, after the profile's settle steps): what a predicted point is judged by."""
    ids = [o.id for o in spec.objects]
    return exam.encode_objects(cameras.object_indices(spec.setup.interface.agentview, ids))


def switch_rows(
    scene: Scene, ik: ArmIK, referent: Referent, spec: EpisodeSpec, state: list[float], trial: int, switches: int
) -> tuple[tuple[exam.Switch, ...], str]:
    """A trial's switch rows, and why any asked for is missing ("" if none is). The oracle does the
    trial's own task from where its rollouts start (the initial state, the profile's settle steps);
    the switch comes where its hand first comes within SWITCH_DISTANCE of where it will take hold of
    what it acts on (oracle/episode.py approach_step). A row is kept only if the oracle, switched there, replans and
    achieves the newly named ask, as the `oracle` policy will in the exam: a switch the privileged
    oracle cannot finish measures nothing."""
    from oracle.episode import approach_step, demonstrate

    if not switches:
        return (), ""
    choices = exam.switch_choices(trial, spec, switches)
    if not choices:
        return (), "no alternative to switch to (the instruction names the only candidate)"
    settle = spec.setup.interface.settle_steps
    demo = demonstrate(scene, ik, spec, referent.demo, np.asarray(state), settle)
    if not demo.success:
        return (), f"the oracle does not finish the original ask from this state ({demo.failure})"
    step = approach_step(scene, demo, exam.SWITCH_DISTANCE)
    if step == 0:
        return (), f"the hand starts within {exam.SWITCH_DISTANCE:.2f} m of where it takes hold: no course to change"
    if step is None:
        return (), "what the oracle acts on never moves in its demonstration: no approach to switch in"
    kept, missed = [], []
    for choice in choices:
        cf = spec.counterfactuals[choice]
        asked = spec.asking(*spec.choice(cf), cf.goal)
        then = demonstrate(scene, ik, asked, referent.demo, np.asarray(state), settle, demo.actions[:step])
        if then.success:
            kept.append(exam.Switch(choice, step))
            continue
        said = spec.counterfactuals[choice].instruction
        if not demonstrate(scene, ik, asked, referent.demo, np.asarray(state), settle).success:
            missed.append(f"the oracle does not achieve {said!r} from this state, switched or not")
        else:
            missed.append(f"switched at step {step} to {said!r}, the oracle fails ({then.failure})")
    return tuple(kept), "; ".join(missed)


def _longest(producer: Producer, referent: Referent, demo: Demo) -> int:
    """The longest demonstration among the trial's programs: every row of a trial gets the same
    horizon, so how long a rollout may run never tells which program its instruction asks for
    (a verb exam's swaps ask for another one than the task)."""
    from oracle.episode import demonstrate

    spec, longest = demo.spec, len(demo.actions)
    for target, program in sorted({spec.choice(cf) for cf in spec.counterfactuals if spec.choice(cf)[1] != spec.task.program}):
        asked = replace(spec, target=target, task=replace(spec.task, program=program))
        longest = max(longest, len(demonstrate(producer.scene, producer.ik, asked, referent.demo).actions))
    return longest


def _header(cfg: GenConfig, planned: Planned, provenance: Provenance) -> dict:
    share = planned.only
    setup, features = share.setup, share.setup.interface
    return {
        "referent": share.referent.name,
        "seed": cfg.seed,
        "split": "exam",
        "command": provenance.command(),
        **({} if features.name == NATIVE.name else {"profile": features.name}),
        **({} if setup.world == "native" else {"world": setup.world}),
        "observation": {
            "keys": [features.image_key(c) for c in setup.cameras] + [STATE_KEY],
            "instruction": f"the `instruction` column of trials.parquet; info['instruction'] in the gymnasium env; "
            f"`{TASK_KEY}` in python -m eval's observation dicts",
            "image_size": setup.image_size,
            "fps": setup.fps,
            "state_names": list(features.state_names),
            "action_names": list(features.action_names),
            "action": features.action_meaning,
            **({} if features.name == NATIVE.name else {"mirrored": features.mirrored, "settle_steps": features.settle_steps}),
        },
        "referent_spec": asdict(share.referent.config),
        "audit": share.audit,
    }
