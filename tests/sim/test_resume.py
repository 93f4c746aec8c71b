"""Crash-safe, resumable, reproducible generation, and the integrity check.

A run is SIGKILLed at several points (fault injection, jobs/faults.py); resuming it must give the
same bytes as a run that was never interrupted, with no episode lost or duplicated."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from core import parquet
from helpers import interruptible

ARGS = ("n=3", "image_size=32", "seed=5")
FILES = (
    "data/chunk-000/file-000.parquet",
    "meta/scenes.parquet",
    "meta/episodes/chunk-000/file-000.parquet",
    "meta/tasks.parquet",
    "meta/stats.json",
    "meta/info.json",
    "videos/observation.images.agentview/chunk-000/file-000.mp4",
    "videos/observation.images.wrist/chunk-000/file-000.mp4",
)


def _gen(*args: str, crash: str | None = None, once: Path | None = None, workers: int = 1) -> subprocess.CompletedProcess[str]:
    env = {**os.environ}
    if crash:
        env["DECONFOUND_CRASH_AT"] = crash
    if once:
        env["DECONFOUND_CRASH_ONCE"] = str(once)
    argv = [sys.executable, "-m", "gen", *ARGS, f"workers={workers}", *args]
    return subprocess.run(argv, capture_output=True, text=True, env=env)


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("clean") / "ds"
    assert _gen(f"out={out}").returncode == 0
    return out


@pytest.mark.parametrize("point", ["episode:1", "save:2", "assemble:1", "finalize"])
def test_resume_after_sigkill_gives_identical_bytes(clean: Path, tmp_path: Path, point: str) -> None:
    out = tmp_path / "ds"
    killed = _gen(f"out={out}", crash=point)
    assert killed.returncode == -9
    assert not out.exists(), "nothing may appear at out before the run completes"
    refused = _gen(f"out={out}")
    assert refused.returncode == 2 and "resume=true" in refused.stderr
    resumed = _gen(f"out={out}", "resume=true")
    assert resumed.returncode == 0, resumed.stderr
    for rel in FILES:
        assert (out / rel).read_bytes() == (clean / rel).read_bytes(), rel
    episodes = parquet.read(out / "meta/episodes")
    assert list(episodes["episode_index"]) == [0, 1, 2]
    assert not list(tmp_path.glob(".ds.*")), "the partial run is cleaned up"


def test_a_worker_killed_mid_episode_is_replaced_and_the_data_is_unchanged(clean: Path, tmp_path: Path) -> None:
    out, once = tmp_path / "ds", tmp_path / "crashed"
    run = _gen(f"out={out}", crash="worker:1", once=once, workers=2)
    assert run.returncode == 0, run.stderr
    assert once.is_file(), "the fault was injected"
    for rel in FILES:
        assert (out / rel).read_bytes() == (clean / rel).read_bytes(), rel


def test_a_worker_that_keeps_dying_stops_the_run_with_a_clear_error(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    run = _gen(f"out={out}", crash="worker:1", workers=2)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines()[-1].startswith("error: a worker process died 3 times"), run.stderr
    assert not out.exists()


def test_resume_refuses_other_options(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    assert _gen(f"out={out}", crash="episode:1").returncode == -9
    other_args = ["n=4", "image_size=32", "seed=5", "workers=1", f"out={out}", "resume=true"]
    other = subprocess.run([sys.executable, "-m", "gen", *other_args], capture_output=True, text=True)
    assert other.returncode == 2 and "used other options (n was 3, now 4)" in other.stderr


def test_resume_of_a_finished_run_is_a_no_op_and_refuses_other_options(clean: Path, tmp_path: Path) -> None:
    out = _copy(clean, tmp_path / "ds")
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    again = _gen(f"out={out}", "resume=true")
    assert again.returncode == 0, again.stderr
    assert "already complete" in again.stdout
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    other = subprocess.run(
        [sys.executable, "-m", "gen", "n=4", "image_size=32", "seed=5", f"out={out}", "resume=true"],
        capture_output=True,
        text=True,
    )
    assert other.returncode == 2 and len(other.stderr.strip().splitlines()) == 1
    assert "another n (3, not 4)" in other.stderr, other.stderr
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_downstream_refuses_an_incomplete_dataset(tmp_path: Path) -> None:
    out = tmp_path / "ds"
    assert _gen(f"out={out}", crash="finalize").returncode == -9
    half = tmp_path / ".ds.partial" / "dataset"
    assert (half / "meta/info.json").is_file() and not (half / "meta/generation.json").exists()
    train = subprocess.run(
        [sys.executable, "-m", "train", f"dataset={half}", "steps=1", f"out={tmp_path / 'c'}"], capture_output=True, text=True
    )
    assert train.returncode == 2 and "incomplete generated dataset" in train.stderr
    check = subprocess.run([sys.executable, "-m", "gen.check", str(half)], capture_output=True, text=True)
    assert check.returncode == 1 and "not a complete generated dataset" in check.stderr


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


def _check(root: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gen.check", str(root)], capture_output=True, text=True)


def test_check_passes_a_fresh_dataset_and_catches_damage(clean: Path, tmp_path: Path) -> None:
    assert _check(clean).returncode == 0
    video = _copy(clean, tmp_path / "video") / FILES[-1]
    video.write_bytes(video.read_bytes()[: len(video.read_bytes()) // 2])
    missing = _copy(clean, tmp_path / "missing")
    table = pq.read_table(missing / FILES[2])
    pq.write_table(table.slice(0, 2), missing / FILES[2])
    frames = _copy(clean, tmp_path / "frames")
    data = pq.read_table(frames / FILES[0])
    pq.write_table(pa.concat_tables([data.slice(0, 10), data.slice(11)]), frames / FILES[0])
    for root, needle in [
        (tmp_path / "video", "observation.images.wrist"),
        (missing, "meta/episodes has 2"),
        (frames, "frames"),
    ]:
        result = _check(root)
        assert result.returncode == 1 and len(result.stderr.strip().splitlines()) == 1 and needle in result.stderr, result.stderr


def test_verify_regenerates_and_catches_tampering(clean: Path, tmp_path: Path) -> None:
    ok = subprocess.run([sys.executable, "-m", "gen.verify", str(clean), "episodes=2"], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    tampered = _copy(clean, tmp_path / "tampered")
    table = pq.read_table(tampered / FILES[0]).to_pylist()
    table[7]["action"] = [a + 1e-3 for a in table[7]["action"]]
    pq.write_table(pa.Table.from_pylist(table, schema=pq.read_schema(tampered / FILES[0])), tampered / FILES[0])
    bad = subprocess.run([sys.executable, "-m", "gen.verify", str(tampered), "episodes=3"], capture_output=True, text=True)
    assert bad.returncode == 1 and "episode 0: actions differ" in bad.stderr


def test_generation_records_what_regenerates_it(clean: Path) -> None:
    record = json.loads((clean / "meta/generation.json").read_text())
    assert record["complete"] is True and record["config"]["seed"] == 5
    assert record["mujoco"] == "3.9.0" and record["robosuite"] == "1.5.2" and len(record["referent_spec_hash"]) == 16


def _files(root: Path) -> dict[Path, bytes]:
    return {p: p.read_bytes() for p in root.rglob("*") if p.is_file()}


def test_overwrite_refuses_a_product_folder_that_also_holds_the_users_files(clean: Path, tmp_path: Path) -> None:
    """overwrite=true replaces what this project wrote, never a report or notes the user put in it."""
    exam = tmp_path / "exam"
    assert _gen(f"out={exam}", "split=exam").returncode == 0
    report = exam / "report-nothing"
    took = subprocess.run(
        [sys.executable, "-m", "eval", "policy=nothing", f"exam={exam}", "rows=1", f"out={report}"],
        capture_output=True,
        text=True,
    )
    assert took.returncode == 0, took.stderr
    dataset = _copy(clean, tmp_path / "ds")
    (dataset / "my_notes.txt").write_text("mine")
    before = _files(tmp_path)
    for out, stray, extra in [(exam, "report-nothing", ["split=exam"]), (dataset, "my_notes.txt", [])]:
        refused = _gen(f"out={out}", "overwrite=true", *extra)
        lines = refused.stderr.strip().splitlines()
        assert refused.returncode == 2 and len(lines) == 1 and stray in lines[0] and "did not write" in lines[0], refused.stderr
    assert _files(tmp_path) == before and not list(tmp_path.glob(".*"))
    shutil.move(report, tmp_path / "report-nothing")
    assert _gen(f"out={exam}", "split=exam", "overwrite=true").returncode == 0


def test_a_second_run_on_the_same_out_is_told_another_run_is_using_it(clean: Path, tmp_path: Path) -> None:
    """The first run holds its partial run locked: the second, with or without resume=true or
    overwrite=true, is refused with one line and the first completes to the same bytes."""
    out = tmp_path / "ds"
    argv = [sys.executable, "-m", "gen", *ARGS, "workers=1", f"out={out}"]
    first = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    record = tmp_path / ".ds.partial" / "run.json"
    deadline = time.monotonic() + 120
    while not record.is_file() and first.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.kill(first.pid, signal.SIGSTOP)  # still holding its lock, and certain not to finish meanwhile
    try:
        for extra in ([], ["resume=true"], ["overwrite=true"]):
            second = _gen(f"out={out}", *extra)
            lines = second.stderr.strip().splitlines()
            assert second.returncode == 2 and len(lines) == 1 and "another run is using" in lines[0], second.stderr
    finally:
        os.kill(first.pid, signal.SIGCONT)
    _, err = first.communicate()
    assert first.returncode == 0, err
    for rel in FILES:
        assert (out / rel).read_bytes() == (clean / rel).read_bytes(), rel


def test_ctrl_c_says_what_is_kept_and_that_resume_continues(clean: Path, tmp_path: Path) -> None:
    """Ctrl-C mid-run: the line says how many finished episodes the partial run keeps and that
    resume=true continues (it said nothing was written, as if the work were lost); resume then gives
    the uninterrupted bytes."""
    out = tmp_path / "ds"
    argv = interruptible("gen", *ARGS, "workers=1", f"out={out}")
    kept = tmp_path / ".ds.partial" / "episodes"
    running = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while len(list(kept.glob("*.pkl"))) < 1 and running.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    os.kill(running.pid, signal.SIGSTOP)
    saved = len(list(kept.glob("*.pkl")))
    os.kill(running.pid, signal.SIGINT)
    os.kill(running.pid, signal.SIGCONT)
    _, err = running.communicate()
    last = err.strip().splitlines()[-1]
    said = re.search(rf"(\d+) of 3 episodes kept in {re.escape(str(tmp_path / '.ds.partial'))}", last)
    assert running.returncode == 130 and said and "resume=true" in last and not out.exists(), err
    assert saved <= int(said[1]) == len(list(kept.glob("*.pkl")))
    assert _gen(f"out={out}", "resume=true").returncode == 0
    for rel in FILES:
        assert (out / rel).read_bytes() == (clean / rel).read_bytes(), rel
