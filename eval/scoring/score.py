"""The scorer: logged rollouts (eval/sims/log.py) judged into the battery's report, without
running the simulator. `python -m eval.score` (eval/score.py) documents the report's fields; the
take (`python -m eval`) and LIBERO's simulator's agreement (`python -m eval.agreement`) score with
these functions.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from core import contact, programs, worlds
from core.catalog import Kind
from core.exam import (
    FRAME_OBJECTS,
    LANDING,
    PREDICTION_RADIUS,
    REACH_THRESHOLDS,
    Exam,
    decode_objects,
    goal_of,
    switch_of,
)
from core.products import EXAM_PATH
from core.programs import achieved
from core.rates import Rate, against_chance, cluster_ci
from core.spec import EpisodeSpec
from core.success import Outcome
from eval.scoring.baseline import REPORT_VERSION, SHORTCUT, exam_digest
from eval.sims.log import SIM_SUCCESS, LogError

# landing threshold (m) of each level, or None: the program achieved
LEVELS = {"5cm": LANDING, "2cm": min(REACH_THRESHOLDS), "achieved": None}
HISTOGRAM_EDGES = (0.0, 0.01, 0.02, 0.03, 0.05, 0.1, 0.2, float("inf"))
BASELINE_MEASURED = f"`{SHORTCUT}` on the same rows, in our simulator (python -m eval measures it once per exam and caches it)"
CARRY_STAGES = ("took_other", "reached_none", "not_lifted", "lifted")  # carry_stage's verdicts, stage by stage
LIFTED = programs.CARRY_LIFT / 2  # (m) raised this far above where it stood: the grasp held it
PREDICTED_FACES = {"swap": "name", "task": "task", "occ": "occ"}  # faces whose first prediction is scored -> its key


def contact_distance(spec: EpisodeSpec, objects: dict[str, np.ndarray], target: str, program: str, ee: np.ndarray) -> np.ndarray:
    """(T,) distances of the end effector from where it reaches when it does `program` to `target`:
    the object's grasp point (a bowl's: its rim) or the release point over a destination, the
    places the oracle's skills go to (core/contact.py)."""
    kind = worlds.kind(spec.object(target).kind, spec.setup.world)
    brings = programs.named(program).brings
    carried = worlds.kind(spec.object(spec.task.params["object"]).kind, spec.setup.world) if brings else None
    return contact.distance(kind, objects[target], ee, carried)


def judge(
    exam: Exam,
    row: pd.Series,
    ee: np.ndarray,
    objects: dict[str, np.ndarray],
    steps: int | None = None,
    turns: dict[str, np.ndarray] | None = None,
) -> dict:
    """What one rollout did to each thing it could have done, judged up to `steps` (default: all
    of it): the row's alternatives and every other object the hand can land on (`landable`).
    `turns`: the movable containers' orientations, where logged (a turned basket's box turns).
    A switch row's landings count from its switch step (where the hand went before the new name
    was given is no landing on it), and each alternative keeps its distance per step (`track`),
    which `landed` reads for where the hand went last."""
    spec = EpisodeSpec.from_json(row["spec"])
    end = len(ee) - 1 if steps is None else steps
    outcome = logged_outcome(ee, objects, end, turns)
    listed = json.loads(row["alternatives"])
    alternatives = [(a["target"], a["program"]) for a in listed]
    since = min(_switch_step(row), end)
    window = slice(since, end + 1)
    result = {}
    for alt in alternatives + landable(spec, alternatives):
        goal = goal_of(listed, *alt)
        aimed = spec.asking(*alt, goal).goals()[goal]  # a task of more goals: the renamed goal's motion is the landing
        distances = contact_distance(aimed, {k: v[window] for k, v in objects.items()}, *alt, ee[window])
        result[alt] = {"achieved": achieved(spec, outcome, *alt, goal), "distance": float(np.min(distances))}
        if since:  # a switch row judged past its switch: where the hand went last decides (`landed`)
            result[alt]["track"] = distances
    return result


def _switch_step(row: pd.Series) -> int:
    """A switch row's switch step (the first step the new instruction is shown), else 0."""
    return int(switch_of(row).get("step", 0))


