"""`python -m eval.suites`' summary of a suite whose exam has no rows of a face (a `_task` suite
whose every swap is left out, as libero_spatial_task's are)."""

from pathlib import Path

from eval.suites import picture, suite_row, table


def test_a_suite_without_swap_rows_gets_a_dash_not_a_crash(tmp_path: Path) -> None:
    rate = {"k": 1, "n": 2, "rate": 0.5, "ci": [0.1, 0.9], "ci_trials": [0.0, 1.0]}
    report = {"exam": "an exam", "faces": {"task": rate, "occ": rate, "nonsense": rate}}
    row = suite_row("libero_spatial_task", report)
    assert row["faces"]["obeyed_name"]["n"] == 0 and row["faces"]["true_target"]["rate"] is None
    text = table(
        "position",
        [row, suite_row("libero_spatial", {**report, "faces": {**report["faces"], "obeyed_name": rate, "true_target": rate}})],
    )
    assert "| libero_spatial_task | 50% (1/2; 0%–100%) | — | — |" in text
    picture("position", [row], tmp_path / "suites.png")
    assert (tmp_path / "suites.png").stat().st_size > 0
