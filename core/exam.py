"""The exam format (version 2): `exam.json`, `trials.parquet` and `answers.parquet`, readable
without this package.

An exam is made from the same specs as a dataset, on the held-out `exam` random stream (its
scene hashes never occur in a training split). Every trial is a scene the oracle solved, and
each row is one rollout to run from that scene's initial state. What a rollout needs — the
scene, its initial state, the instruction — is in `trials.parquet`, the policy's side; the
answer key — which face a row is, what it asks for, the full episode spec with its target and
counterfactuals — is in `answers.parquet`, which only the scorer reads. Hand a policy nothing
from answers.parquet and it cannot cheat without knowing.

| face | instruction | asks for | cameras |
|---|---|---|---|
| `task` | the original | the original target/program | on |
| `swap` | one word changed, once per alternative (the decoy rotates over every non-target) | the decoy | on |
| `occ` | the original | the original | blanked (all zeros) |
| `nonsense` | `xxx` | the original | on |
| `switch` | the original, then from a recorded step one word changed (after the approach committed) | the newly named one | on |

Columns of trials.parquet (the policy's side):
  row (int, unique), trial (int: rollouts of a trial share its scene), instruction (str),
  occluded (bool: the cameras are blanked), scene (JSON: the episode spec with the answer
  withheld — objects with id, kind, name, slot, pos, yaw, attributes; the inventory; the setup
  (key `sim`: world, profile, cameras, frame size and rate); target, instruction, counterfactuals
  and task left empty; see core/spec.py), initial_state (list[float]: MuJoCo mjSTATE_INTEGRATION of the compiled scene),
  max_steps (int: rollout horizon at the exam's fps; a switch row's is its switch step plus the
  trial's horizon, which counts from the switch), and in exams with switch rows switch (JSON:
  {"step": s, "instruction": ...} on a switch row, the instruction the policy is shown from step s
  on, "{}" on every other row; exams written before it have no such column and no switch rows).
Columns of answers.parquet (the scorer's side), one row per rollout too:
  row, face (str), variant (int: 0 for task/occ/nonsense, 1.. for swaps), target (str: the
  object asked for), program (str: pick | push | place), original_target (str),
  original_program (str), spec (JSON: the trial's full episode spec), scene_hash (str),
  alternatives (JSON: `[{"target", "program"}]`, the original first: what the instruction
  chooses among; in a task of more goals than one, LIBERO-10's, an alternative renaming another
  goal than the first says which, `"goal": k`, and is achieved when that goal is done of it and
  every other goal as asked), slot (int: slot of the object asked for), value (str: what the instruction
  calls it), initial_ee (list[float]: the end effector's position in the initial state),
  settled_start (JSON: {"ee": [x, y, z], "objects": {id: [x, y, z]}} after the profile's settle
  steps, where `reset()` of the gymnasium env leaves them; only where the profile has settle
  steps), and in exams written since the prediction face frame_objects (bytes: zlib-compressed
  uint8 H x W map of the agentview camera's first frame, what a rollout's first observation shows,
  from MuJoCo's segmentation: pixel k > 0 shows the spec's k-th object, 0 anything else; the same
  for every row of a trial). A log's step 0 must show one of the two: the initial state (then the
  settle steps are logged as steps) or the settled start.

exam.json holds the format name and version, the faces, the scoring parameters, the
observation/action conventions, the geometry of every object kind (to score logs without the
simulator), the referent spec, the plan's confound audit and, in exams made with switch rows,
`without_switch`: {trial: why it has no switch row} for each trial that has none.
"""

from __future__ import annotations

import json
import zlib
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from core import __version__, contact, parquet, profiles, success, worlds
from core.products import ANSWERS_FILE, EXAM_PATH, TRIALS_FILE
from core.profiles import ACTION_KEY, NATIVE, STATE_KEY
from core.spec import Counterfactual, EpisodeSpec, SpecError

