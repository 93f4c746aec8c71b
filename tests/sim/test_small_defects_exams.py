"""Issue 49's small defects that need a generated exam (the others are in
tests/fast/test_small_defects.py): `sim=libero` with a `.venv-libero` that lacks its packages is
refused with one line before a take starts, a take that fails before any rollout leaves no partial
run to block the rerun, `python -m eval` refuses to write its report into the exam, and
`gen.canonical`'s hint can be pasted into a shell."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from eval.__main__ import EvalOptions, evaluate
from eval.sims import libero as libero_sim
from jobs.cli import main


@pytest.fixture(scope="module")
def canonical(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """A one-state canonical LIBERO-Object exam in a folder whose path has spaces, and what
    gen.canonical printed (a few seconds: no oracle runs without switch rows)."""
    out = tmp_path_factory.mktemp("exams") / "my exams" / "lo canonical"
    args = ["world=libero_object", "states=1", "tasks=1", "image_size=32", "switches=0", f"out={out}"]
    made = subprocess.run(
        [sys.executable, "-m", "gen.canonical", *args], capture_output=True, text=True, env={**os.environ, "MUJOCO_GL": "egl"}
    )
    assert made.returncode == 0, made.stderr
    return out, made.stdout


@pytest.fixture(scope="module")
def bare_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The python of a virtual environment with no packages: a `.venv-libero` without LIBERO."""
    venv = tmp_path_factory.mktemp("libero") / ".venv-libero"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    return venv / "bin" / "python"


def _eval(*args: str) -> int:
    return main("python -m eval", EvalOptions, evaluate, list(args))


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    return lines[0].removeprefix("error: ")


def test_sim_libero_without_libero_installed_is_refused_before_the_take_starts(
    canonical: tuple[Path, str], bare_python: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    monkeypatch.setattr(libero_sim, "PYTHON", bare_python)
    out = tmp_path / "report"
    assert _eval("policy=nothing", f"exam={canonical[0]}", f"out={out}", "sim=libero") == 2
    line = _one_line(capsys)
    assert "LIBERO's environment" in line and "libero" in line.split("(", 1)[1] and "make setup" in line, line
    assert list(tmp_path.iterdir()) == []  # no report, and no partial run beside it


def test_a_take_that_fails_before_any_rollout_leaves_no_partial_run_to_block_the_rerun(
    canonical: tuple[Path, str], bare_python: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """LIBERO's server dies at once (an environment the check let through): the take fails with
    one line and exit 1, and the same command run again fails the same way, not as a run to resume."""
    monkeypatch.setattr(libero_sim, "PYTHON", bare_python)
    monkeypatch.setattr(libero_sim, "check", lambda exam, policy: None)
    out = tmp_path / "report"
    for _ in range(2):
        assert _eval("policy=nothing", f"exam={canonical[0]}", f"out={out}", "sim=libero") == 1
        errors = [e for e in capsys.readouterr().err.splitlines() if e.startswith("error: ")]  # after the progress bar
        assert len(errors) == 1, errors
        line = errors[0]
        assert "LIBERO's server stopped" in line and "interrupted run" not in line, line
        assert list(tmp_path.iterdir()) == [], list(tmp_path.iterdir())


def test_eval_refuses_to_write_its_report_into_the_exam(canonical: tuple[Path, str], capsys: pytest.CaptureFixture[str]) -> None:
    exam = canonical[0]
    before = {p: p.read_bytes() for p in exam.rglob("*") if p.is_file()}
    for overwrite in ("false", "true"):
        assert _eval("policy=nothing", f"exam={exam}", f"out={exam}", "rows=1", f"overwrite={overwrite}") == 2
        assert _one_line(capsys) == f"out={exam} is an exam made here, not a report folder: choose another out"
    assert {p: p.read_bytes() for p in exam.rglob("*") if p.is_file()} == before
    assert [p.name for p in exam.parent.iterdir()] == [exam.name]  # no partial run beside it either


def test_the_canonical_exams_hint_pastes_into_a_shell(canonical: tuple[Path, str]) -> None:
    exam, printed = canonical
    hint = printed.strip().splitlines()[-1]
    assert hint.startswith("take it with: python -m eval "), printed
    words = shlex.split(hint.removeprefix("take it with: "))
    assert words == ["python", "-m", "eval", "policy=<policy>", f"exam={exam}"], words