def logged_outcome(
    ee: np.ndarray, objects: dict[str, np.ndarray], end: int, turns: dict[str, np.ndarray] | None = None
) -> Outcome:
    """A logged rollout's outcome at step `end`: where everything started, and stood then."""
    return Outcome(
        {k: tuple(v[0]) for k, v in objects.items()},
        {k: tuple(v[end]) for k, v in objects.items()},
        tuple(ee[end]),
        {k: tuple(v[end]) for k, v in (turns or {}).items()},
    )


def landable(spec: EpisodeSpec, alternatives: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """The other objects of the scene a hand can land on when the program acts on the named object
    (not where a program brings something, nor a motion of the furniture): every object but places on furniture, what the program
    carries something into, and the alternatives'. A landing there is a distractor's, and chance
    is one over the alternatives and these together."""
    program = alternatives[0][1]
    if not programs.named(program).lands:
        return []
    params, named = spec.task.params, {target for target, _ in alternatives}
    kept = {params.get("destination"), params.get("object"), *named}
    return [(o.id, program) for o in spec.objects if o.id not in kept and not worlds.kind(o.kind, spec.setup.world).is_site]


def _landing(spec: EpisodeSpec) -> str:
    """The level a swap or switch row is read at: where the hand lands (5 cm), or for a task of more
    goals (LIBERO-10's "put both"), whether the whole ask was done: there the hand lands on the kept
    name's object whichever name it read."""
    return "achieved" if len(spec.goals()) > 1 else "5cm"


def landed(judged: dict, threshold: float = LANDING) -> tuple[str, str] | None:
    """The alternative a rollout lands on: the one it achieved, else the one its hand came closest
    to within `threshold` (ties: none). A switch row (`judge` kept its `track`) lands where the hand
    last came within `threshold` after the switch: a hand already over the original when the name
    changes that then goes to the new one obeyed it; one that goes on, or back, to the original did not."""
    done = [a for a, j in judged.items() if j["achieved"]]
    if done:
        return min(done, key=lambda a: judged[a]["distance"])
    if any("track" in j for j in judged.values()):
        return _landed_last(judged, threshold)
    ranked = sorted(judged, key=lambda a: judged[a]["distance"])
    best = judged[ranked[0]]["distance"]
    if best > threshold or (len(ranked) > 1 and judged[ranked[1]]["distance"] - best < 1e-9):
        return None
    return ranked[0]


def _landed_last(judged: dict, threshold: float) -> tuple[str, str] | None:
    """The alternative the hand came within `threshold` of last (at one step: the nearer; ties: none)."""
    last = {a: np.flatnonzero(j["track"] <= threshold) for a, j in judged.items()}
    last = {a: int(steps[-1]) for a, steps in last.items() if len(steps)}
    if not last:
        return None
    step = max(last.values())
    there = sorted((float(judged[a]["track"][step]), a) for a, at in last.items() if at == step)
    if len(there) > 1 and there[1][0] - there[0][0] < 1e-9:
        return None
    return there[0][1]


START_TOLERANCE = 0.002  # m: how far a logged step-0 object may sit from where its trial starts


class Logged(NamedTuple):
    """One rollout's log as the scorer reads it."""

    ee: np.ndarray  # (steps + 1, 3)
    objects: dict[str, np.ndarray]  # id -> (steps + 1, 3)
    error: str | None
    located: np.ndarray | None  # (3,): where the policy believes the named object stands
    predicted: np.ndarray | None  # (2,): [column, row] in the agentview frame, where it predicts its motion will go
    turns: dict[str, np.ndarray]  # movable container id -> (steps + 1, 4) orientations (w, x, y, z), where logged


def parsed_logs(logs: pd.DataFrame, exam: Exam) -> dict[int, Logged]:
    """Each row's log, checked against the exam (a LogError says how it does not fit)."""
    rows = exam.trials["row"]
    if not pd.api.types.is_integer_dtype(logs["row"]):
        kind = type(logs["row"].iloc[0]).__name__ if len(logs) else logs["row"].dtype
        raise LogError(f"column 'row' must hold integers (the exam's row numbers), got {kind}")
    stray = sorted(set(logs["row"]) - set(rows))
    if stray:
        raise LogError(f"the logs hold row {stray[0]}, which the exam does not have (its rows are {rows.min()}..{rows.max()})")
    missing = set(rows) - set(logs["row"])
    if missing:
        raise LogError(f"the logs lack {len(missing)} of the exam's {len(exam.trials)} rollouts (e.g. row {min(missing)})")
    twice = logs["row"][logs["row"].duplicated()]
    if len(twice):
        raise LogError(
            f"the logs hold row {int(twice.iloc[0])} more than once ({len(twice)} duplicated rows): one log per rollout"
        )
    starts = {int(r["row"]): _starts(r) for _, r in exam.trials.iterrows()}
    parsed = {}
    for _, log in logs.iterrows():
        ee, objects = _positions(log)
        error = log["error"] if isinstance(log["error"], str) else None
        if error and not len(ee) and int(log["row"]) in starts:  # broken before its first step: it stayed where it started
            start = dict(starts[int(log["row"])][0])
            ee, objects = start.pop("the end effector")[None], {k: v[None] for k, v in start.items()}
        if not len(ee) or any(len(v) != len(ee) for v in objects.values()):
            raise LogError(f"row {log['row']}: every object needs one position per end-effector position")
        if int(log["row"]) in starts:
            offs = [_off(start, ee[0], objects) for start in starts[int(log["row"])]]
            if all(off is not None for off in offs):
                name, where = offs[0]
                raise LogError(
                    f"row {log['row']}: step 0 is not the trial's recorded initial state ({name} is {where}) "
                    "nor where reset() leaves it after the settle steps; log step 0 before any action"
                )
        turns = _turns(log, len(ee))
        parsed[int(log["row"])] = Logged(ee, objects, error, _optional(log, "located", 3), _optional(log, "predicted", 2), turns)
    return parsed


def _turns(log: pd.Series, steps: int) -> dict[str, np.ndarray]:
    """The optional `turns` column: {container id: [[w, x, y, z], ...]}, one orientation per
    end-effector position (logs without it judge containers at rest, as before it was logged)."""
    value = log.get("turns")
    if value is None or (np.ndim(value) == 0 and pd.isna(value)):
        return {}
    turns = _per_object(log, "turns", "w, x, y, z")
    if any(len(v) != steps for v in turns.values()):
        raise LogError(f"row {log['row']}: every turned container needs one orientation per end-effector position")
    return turns


def _per_object(log: pd.Series, column: str, names: str) -> dict[str, np.ndarray]:
    """A JSON column {object id: [[`names`], ...]} as arrays, one row per step, or a LogError
    naming the column, the shape it must have and the row."""
    value = log[column]
    try:
        decoded = json.loads(value)
        if not isinstance(decoded, dict):
            raise TypeError
        return {str(k): np.asarray(v, float).reshape(-1, len(names.split(", "))) for k, v in decoded.items()}
    except (TypeError, ValueError):
        raise LogError(
            f"column '{column}' must hold a JSON string {{object id: [[{names}], ...]}} per rollout; "
            f"row {log['row']} has a {type(value).__name__}"
        ) from None


def _optional(log: pd.Series, column: str, size: int) -> np.ndarray | None:
    """An optional per-rollout vector column (`located`, `predicted`): None where absent or null,
    else `size` finite numbers, or a LogError naming the row."""
    value = log.get(column)
    if value is None or (np.ndim(value) == 0 and pd.isna(value)):
        return None
    try:
        vector = np.asarray(value, float)
    except (TypeError, ValueError):
        vector = np.zeros(0)
    if vector.shape != (size,) or not np.all(np.isfinite(vector)):
        raise LogError(f"row {log['row']}: column {column!r} must hold {size} finite numbers or null, got {value!r}")
    return vector


def _starts(row: pd.Series) -> list[dict[str, np.ndarray]]:
    """Where a rollout's step 0 may find the hand and the objects: the recorded initial state
    (a loop that logs the settle steps, as ours does) or after the settle steps (what the
    gymnasium env's `reset()` returns), each as {name: position}."""
    spec = EpisodeSpec.from_json(row["spec"])
    # a drawer or a door is recorded where it stands shut (success.closed), which LIBERO-10's states may leave it open from
    shut = {o.id for o in spec.objects if _articulated(worlds.kind(o.kind, spec.setup.world))}
    recorded = {o.id: np.asarray(o.pos) for o in spec.objects if o.id not in shut}
    starts = [{"the end effector": np.asarray(row["initial_ee"], float), **recorded}]
    settled = json.loads(row["settled_start"] or "{}")
    if settled:
        objects = {k: np.asarray(v, float) for k, v in settled["objects"].items()}
        starts.append({"the end effector": np.asarray(settled["ee"], float), **objects})
    return starts


def _articulated(kind: Kind) -> bool:
    """A place that slides or swings (a drawer, a door), not one that stays where it is recorded."""
    return kind.drawer is not None or kind.door is not None


def _off(start: dict[str, np.ndarray], ee: np.ndarray, objects: dict[str, np.ndarray]) -> tuple[str, str] | None:
    """The first thing a log's step 0 does not show where `start` has it (name, how far), or None."""
    logged = {"the end effector": ee, **{k: v[0] for k, v in objects.items()}}
    for name, recorded in start.items():
        off = float(np.linalg.norm(logged[name] - recorded)) if name in logged else float("inf")
        if off > START_TOLERANCE:
            return name, "missing" if name not in logged else f"{off * 100:.1f} cm from where it starts"
    return None


def _positions(log: pd.Series) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A log row's end-effector and object positions, or a LogError naming the column and the type it must have."""
    row = log["row"]
    try:
        ee = np.asarray([np.asarray(p, float) for p in log["ee"]]).reshape(-1, 3)
    except (TypeError, ValueError):
        got = type(log["ee"]).__name__
        raise LogError(
            f"column 'ee' must hold each rollout's end-effector positions, a list of [x, y, z]; row {row} has a {got}"
        ) from None
    return ee, _per_object(log, "objects", "x, y, z")


def score(exam: Exam, logs: pd.DataFrame, policy: str, exam_rollouts: int | None = None) -> dict:
    """The report of `logs` on `exam`'s rows; `exam_rollouts`: how many rollouts the whole exam
    has, when `exam` holds only the rows a partial take ran (default: all of them)."""
    parsed = parsed_logs(logs, exam)
    faces: dict[str, list[dict]] = defaultdict(list)  # per face: one entry per rollout it counts
    probe: dict[str, dict[str, int]] = defaultdict(lambda: {"reached_target": 0, "went_distractor": 0, "neither": 0})
    carry: dict[str, dict[str, int]] = defaultdict(lambda: dict.fromkeys(CARRY_STAGES, 0))
    distances: list[tuple[float, float]] = []
    per_slot: dict[str, dict[str, list[tuple[float, int]]]] = defaultdict(lambda: defaultdict(list))  # (ok, trial)
    per_object: dict[str, dict[str, list[tuple[float, int]]]] = defaultdict(lambda: defaultdict(list))
    grounding: list[tuple[float, int, float]] = []
    prediction: dict[str, list[tuple[float, int, float]]] = defaultdict(list)  # (on the asked object, trial, chance)
    unmapped = 0
    verdicts = _verdicts(logs)  # the simulator's own judgement of each row's ask (sim=libero), where logged
    judged_by_sim: dict[str, list[tuple[float, int]]] = defaultdict(list)
    partial: list[tuple[list[bool], int]] = []  # task rows of a task of more goals: each goal done, and the trial
    errors = []
    for _, row in exam.trials.iterrows():
        ee, objects, error, located, predicted, turns = parsed[int(row["row"])]
        judged = judge(exam, row, ee, objects, turns=turns)
        at_start = judge(exam, row, ee, objects, steps=0, turns=turns)
        asked = (row["target"], row["program"])
        original = (row["original_target"], row["original_program"])
        if error:
            errors.append({"row": int(row["row"]), "error": error})
            for j in judged.values():
                j["achieved"] = False
        trial, face, chance = int(row["trial"]), row["face"], 1.0 / len(judged)

        def count(name: str, wanted: tuple[str, str], headline: str) -> bool:
            """Record one rollout for face `name`: did it land on / achieve `wanted` at each level."""
            levels = {
                level: (judged[wanted]["achieved"] if t is None else (not error and landed(judged, t) == wanted))
                for level, t in LEVELS.items()
            }
            init = at_start[wanted]["achieved"] if LEVELS[headline] is None else landed(at_start, LEVELS[headline]) == wanted
            faces[name].append({"trial": trial, "ok": levels[headline], "init": init, "chance": chance, "levels": levels})
            return levels[headline]

        spec = EpisodeSpec.from_json(row["spec"])
        landing = _landing(spec)
        if face == "swap":
            ok = count("obeyed_name", asked, landing)
            count("true_target", original, landing)
            count("swap_success", asked, "achieved")
            distances.append((judged[asked]["distance"], judged[original]["distance"]))
            if located is not None:
                nearest = _nearest(spec, objects, located)
                grounding.append((float(nearest == row["target"]), trial, chance))
        elif face == "switch":  # scored as a swap: the newly named one, or on to the original (blind)
            ok = count("switch_obeyed", asked, landing)
            count("switch_blind", original, landing)
        else:
            ok = count(face, asked, "achieved")
            if face == "task" and len(spec.goals()) > 1:  # each goal of a task of more, done at the end
                done = programs.each(spec, logged_outcome(ee, objects, len(ee) - 1, turns))
                partial.append(([g and not error for g in done], trial))
        if predicted is not None and face in PREDICTED_FACES:
            if row[FRAME_OBJECTS] is None:
                unmapped += 1
            elif row["target"] != row["original_target"] or face != "swap":  # a swap that names another object
                on, seen = predicted_on(row, predicted, int(exam.meta["observation"]["image_size"]))
                prediction[PREDICTED_FACES[face]].append((float(on == row["target"]), trial, 1.0 / max(seen, 1)))
                if face == "swap":
                    prediction["original"].append((float(on == row["original_target"]), trial, 1.0 / max(seen, 1)))
        verdict = verdicts.get(int(row["row"]))
        if verdict is not None:
            judged_by_sim["swap_success" if face == "swap" else face].append((float(verdict and not error), trial))
        main = {"swap": "obeyed_name", "switch": "switch_obeyed"}.get(face, face)
        if face in ("task", "swap"):
            per_slot[str(row["slot"])][main].append((float(ok), trial))
            per_object[str(row["value"])][main].append((float(ok), trial))
        if not ok:
            probe[main][_probe(judged, asked)] += 1
            if face in ("task", "swap") and (stage := carry_stage(spec, asked[1], ee, objects)) is not None:
                carry[main][stage] += 1
    level_of = {t: level for level, t in LEVELS.items()}
    by_threshold = {
        t: {name: [e["levels"][level_of[t]] for e in faces.get(name, [])] for name in ("obeyed_name", "true_target")}
        for t in REACH_THRESHOLDS
    }
    report = {
        "version": REPORT_VERSION,
        "policy": policy,
        "simulator": logs.attrs.get("sim", "not recorded"),
        "simulator_versions": logs.attrs.get("sim_versions", {}),
        "exam": exam_label(exam),
        "exam_digest": exam_digest(exam) if (exam.root / EXAM_PATH).is_file() else None,  # None: an exam held in memory only
        "referent": exam.meta["referent"],
        "rollouts": len(exam.trials),
        "exam_rollouts": len(exam.trials) if exam_rollouts is None else exam_rollouts,
        "trials": int(exam.trials["trial"].nunique()),
        "faces": {name: _face(entries) for name, entries in faces.items()},
        "init_value": {
            "faces": {f: round(float(np.mean([e["init"] for e in v])), 4) for f, v in faces.items()},
            "trusted": all(not any(e["init"] for e in v) for v in faces.values()),
        },
        "reach_probe": dict(probe),
        **({"carry_probe": dict(carry)} if carry else {}),
        "distances": _distances(
            distances,
            by_threshold,
            float(np.mean([e["chance"] for e in faces.get("obeyed_name", [])] or [0.0])),
            [e["trial"] for e in faces.get("obeyed_name", [])],
        ),
        "per_slot": _rates(per_slot),
        "per_object": _rates(per_object),
        "errors": errors,
    }
    if "prediction_trained" in logs.attrs:
        report["prediction_trained"] = logs.attrs["prediction_trained"]
    if judged_by_sim:
        report["sim_success"] = {face: clustered_rate(*zip(*entries)) for face, entries in judged_by_sim.items()}
    if partial:
        report["partial"] = _partial(partial)
    if grounding:
        hits, trials, chances = zip(*grounding)
        report["grounding"] = {**clustered_rate(hits, trials), "chance": round(float(np.mean(chances)), 4)}
    if prediction:
        report["prediction"] = {
            face: {**clustered_rate(hits, trials), "chance": round(float(np.mean(chances)), 4)}
            for face, (hits, trials, chances) in ((f, zip(*e)) for f, e in prediction.items())
        }
    elif unmapped:
        report["prediction"] = {
            "unscored": f"{unmapped} rollouts logged a prediction, but the exam holds no first-frame object maps "
            f"(answers.parquet {FRAME_OBJECTS}: made before the prediction face); make the exam again to score them"
        }
    return report


def _partial(entries: list[tuple[list[bool], int]]) -> dict:
    """The partial face of a task of more goals (LIBERO-10's): each goal's rate on the task rows
    (clustered by trial), and how many rollouts did which of them (`done`: "1+2" both, "1" the
    first only, "none" neither)."""
    done, trials = zip(*entries)
    patterns = Counter("+".join(str(k + 1) for k, ok in enumerate(d) if ok) or "none" for d in done)
    return {
        "goals": len(done[0]),
        "each": [clustered_rate([float(d[k]) for d in done], trials) for k in range(len(done[0]))],
        "done": dict(sorted(patterns.items())),
    }


def predicted_on(row: pd.Series, point: np.ndarray, size: int) -> tuple[str | None, int]:
    """The object a predicted point [column, row] falls on in the row's first frame — the one whose
    pixels (their centres) come nearest, if within PREDICTION_RADIUS of the frame's width — and how
    many of the scene's objects that frame shows (chance is one over them)."""
    spec = EpisodeSpec.from_json(row["spec"])
    labels = decode_objects(row[FRAME_OBJECTS], size)
    rows, columns = np.nonzero(labels)
    seen = np.unique(labels[rows, columns])
    if not len(rows):
        return None, 0
    gaps = np.hypot(columns + 0.5 - point[0], rows + 0.5 - point[1])
    nearest = int(np.argmin(gaps))
    if gaps[nearest] > PREDICTION_RADIUS * size:
        return None, len(seen)
    return spec.objects[int(labels[rows[nearest], columns[nearest]]) - 1].id, len(seen)


def _verdicts(logs: pd.DataFrame) -> dict[int, bool]:
    """row -> the simulator's own verdict on its ask (the `sim_success` column), where logged."""
    if SIM_SUCCESS not in logs:
        return {}
    return {int(r): bool(v) for r, v in zip(logs["row"], logs[SIM_SUCCESS]) if v is not None and not pd.isna(v)}


def clustered_rate(outcomes: Sequence[float], trials: Sequence[int]) -> dict:
    """k/n with its Wilson interval and the interval that resamples whole trials."""
    return {**Rate(float(sum(outcomes)), len(outcomes)).to_dict(), "ci_trials": list(cluster_ci(outcomes, trials))}


def _face(entries: list[dict]) -> dict:
    """A face's headline rate with both intervals, its chance and its three landing levels."""
    trials = [e["trial"] for e in entries]
    return {
        **clustered_rate([float(e["ok"]) for e in entries], trials),
        "chance": round(float(np.mean([e["chance"] for e in entries])), 4),
        "by_level": {level: clustered_rate([float(e["levels"][level]) for e in entries], trials) for level in LEVELS},
    }


def _nearest(spec: EpisodeSpec, objects: dict[str, np.ndarray], point: np.ndarray) -> str:
    """The scene object whose starting position is nearest `point`."""
    return min((o.id for o in spec.objects), key=lambda i: float(np.linalg.norm(objects[i][0] - point)))


def _probe(judged: dict, asked: tuple[str, str]) -> str:
    if judged[asked]["distance"] <= LANDING:
        return "reached_target"
    closest = min(judged, key=lambda a: judged[a]["distance"])
    return "went_distractor" if judged[closest]["distance"] <= LANDING else "neither"


def carry_stage(spec: EpisodeSpec, program: str, ee: np.ndarray, objects: dict[str, np.ndarray]) -> str | None:
    """Where a failed rollout of a program that carries one thing to another (`put the bowl on the
    plate`) stopped: `took_other`, the hand reached another thing it could carry, never this one (its
    name not read); `reached_none`, it reached nothing it could carry; `not_lifted`, it reached this
    one and never lifted it (the grasp); `lifted`, it lifted it and did not bring it where asked
    (the carrying, or the place's name). None for a program that carries nothing to a place: the
    reach probe (`_probe`) says where those went."""
    if not programs.named(program).carries:
        return None
    carried = spec.task.params["object"]
    reached = {
        o.id
        for o in spec.objects
        if (kind := worlds.kind(o.kind, spec.setup.world)).graspable()
        and not kind.is_site
        and o.id in objects
        and float(np.min(contact.grasp_distance(kind, objects[o.id], ee))) <= LANDING
    }
    if carried not in reached:
        return "took_other" if reached else "reached_none"
    height = objects[carried][:, 2]
    return "lifted" if float(np.max(height) - height[0]) >= LIFTED else "not_lifted"


def _distances(pairs: list[tuple[float, float]], by_threshold: dict, chance: float, trials: list[int]) -> dict:
    if not pairs:
        return {"n": 0}
    named, original = np.array(pairs).T
    closest = np.minimum(named, original)
    lo, hi = REACH_THRESHOLDS
    against = {
        str(t): against_chance(clustered_rate([float(v) for v in outcomes["obeyed_name"]], trials), chance)
        for t, outcomes in by_threshold.items()
    }
    return {
        "n": len(pairs),
        "median_to_named": round(float(np.median(named)), 4),
        "median_to_original": round(float(np.median(original)), 4),
        "grazing": int(np.sum((closest > lo) & (closest <= hi))),
        "by_threshold": {str(t): {k: Rate(sum(v), len(v)).to_dict() for k, v in d.items()} for t, d in by_threshold.items()},
        "threshold_robust": len(set(against.values())) == 1,
        "against_chance": against,
        "to_named": [round(float(v), 4) for v in named],
        "to_original": [round(float(v), 4) for v in original],
        "histogram": {
            "edges": [e if np.isfinite(e) else None for e in HISTOGRAM_EDGES],
            "to_named": np.histogram(named, HISTOGRAM_EDGES)[0].tolist(),
            "to_original": np.histogram(original, HISTOGRAM_EDGES)[0].tolist(),
        },
    }


def _rates(table: dict) -> dict:
    """Per key and face, the rate of its (ok, trial) entries with both intervals."""
    return {
        key: {face: clustered_rate(*zip(*entries)) for face, entries in faces.items()}
        for key, faces in sorted(table.items(), key=lambda kv: (len(kv[0]), kv[0]))
    }


def exam_label(exam: Exam) -> str:
    """The report's name for the exam. A canonical exam (python -m gen.canonical) holds its LIBERO
    suite's own tasks and initial states, whose task rate is the suite's published number: it
    must not read as a deconfounded `split=exam` exam of the same referent."""
    canonical = exam.meta.get("canonical")
    if not canonical:
        return exam.name
    base = canonical.get("base_suite", canonical["suite"])
    suite = "LIBERO-" + base.removeprefix("libero_").title()
    if canonical["suite"] != base:  # a LIBERO-PRO perturbation of it
        suite += f" ({canonical['suite']}, LIBERO-PRO)"
    per_task = len(next(iter(canonical["states"].values())))
    return (
        f"{suite} canonical exam: LIBERO's own initial states, {per_task} per task, seed {exam.meta.get('seed', '?')} "
        f"({exam.meta['trials']} trials)"
    )


def swaps_obeyed(exam: Exam, logs: pd.DataFrame) -> dict[int, bool]:
    """Each swap rollout's row -> whether it landed on the named object (5 cm; a task of more goals:
    achieved the renamed ask, `_landing`), as `score` counts obeyed name: what lets two policies'
    swaps be compared row by row."""
    parsed, obeyed = parsed_logs(logs, exam), {}
    for _, row in exam.trials[exam.trials["face"] == "swap"].iterrows():
        log = parsed[int(row["row"])]
        judged = judge(exam, row, log.ee, log.objects, turns=log.turns)
        asked = (row["target"], row["program"])
        at = LEVELS[_landing(EpisodeSpec.from_json(row["spec"]))]
        read = judged[asked]["achieved"] if at is None else landed(judged) == asked
        obeyed[int(row["row"])] = not log.error and read
    return obeyed