EXAM_FORMAT = "deconfound-exam"
EXAM_VERSION = 2
NONSENSE = "xxx"
FACES = {
    "task": "original instruction; success = the program's predicate on the original target",
    "swap": "one word changed to name another alternative; obeyed = the rollout lands on the newly named one",
    "occ": "original instruction, cameras blanked; success must collapse for a policy that reads its cameras",
    "nonsense": f"instruction replaced by {NONSENSE!r}; a grounded policy should fail",
    "switch": "the original instruction, replaced at a recorded step (the oracle's hand within SWITCH_DISTANCE of where "
    "it takes hold of what it acts on first, before it does: the approach has committed) by one naming another "
    "alternative, the horizon counted from the switch; kept only where the oracle, switched there, achieves the new "
    "ask; obeyed = lands on the newly named one, blind = goes on to the original",
}
SWITCH = "switch"  # a public column of exams with switch rows: {"step", "instruction"} on those rows, "{}" elsewhere
SWITCH_DISTANCE = 0.10  # m from where the hand takes hold of what it acts on first, at which the switch comes
NO_SWITCH = "without_switch"  # exam.json: {trial: why it has no switch row} for the trials that have none
REACH_THRESHOLDS = (0.02, 0.05)
LANDING = 0.05  # closest approach (m) at which a rollout counts as landing on an alternative
PUBLIC_COLUMNS = ("row", "trial", "instruction", "occluded", "scene", "initial_state", "max_steps")
ANSWER_COLUMNS = (
    "row", "face", "variant", "target", "program", "original_target", "original_program", "spec", "scene_hash",
    "alternatives", "slot", "value", "initial_ee",
)  # fmt: skip
SETTLED = "settled_start"  # an answers column of exams whose profile settles (added within version 2; older ones lack it)
FRAME_OBJECTS = "frame_objects"  # an answers column: the first frame's objects (added within version 2; older ones lack it)
PREDICTION_RADIUS = 0.04  # of the frame's width: how near a predicted point must come to an object's pixels to be on it


class ExamError(ValueError):
    """An exam folder is missing, corrupt or of another version; the message says which."""


def scoring() -> dict[str, Any]:
    return {
        "lift_margin": "per trial: spec.task.lift_margin",
        "push_margin": success.PUSH_MARGIN,
        "push_direction": list(success.PUSH_DIRECTION),
        "slide_max_rise": success.SLIDE_MAX_RISE,
        "place_max_hover": success.PLACE_MAX_HOVER,
        "landing_threshold": LANDING,
        "reach_thresholds": list(REACH_THRESHOLDS),
        "grazing_band": list(REACH_THRESHOLDS),
        "contact_point": "pick/push: the object's grasp point (top centre minus grasp_depth), for a kind with a `rim` "
        "(a bowl, taken by its wall) the ring of that radius around it at the grasp point's height; place: the "
        "destination's top centre raised by the carried object's height minus its grasp_depth, plus "
        f"{contact.PLACE_CLEARANCE} m release clearance",
        "landable": "a rollout lands on the row's alternatives or on any other object of the scene the program could act "
        "on (not a place on furniture, not what the program carries things into; a `place` program lands on its "
        "alternatives only); chance is one over them",
    }


def geometry(*names: str) -> dict[str, dict[str, Any]]:
    """Every object kind of the exam's world (or worlds, LIBERO-10's: their kinds are one catalog's):
    what the scorer needs to judge a log without our simulator."""
    out: dict[str, dict[str, Any]] = {}
    kinds = {k.name: k for name in names or ("native",) for k in worlds.world(name).kinds.values()}
    for k in kinds.values():
        out[k.name] = {"size": list(k.size), "bottom": k.bottom, "grasp_depth": k.grasp_depth(), "inner": k.inner}
        if k.rim:
            out[k.name]["rim"] = k.rim
        if k.contain is not None:
            out[k.name]["contain"] = {"offset": list(k.contain[0]), "half_size": list(k.contain[1])}
            if k.contain_quat != (1.0, 0.0, 0.0, 0.0):
                out[k.name]["contain"]["quat"] = list(k.contain_quat)
        if k.quat != (1.0, 0.0, 0.0, 0.0):
            out[k.name]["rest_quat"] = list(k.quat)
    return out


@dataclass(frozen=True)
class Switch:
    """One switch row: from `step` on, the instruction is the trial's `counterfactual`-th swap's."""

    counterfactual: int  # index into the spec's counterfactuals
    step: int  # the first step the policy is shown the new instruction


def alternative(spec: EpisodeSpec, cf: Counterfactual) -> dict[str, Any]:
    """A counterfactual as the answers' `alternatives` list it: what it asks for, and which goal of
    a task of more it renames (`goal`, only where not the first: exams before it have none)."""
    target, program = spec.choice(cf)
    return {"target": target, "program": program, **({"goal": cf.goal} if cf.goal else {})}


def goal_of(alternatives: list[dict[str, Any]], target: str, program: str) -> int:
    """The goal of a task of more that a row asking `program` of `target` renames (0: the first, or
    a task of one goal), read from its trial's `alternatives`."""
    return next((int(a.get("goal", 0)) for a in alternatives if (a["target"], a["program"]) == (target, program)), 0)


def switch_of(row: Any) -> dict[str, Any]:
    """A row's switch, {"step", "instruction"}, or {} on a row (or in an exam) without one."""
    return json.loads(row.get(SWITCH) or "{}")


