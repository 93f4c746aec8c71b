"""Taking an exam never loses or silently replaces a result: a report is replaced only when asked,
an unusable `out` is refused before any rollout, and Ctrl-C keeps every finished rollout for
`resume=true`, which gives the report an uninterrupted take gives."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from eval.__main__ import EvalOptions, evaluate
from eval.policies.registry import make, register
from helpers import Shared, interruptible, make_dataset
from jobs.cli import main

REPORT = ("report.json", "rollouts.parquet")


@pytest.fixture(scope="module")
def exam(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """3 trials, 18 rollouts."""
    folder = tmp_path_factory.mktemp("exam") / "exam"
    return make_dataset(folder, "n=3", "split=exam", "seed=1", "image_size=32", "workers=1", "switches=0")


def _eval(*args: str) -> int:
    return main("python -m eval", EvalOptions, evaluate, list(args))


def _files(root: Path) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_same_named_exams_get_their_own_report_folders_and_no_report_is_silently_replaced(
    shared: Shared, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    first, second = (shared.dataset("exam", "n=1", "split=exam", f"seed={seed}", "image_size=32", "workers=1") for seed in (1, 2))
    monkeypatch.chdir(tmp_path)
    for exam in (first, second):
        assert _eval("policy=nothing", f"exam={exam}", "rows=1") == 0
    folders = sorted(p.parent for p in (tmp_path / "runs").glob("*/nothing/report.json"))
    assert len(folders) == 2 and all(f.parent.name.startswith("exam-") for f in folders), folders
    before = _files(tmp_path / "runs")
    capsys.readouterr()
    assert _eval("policy=nothing", f"exam={first}", "rows=1") == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "already holds a report" in lines[0] and "overwrite=true" in lines[0], lines
    assert _files(tmp_path / "runs") == before
    assert _eval("policy=nothing", f"exam={first}", "rows=1", "overwrite=true") == 0


def test_an_unusable_out_is_refused_before_the_policy_loads(
    exam: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    made: list[str] = []
    register("counted", lambda: made.append("policy") or make("nothing"))
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    for out, needle in [
        (blocker, "exists and is not a folder"),
        (blocker / "report", "not writable"),
        (Path("/proc/deconfound/report"), "not writable"),
    ]:
        assert _eval("policy=counted", f"exam={exam}", f"out={out}") == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and needle in lines[0], lines
    assert made == [] and blocker.read_text() == "x"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_file"]


def _eval_argv(*args: str) -> list[str]:
    return interruptible("eval", "policy=oracle", *args)


def _eval_process(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(_eval_argv(*args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_ctrl_c_keeps_the_finished_rollouts_and_resume_gives_the_uninterrupted_report(exam: Path, tmp_path: Path) -> None:
    out = tmp_path / "oracle"
    kept = tmp_path / ".oracle.partial" / "rollouts"
    taking = _eval_process(f"exam={exam}", f"out={out}", "workers=1")
    deadline = time.monotonic() + 120
    while len(list(kept.glob("*.pkl"))) < 3 and taking.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    taking.send_signal(signal.SIGINT)
    _, err = taking.communicate()
    last = err.strip().splitlines()[-1]
    assert taking.returncode == 130 and last.startswith("error: interrupted: ") and "of 18 rollouts kept in" in last, err
    assert str(tmp_path / ".oracle.partial") in last and "resume=true" in last
    saved = len(list(kept.glob("*.pkl")))
    assert 3 <= saved < 18 and f"{saved} of 18" in last and not out.exists()
    again = _eval_process(f"exam={exam}", f"out={out}")
    _, err = again.communicate()
    assert again.returncode == 2 and len(err.strip().splitlines()) == 1 and "pass resume=true" in err, err
    resumed = _eval_process(f"exam={exam}", f"out={out}", "resume=true", "workers=2")
    stdout, err = resumed.communicate()
    assert resumed.returncode == 0, err
    assert f"{18 - saved} rollouts in" in stdout and f"{saved} kept from the interrupted take" in stdout, stdout
    whole = _eval_process(f"exam={exam}", f"out={tmp_path / 'whole'}")
    _, err = whole.communicate()
    assert whole.returncode == 0, err
    for name in REPORT:
        assert (out / name).read_bytes() == (tmp_path / "whole" / name).read_bytes(), name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["oracle", "whole"], "the partial takes are cleaned up"
    assert sorted(os.listdir(out)) == sorted(os.listdir(tmp_path / "whole"))


def test_a_worker_that_dies_mid_take_ends_it_in_one_line_and_resume_goes_on(exam: Path, tmp_path: Path) -> None:
    """A rollout worker killed outright (a native crash, the OOM killer) used to leave the take waiting
    forever for its chunk; now the take stops, says what it kept, and resume=true finishes it."""
    out = tmp_path / "oracle"
    env = {**os.environ, "DECONFOUND_CRASH_AT": "rollout:12"}  # in the second worker's chunk (rows 9-17)
    dying = subprocess.Popen(_eval_argv(f"exam={exam}", f"out={out}", "workers=2"), stderr=subprocess.PIPE, text=True, env=env)
    _, err = dying.communicate(timeout=300)
    last = err.strip().splitlines()[-1]
    assert dying.returncode == 1 and last.startswith("error: a rollout worker died (SIGKILL)") and "resume=true" in last, err
    assert not out.exists() and 3 <= len(list((tmp_path / ".oracle.partial" / "rollouts").glob("*.pkl"))) < 18
    resumed = subprocess.run(_eval_argv(f"exam={exam}", f"out={out}", "resume=true", "workers=2"), capture_output=True, text=True)
    assert resumed.returncode == 0 and (out / "report.json").is_file(), resumed.stderr[-2000:]


def test_ctrl_c_while_the_shortcut_baseline_is_measured_keeps_its_rollouts_too(exam: Path, tmp_path: Path) -> None:
    """The `position` baseline runs after the policy's rollouts (once per exam; a fresh cache here):
    interrupted then, the line says so and how many of its rollouts are kept, and resume=true goes on
    from them to the report."""
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    argv = interruptible("eval", "policy=nothing", f"exam={exam}", f"out={tmp_path / 'nothing'}", "workers=1")
    kept = tmp_path / ".nothing.partial" / "baseline" / ".position.partial" / "rollouts"
    taking = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 180
    while len(list(kept.glob("*.pkl"))) < 2 and taking.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    taking.send_signal(signal.SIGINT)
    _, err = taking.communicate()
    last = err.strip().splitlines()[-1]
    assert taking.returncode == 130 and "18 of 18 rollouts kept" in last, err
    saved = len(list(kept.glob("*.pkl")))
    assert 2 <= saved < 18 and f"while the `position` baseline was measured: {saved} of 18 rollouts kept" in last, last
    resumed = subprocess.run([*argv, "resume=true"], capture_output=True, text=True, env=env)
    assert resumed.returncode == 0, resumed.stderr
    assert "baseline" in (tmp_path / "nothing" / "report.json").read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "nothing"], "the partial takes are cleaned up"
