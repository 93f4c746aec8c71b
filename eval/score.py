"""Score logged rollouts into the battery's report, without running the simulator.

python -m eval.score exam=<exam dir> logs=<rollouts.parquet> [out=<dir>] [policy=<label>]

`python -m eval` writes its rollouts in this format and scores them with this module, so a lab
that logs end-effector and object positions in its own simulator gets the identical report.

Per rollout, for every alternative of its trial (the original ask and each swap's): whether the
program's success predicate holds on the final state (core/success.py), and the closest
approach of the end effector to the alternative's contact point. The rollout *lands* on the
alternative it achieved, or else on the one it came closest to if that is within the landing
threshold (5 cm; ties land nowhere).

report.json schema (version 1):
  policy, exam, referent, rollouts, trials
  faces.<face> = {k, n, rate, ci: [lo, hi], chance} for task (achieved the ask), obeyed_name
      (swap: landed on the newly named alternative), true_target (swap: landed on the original),
      occ and nonsense (achieved the original ask), swap_success (swap: achieved the new ask)
  init_value = {faces: {face: rate}, trusted}: the same scoring on every rollout's initial
      state (a do-nothing policy); rates are trusted only when all are 0
  reach_probe.<face> = {reached_target, went_distractor, neither}: every failed rollout
  distances = {n, median_to_named, median_to_original, grazing (closest approach to either in
      (2, 5] cm), by_threshold: {"0.02": {obeyed_name, true_target}, "0.05": {...}},
      threshold_robust (the verdict against chance is the same at both thresholds),
      to_named, to_original (each swap rollout's closest approach, metres)}
  per_slot / per_object = {value: {task, obeyed_name}} (rates of the asked-for slot or value)
  errors = [{row, error}] for rollouts that broke (they count as failures)
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from core import catalog, contact
from core.exam import LANDING, REACH_THRESHOLDS, Exam, ExamError, read
from core.rates import Rate
from core.spec import EpisodeSpec
from core.success import Outcome, achieved
from gen.cli import UserError, main

REPORT_VERSION = 1
POLICY_KEY = b"deconfound.policy"


class LogError(ValueError):
    """Rollout logs that do not match the exam; the message says how."""


def contact_points(spec: EpisodeSpec, objects: dict[str, np.ndarray], target: str, program: str) -> np.ndarray:
    """(T, 3) positions the end effector reaches for when it does `program` to `target`: the
    points the oracle's skills go to (core/contact.py)."""
    kind = catalog.kind(spec.object(target).kind)
    if program == "place":
        carried = catalog.kind(spec.object(spec.task.params["object"]).kind)
        return contact.release_point(kind, objects[target], carried)
    return contact.grasp_point(kind, objects[target])


def judge(exam: Exam, row: pd.Series, ee: np.ndarray, objects: dict[str, np.ndarray], steps: int | None = None) -> dict:
    """What one rollout did, judged up to `steps` (default: all of it)."""
    spec = EpisodeSpec.from_json(row["spec"])
    end = len(ee) - 1 if steps is None else steps
    outcome = Outcome(
        {k: tuple(v[0]) for k, v in objects.items()}, {k: tuple(v[end]) for k, v in objects.items()}, tuple(ee[end])
    )
    alternatives = [(a["target"], a["program"]) for a in json.loads(row["alternatives"])]
    result = {}
    for alt in alternatives:
        points = contact_points(spec, objects, *alt)[: end + 1]
        result[alt] = {
            "achieved": achieved(spec, outcome, *alt),
            "distance": float(np.min(np.linalg.norm(ee[: end + 1] - points, axis=1))),
        }
    return result


def landed(judged: dict, threshold: float = LANDING) -> tuple[str, str] | None:
    done = [a for a, j in judged.items() if j["achieved"]]
    if done:
        return min(done, key=lambda a: judged[a]["distance"])
    ranked = sorted(judged, key=lambda a: judged[a]["distance"])
    best = judged[ranked[0]]["distance"]
    if best > threshold or (len(ranked) > 1 and judged[ranked[1]]["distance"] - best < 1e-9):
        return None
    return ranked[0]


def _parse(logs: pd.DataFrame, exam: Exam) -> dict[int, tuple[np.ndarray, dict[str, np.ndarray], str | None]]:
    missing = set(exam.trials["row"]) - set(logs["row"])
    if missing:
        raise LogError(f"the logs lack {len(missing)} of the exam's {len(exam.trials)} rollouts (e.g. row {min(missing)})")
    parsed = {}
    for _, log in logs.iterrows():
        ee = np.asarray([np.asarray(p, float) for p in log["ee"]]).reshape(-1, 3)
        objects = {k: np.asarray(v, float).reshape(-1, 3) for k, v in json.loads(log["objects"]).items()}
        if not len(ee) or any(len(v) != len(ee) for v in objects.values()):
            raise LogError(f"row {log['row']}: every object needs one position per end-effector position")
        parsed[int(log["row"])] = (ee, objects, log["error"] if isinstance(log["error"], str) else None)
    return parsed