def switch_choices(trial: int, spec: EpisodeSpec, switches: int) -> list[int]:
    """The counterfactuals a trial's `switches` switch rows name: the next ones in turn from the
    trial's number, so across trials every alternative is switched to as often."""
    n = len(spec.counterfactuals)
    return [(trial + k) % n for k in range(switches)] if n else []


def trial_rows(
    trial: int,
    spec: EpisodeSpec,
    values_by_id: dict[str, str],
    initial_state: list[float],
    max_steps: int,
    initial_ee: list[float],
    settled_start: dict[str, Any] | None = None,
    switches: tuple[Switch, ...] = (),
    frame_objects: bytes | None = None,
) -> list[dict]:
    """The rollouts of one trial: task, a swap per alternative, occ, nonsense, and a switch row per
    `switches` (the instruction changed at its step; `max_steps` more steps after it, the new ask's
    own horizon counted from the switch).

    `values_by_id` says what the instruction calls each alternative (an object id, or a
    program for verb-like types); `frame_objects` is the first frame's map (`encode_objects`).
    """
    objects = {o.id for o in spec.objects}
    values = {((i, spec.task.program) if i in objects else (spec.target, i)): v for i, v in values_by_id.items()}
    original = {"target": spec.target, "program": spec.task.program}
    alternatives = [original] + [alternative(spec, c) for c in spec.counterfactuals]
    common = {
        "trial": trial,
        "original_target": spec.target,
        "original_program": spec.task.program,
        "spec": spec.to_json(),
        "scene": spec.public().to_json(),
        "scene_hash": spec.scene_hash,
        "initial_state": initial_state,
        "initial_ee": initial_ee,
        SETTLED: json.dumps(settled_start or {}),
        "max_steps": max_steps,
        "alternatives": json.dumps(alternatives),
        FRAME_OBJECTS: frame_objects,
    }

    def row(face: str, variant: int, instruction: str, target: str, program: str, occluded: bool = False, **more: Any) -> dict:
        value = values.get((target, program), target)
        return {**common, "face": face, "variant": variant, "instruction": instruction, "target": target,
                "program": program, "occluded": occluded, "slot": spec.object(target).slot, "value": value, **more}  # fmt: skip

    rows = [row("task", 0, spec.instruction, spec.target, spec.task.program)]
    for i, cf in enumerate(spec.counterfactuals, start=1):
        rows.append(row("swap", i, cf.instruction, *spec.choice(cf)))
    rows.append(row("occ", 0, spec.instruction, spec.target, spec.task.program, occluded=True))
    rows.append(row("nonsense", 0, NONSENSE, spec.target, spec.task.program))
    for k, switch in enumerate(switches, start=1):
        cf = spec.counterfactuals[switch.counterfactual]
        at = json.dumps({"step": switch.step, "instruction": cf.instruction})
        rows.append(row("switch", k, spec.instruction, *spec.choice(cf), **{SWITCH: at, "max_steps": switch.step + max_steps}))
    return rows


def encode_objects(indices: np.ndarray) -> bytes:
    """A first frame's object map (H, W) uint8 as the exam stores it: zlib over its bytes, row by row."""
    return zlib.compress(np.ascontiguousarray(indices, np.uint8).tobytes(), 9)


def decode_objects(blob: bytes, size: int) -> np.ndarray:
    """The (size, size) uint8 map `encode_objects` stored."""
    return np.frombuffer(zlib.decompress(blob), np.uint8).reshape(size, size)


def write(root: Path, rows: list[dict], meta: dict[str, Any]) -> None:
    for i, r in enumerate(rows):
        r["row"] = i
        r.setdefault(SWITCH, "{}")
    settles = any(r[SETTLED] != "{}" for r in rows)  # only a profile with settle steps records where they leave it
    answers = (*ANSWER_COLUMNS, SETTLED) if settles else ANSWER_COLUMNS
    answers += (FRAME_OBJECTS,) if any(r.get(FRAME_OBJECTS) for r in rows) else ()
    public = (*PUBLIC_COLUMNS, SWITCH) if any(r[SWITCH] != "{}" for r in rows) else PUBLIC_COLUMNS
    for name, columns in ((TRIALS_FILE, public), (ANSWERS_FILE, answers)):
        pq.write_table(pa.Table.from_pylist([{c: r[c] for c in columns} for r in rows]), root / name)
    header = {
        "format": EXAM_FORMAT,
        "version": EXAM_VERSION,
        "trials": len({r["trial"] for r in rows}),
        "rollouts": len(rows),
        "faces": FACES,
        "scoring": scoring(),
        "geometry": geometry(*meta.get("worlds", [meta.get("world", "native")])),
        "created_with": {
            "generator": __version__,
            "mujoco": metadata.version("mujoco"),
            "robosuite": metadata.version("robosuite"),
        },
        **meta,
    }
    (root / EXAM_PATH).write_text(json.dumps(header, indent=2, default=str))


