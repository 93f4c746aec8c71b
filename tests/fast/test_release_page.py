"""docs/RESULTS_LIBERO_AXES.md says which generation of an exam each row was taken on, where an
axis's rows were not all taken on one (train/release.py `_exams_taken`), and where a carrying
axis's failures stopped (`_short_of`), and the fix tried once beside the release (`_fix_tried`)."""

from __future__ import annotations

from train.release import _exams_taken, _fix_tried, _short_of


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


def test_the_fix_tried_once_stands_beside_the_release_where_both_took_an_exam() -> None:
    def rate(k: int) -> dict:
        return {"k": k, "n": 20, "rate": k / 20, "ci": [0.0, 1.0], "ci_trials": [0.0, 1.0]}

    def taken(axis: str, arm: str, sim: str, obeyed: int, task: int) -> dict:
        return _row(axis, arm, sim, None) | {"faces": {"obeyed_name": rate(obeyed), "task": rate(task)}}

    rows = [taken("goal", "deconfounded", "ours", 2, 1), taken("goal", "favoured", "ours", 0, 0)]
    rows += [taken("object", "deconfounded", "ours", 19, 16), taken("object", "favoured", "ours", 19, 10)]
    rows += [taken("object", "deconfounded", "libero", 19, 14)]  # the favoured one not taken there: no row
    lines = _fix_tried({"rows": rows, "training": {"favoured": {"favour": ["goal"]}}})
    table = [line for line in lines if line.startswith(("| goal", "| object"))]
    assert table == [
        "| object | ours | 95.0% (19/20; 0%–100%) | 95.0% (19/20; 0%–100%) | 80.0% (16/20; 0%–100%) | 50.0% (10/20; 0%–100%) |",
        "| goal (favoured) | ours | 10.0% (2/20; 0%–100%) | 0.0% (0/20; 0%–100%) | 5.0% (1/20; 0%–100%) | 0.0% (0/20; 0%–100%) |",
    ]
    assert _fix_tried({"rows": rows[:1], "training": {}}) == []
