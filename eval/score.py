"""Score logged rollouts into the battery's report, without running the simulator.

python -m eval.score exam=<exam dir> logs=<rollouts.parquet> [out=<dir>] [policy=<label>]

`python -m eval` writes its rollouts in this format and scores them with this module, so a lab
that logs end-effector and object positions in its own simulator gets the identical report.

Per rollout, for every alternative of its trial (the original ask and each swap's): whether the
program's success predicate holds on the final state (core/success.py), and the closest
approach of the end effector to the alternative's contact point. The rollout *lands* on the
alternative it achieved, or else on the one it came closest to if that is within the landing
threshold (5 cm; ties land nowhere).

report.json schema (version 2):
  policy, simulator (where the rollouts ran: `ours`, `libero` (LIBERO's own, `sim=libero`), or
      `not recorded` for logs written elsewhere), simulator_versions ({mujoco, robosuite, and for
      `libero` libero: the packages it ran on}; {} where the logs do not say), exam (its label:
      `<referent>-exam/seed<s>/<n>trials`, or for a canonical exam `LIBERO-<Suite> canonical exam: ...`),
      exam_digest (sha256 of the exam's files, eval/scoring/baseline.py
      exam_digest: which exam this is, whatever folder holds it), referent, rollouts (those scored),
      exam_rollouts (the exam's rollouts: more than `rollouts` for a partial take, `python -m eval
      rows=N`), trials (those scored)
  faces.<face> = {k, n, rate, ci: [lo, hi], ci_trials: [lo, hi], chance, by_level} for task
      (achieved the ask), obeyed_name (swap: landed on the newly named alternative), true_target
      (swap: landed on the original), occ and nonsense (achieved the original ask), swap_success
      (swap: achieved the new ask), and on exams with switch rows switch_obeyed (the instruction
      changed mid-course: from the switch step on, the hand came within the threshold of the newly
      named alternative last) and switch_blind (of the original last). `ci` is
      Wilson's (every rollout independent); `ci_trials` resamples whole trials,
      whose rollouts share a scene (core/rates.py). `by_level` =
      {"5cm", "2cm", "achieved": {k, n, rate, ci, ci_trials}}: the same face judged as landing
      within 5 cm, within 2 cm, or achieving the program (lifted / pushed / placed) on what the
      face counts (the ask; for true_target and switch_blind the original). The headline is the 5 cm
      level for obeyed_name, true_target and the switch faces, and the achieved level for the others.
  baseline = the faces of the `position` reference policy (the measured shortcut) on the same
      exam, when known (python -m eval runs it once per exam and caches it); baseline_source says
      where it came from, or how to measure it where it is missing
  grounding = {k, n, rate, ci, ci_trials, chance} for policies that predict where the named
      object is (a `located` column in the logs): swap rollouts whose first-frame prediction is
      nearest the newly named object, whatever the arm then did
  prediction_trained = whether the policy's predictions come from a trained head, where the take
      knows (`python -m eval` records its policy's `prediction_trained`): false for a tiny-policy
      checkpoint trained with point_weight 0 (or before it existed), whose pointer map was never
      taught anything, so its `prediction` rows are no prediction; absent where unknown
  prediction = {name, original, task, occ: {k, n, rate, ci, ci_trials, chance}} for policies that
      predict where their motion will go (a `predicted` column: [column, row] in the agentview
      frame, with the first action chunk): the object the point falls on in the exam's map of that
      frame (answers.parquet frame_objects; within 4% of the frame's width of its pixels) — on a swap
      row that names another object the newly named one (name) or the original (original), on task
      and occ rows the named one (occ: the cameras blank, the blind control); chance is one over the
      objects the frame shows. {unscored: why} where the exam predates the maps
  init_value = {faces: {face: rate}, trusted}: the same scoring on every rollout's initial
      state (a do-nothing policy); rates are trusted only when all are 0
  reach_probe.<face> = {reached_target, went_distractor, neither}: every failed rollout
  carry_probe.<face> = {took_other, reached_none, not_lifted, lifted}: the failed task and swap
      rollouts of a program that carries one thing to another (`put the bowl on the plate`), by
      the stage they stopped at: the hand within 5 cm of another thing it could carry and never
      of this one, of nothing, of this one that never rose 5 cm, or it rose and was not brought;
      absent where no such program failed
  distances = {n, median_to_named, median_to_original, grazing (closest approach to either in
      (2, 5] cm), by_threshold: {"0.02": {obeyed_name, true_target}, "0.05": {...}},
      threshold_robust (the verdict against chance is the same at both thresholds),
      against_chance: {"0.02": v, "0.05": v} (obeyed_name's verdict against its chance at each
      threshold: `above` or `below` where both its intervals, Wilson's and the trials-resampled, lie
      above or below it, else `overlaps`; the report's verdict judges the headline the same way),
      to_named, to_original (each swap rollout's closest approach, metres),
      histogram: {edges, to_named, to_original} (counts per distance bin)}
  per_slot / per_object = {value: {task, obeyed_name}} (rates of the asked-for slot or value, with both
      intervals: {k, n, rate, ci, ci_trials})
  errors = [{row, error}] for rollouts that broke (they count as failures)
  sim_success = {task, swap_success, occ, nonsense, switch: {k, n, rate, ci, ci_trials}}: the simulator's own
      verdict on each row's ask (LIBERO's `In`/`On` predicates under sim=libero: its `check_success()`
      on a task row), beside ours in faces; only for logs that carry it
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from core.exam import ExamError, read
from eval.scoring.baseline import SHORTCUT, cached_baseline
from eval.scoring.report import check_out, write_reports
from eval.scoring.score import BASELINE_MEASURED, score
from eval.sims.log import LogError, read_logs
from jobs.cli import UserError, main


@dataclass
class ScoreOptions:
    exam: str  # the exam folder the rollouts were taken on
    logs: str  # the rollout logs (rollouts.parquet; columns in eval/sims/log.py)
    out: str | None = None  # report folder; default the logs' folder
    policy: str | None = None  # the policy's label in the report; default the one in the logs, else unknown
    overwrite: bool = False  # replace the report already in `out` (report.json, report.md, report.html; nothing else)


def run(options: ScoreOptions) -> None:
    out = Path(options.out or Path(options.logs).parent)
    check_out(out, options.overwrite)
    try:
        exam = read(options.exam)
        logs, logged_policy = read_logs(Path(options.logs))
        report = score(exam, logs, options.policy or logged_policy or "unknown")
    except (ExamError, LogError) as exc:
        raise UserError(str(exc)) from None
    baseline = report["faces"] if report["policy"] == SHORTCUT else cached_baseline(exam, list(exam.trials["row"]))
    if baseline is not None:
        report["baseline"] = baseline
        report["baseline_source"] = BASELINE_MEASURED
    else:
        report["baseline_source"] = (
            f"none: no `{SHORTCUT}` run of these rows is cached; python -m eval policy={SHORTCUT} exam={options.exam} "
            "measures it, and scoring finds it then"
        )
    try:
        write_reports(out, report)
    except OSError as exc:  # e.g. a file where a folder of the path should be, or no permission
        raise UserError(f"cannot write the reports to out={out} ({exc.strerror or exc})") from None
    print(f"wrote {out}/report.json, report.md, report.html")


if __name__ == "__main__":
    sys.exit(main("python -m eval.score", ScoreOptions, run, doc=__doc__))