@dataclass
class Exam:
    """An exam as the battery and the scorer see it: `trials` joins both files on `row`."""

    root: Path
    meta: dict[str, Any]
    trials: pd.DataFrame

    @property
    def name(self) -> str:
        return f"{self.meta['referent']}-exam/seed{self.meta.get('seed', '?')}/{self.meta['trials']}trials"

    @property
    def profile(self) -> str:
        """The profile the exam speaks (exam.json names it unless it is the native one)."""
        return self.meta.get("profile", NATIVE.name)

    @property
    def features(self) -> dict[str, tuple[int, ...]]:
        """Every observation key and the action, with the shape a policy receives or must
        return ((H, W, 3) uint8 frames): what a checkpoint's features are checked against."""
        features = profiles.named(self.profile)
        size = self.meta["observation"]["image_size"]
        return {
            **{key: (size, size, 3) for key in features.image_keys},
            STATE_KEY: (features.state_size,),
            ACTION_KEY: (features.action_size,),
        }

    def spec(self, row: pd.Series) -> EpisodeSpec:
        return EpisodeSpec.from_json(row["spec"])


def read(root: Path | str) -> Exam:
    """Load and validate an exam folder; any problem raises ExamError with one line."""
    root = Path(root)
    if not root.exists():
        raise ExamError(f"exam={root} does not exist")
    if not root.is_dir():
        raise ExamError(f"exam={root} is a file, not an exam folder")
    try:
        meta = json.loads((root / EXAM_PATH).read_text())
    except FileNotFoundError:
        raise ExamError(f"{root} is not an exam: no exam.json") from None
    except (OSError, json.JSONDecodeError) as exc:
        raise ExamError(f"{root}/exam.json is corrupt: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != EXAM_FORMAT:
        raise ExamError(f"{root}/exam.json is not a {EXAM_FORMAT} file")
    if meta.get("version") != EXAM_VERSION:
        raise ExamError(
            f"{root}: exam format version {meta.get('version')} is not supported (this reader: {EXAM_VERSION}); "
            "make the exam again with this generator"
        )
    trials, answers = (
        _table(root, name, columns) for name, columns in ((TRIALS_FILE, PUBLIC_COLUMNS), (ANSWERS_FILE, ANSWER_COLUMNS))
    )
    if len(trials) != meta.get("rollouts") or trials["trial"].nunique() != meta.get("trials"):
        raise ExamError(f"{root}: {TRIALS_FILE} holds {len(trials)} rollouts, exam.json says {meta.get('rollouts')}")
    if sorted(trials["row"]) != sorted(answers["row"]) or trials["row"].duplicated().any():
        raise ExamError(f"{root}: {TRIALS_FILE} and {ANSWERS_FILE} do not hold the same rows once each")
    if SETTLED not in answers.columns:
        answers[SETTLED] = "{}"
    if FRAME_OBJECTS not in answers.columns:  # written before the prediction face: predictions go unscored
        answers[FRAME_OBJECTS] = None
    if SWITCH not in trials.columns:  # written before switch rows existed
        trials[SWITCH] = "{}"
    trials = trials.merge(answers, on="row")
    late = [
        (int(r), json.loads(s)["step"], int(m)) for r, s, m in zip(trials["row"], trials[SWITCH], trials["max_steps"])
        if s != "{}" and not 0 < json.loads(s)["step"] < m
    ]  # fmt: skip
    if late:
        row, step, horizon = late[0]
        raise ExamError(f"{root}: row {row} switches its instruction at step {step}, outside its 1..{horizon - 1} steps")
    try:
        EpisodeSpec.from_json(trials["spec"].iloc[0])
    except SpecError as exc:
        raise ExamError(f"{root}: {exc}") from None
    return Exam(root, meta, trials.sort_values("row").reset_index(drop=True))


def _table(root: Path, name: str, columns: tuple[str, ...]) -> pd.DataFrame:
    try:
        table = parquet.read(root / name)
    except FileNotFoundError:
        raise ExamError(f"{root} has no {name}") from None
    except Exception as exc:  # pyarrow raises several types for damaged files
        raise ExamError(f"{root}/{name} is corrupt: {type(exc).__name__}: {exc}") from None
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ExamError(f"{root}/{name} lacks columns {missing}")
    return table