def score(exam: Exam, logs: pd.DataFrame, policy: str) -> dict:
    parsed = _parse(logs, exam)
    faces: dict[str, list[float]] = defaultdict(list)
    init: dict[str, list[float]] = defaultdict(list)
    chance: dict[str, list[float]] = defaultdict(list)
    probe: dict[str, dict[str, int]] = defaultdict(lambda: {"reached_target": 0, "went_distractor": 0, "neither": 0})
    distances: list[tuple[float, float]] = []
    by_threshold: dict[float, dict[str, list[float]]] = {t: defaultdict(list) for t in REACH_THRESHOLDS}
    per_slot: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    per_object: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    errors = []
    for _, row in exam.trials.iterrows():
        ee, objects, error = parsed[int(row["row"])]
        judged = judge(exam, row, ee, objects)
        at_start = judge(exam, row, ee, objects, steps=0)
        asked = (row["target"], row["program"])
        original = (row["original_target"], row["original_program"])
        if error:
            errors.append({"row": int(row["row"]), "error": error})
            for j in judged.values():
                j["achieved"] = False
        face = row["face"]
        outcomes = {"task": [], "obeyed_name": [], "true_target": [], "occ": [], "nonsense": [], "swap_success": []}
        if face == "swap":
            land = None if error else landed(judged)
            outcomes["obeyed_name"] = [land == asked, landed(at_start) == asked]
            outcomes["true_target"] = [land == original, landed(at_start) == original]
            outcomes["swap_success"] = [judged[asked]["achieved"], at_start[asked]["achieved"]]
            distances.append((judged[asked]["distance"], judged[original]["distance"]))
            for t in REACH_THRESHOLDS:
                land_t = None if error else landed(judged, t)
                by_threshold[t]["obeyed_name"].append(land_t == asked)
                by_threshold[t]["true_target"].append(land_t == original)
        else:
            outcomes[face] = [judged[asked]["achieved"], at_start[asked]["achieved"]]
        for name, pair in outcomes.items():
            if pair:
                faces[name].append(float(pair[0]))
                init[name].append(float(pair[1]))
                chance[name].append(1.0 / len(judged))
        ok = outcomes["obeyed_name"][0] if face == "swap" else outcomes[face][0]
        main = "obeyed_name" if face == "swap" else face
        if face in ("task", "swap"):
            per_slot[str(row["slot"])][main].append(float(ok))
            per_object[str(row["value"])][main].append(float(ok))
        if not ok:
            probe[main][_probe(judged, asked)] += 1
    return {
        "version": REPORT_VERSION,
        "policy": policy,
        "exam": exam.name,
        "referent": exam.meta["referent"],
        "rollouts": len(exam.trials),
        "trials": int(exam.trials["trial"].nunique()),
        "faces": {f: {**Rate(sum(v), len(v)).to_dict(), "chance": round(float(np.mean(chance[f])), 4)} for f, v in faces.items()},
        "init_value": {
            "faces": {f: round(float(np.mean(v)), 4) for f, v in init.items()},
            "trusted": all(sum(v) == 0 for v in init.values()),
        },
        "reach_probe": dict(probe),
        "distances": _distances(distances, by_threshold, float(np.mean(chance["obeyed_name"] or [0.0]))),
        "per_slot": _rates(per_slot),
        "per_object": _rates(per_object),
        "errors": errors,
    }


def _probe(judged: dict, asked: tuple[str, str]) -> str:
    if judged[asked]["distance"] <= LANDING:
        return "reached_target"
    closest = min(judged, key=lambda a: judged[a]["distance"])
    return "went_distractor" if judged[closest]["distance"] <= LANDING else "neither"


def _distances(pairs: list[tuple[float, float]], by_threshold: dict, chance: float) -> dict:
    if not pairs:
        return {"n": 0}
    named, original = np.array(pairs).T
    closest = np.minimum(named, original)
    lo, hi = REACH_THRESHOLDS
    verdicts = set()
    for outcomes in by_threshold.values():
        r = Rate(sum(outcomes["obeyed_name"]), len(outcomes["obeyed_name"]))
        verdicts.add((r.ci[0] > chance, r.ci[1] < chance))
    return {
        "n": len(pairs),
        "median_to_named": round(float(np.median(named)), 4),
        "median_to_original": round(float(np.median(original)), 4),
        "grazing": int(np.sum((closest > lo) & (closest <= hi))),
        "by_threshold": {str(t): {k: Rate(sum(v), len(v)).to_dict() for k, v in d.items()} for t, d in by_threshold.items()},
        "threshold_robust": len(verdicts) == 1,
        "to_named": [round(float(v), 4) for v in named],
        "to_original": [round(float(v), 4) for v in original],
    }


def _rates(table: dict) -> dict:
    return {
        key: {face: Rate(sum(v), len(v)).to_dict() for face, v in faces.items()}
        for key, faces in sorted(table.items(), key=lambda kv: (len(kv[0]), kv[0]))
    }


def read_logs(path: Path) -> tuple[pd.DataFrame, str | None]:
    try:
        table = pq.read_table(path)
    except FileNotFoundError:
        raise LogError(f"no rollout logs at {path}") from None
    except Exception as exc:
        raise LogError(f"{path} is not a readable parquet file: {exc}") from None
    missing = {"row", "ee", "objects", "error"} - set(table.column_names)
    if missing:
        raise LogError(f"{path} lacks columns {sorted(missing)}")
    policy = (table.schema.metadata or {}).get(POLICY_KEY)
    return table.to_pandas(), policy.decode() if policy else None


@dataclass
class ScoreOptions:
    exam: str  # the exam folder the rollouts were taken on
    logs: str  # the rollout logs (rollouts.parquet; columns in eval/rollout.py)
    out: str | None = None  # report folder; default the logs' folder
    policy: str | None = None  # the policy's label in the report; default the one in the logs, else unknown


def run(options: ScoreOptions) -> None:
    from eval.report import write_reports

    try:
        exam = read(options.exam)
        logs, logged_policy = read_logs(Path(options.logs))
        report = score(exam, logs, options.policy or logged_policy or "unknown")
    except (ExamError, LogError) as exc:
        raise UserError(str(exc)) from None
    out = Path(options.out or Path(options.logs).parent)
    write_reports(out, report)
    print(f"wrote {out}/report.json, report.md, report.html")


if __name__ == "__main__":
    sys.exit(main("python -m eval.score", ScoreOptions, run, doc=__doc__))
