"""docs/RESULTS_LIBERO_AXES.md says which generation of an exam each row was taken on, where an
axis's rows were not all taken on one (train/release.py `_exams_taken`), and where a carrying
axis's failures stopped (`_short_of`)."""

from __future__ import annotations

from train.release import _exams_taken, _short_of


def _row(axis: str, arm: str, sim: str, digest: str | None) -> dict:
    return {"axis": axis, "exam": "axis", "arm": arm, "sim": sim, "exam_digest": digest}


def test_rows_of_one_exam_taken_on_two_generations_are_named() -> None:
    rows = [
        _row("object", "deconfounded", "ours", None),
        _row("object", "confounded", "libero", "ab" * 32),
        _row("object", "named_place", "ours", "ab" * 32),
        _row("goal", "deconfounded", "ours", "cd" * 32),
        _row("goal", "confounded", "ours", "cd" * 32),
    ]
    lines = _exams_taken({"rows": rows})
    table = [line for line in lines if line.startswith("| object")]
    assert table == ["| object | axis | abababab: confounded libero, named_place ours; not recorded: deconfounded ours |"]
    assert not any(line.startswith("| goal") for line in lines)  # one generation: nothing to say
    assert _exams_taken({"rows": rows[3:]}) == []


def test_a_carrying_axis_failures_are_told_by_stage() -> None:
    rate = {"k": 1, "n": 4, "rate": 0.25, "ci": [0.0, 0.5], "ci_trials": [0.0, 0.5]}
    carry = {"task": {"took_other": 1, "reached_none": 0, "not_lifted": 2, "lifted": 0}}
    goal = _row("goal", "deconfounded", "ours", None) | {
        "faces": {"task": rate, "obeyed_name": rate},
        "reach_probe": {"task": {"neither": 3}},
        "carry_probe": carry,
    }
    lines = _short_of({"rows": [goal, {**goal, "axis": "object", "carry_probe": None}]})
    staged = [line for line in lines if line.endswith("| task | 1 | 0 | 2 | 0 |")]
    assert staged == ["| goal | deconfounded | ours | task | 1 | 0 | 2 | 0 |"]
