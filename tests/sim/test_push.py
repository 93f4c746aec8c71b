"""Pushing datasets and exams to a hub: the real `huggingface_hub` client against a small
hub on loopback (tests/hubserver.py) that records every request."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from hubserver import Hub
from ledataset.datasets.lerobot_dataset import LeRobotDataset

from core.exam import EXAM_VERSION
from helpers import ONE_TRIAL, Shared

TOKEN = "hf_not_a_real_token_4f8a"


def _env(hub: Hub) -> dict[str, str]:
    return {**os.environ, "HF_ENDPOINT": hub.url, "HF_TOKEN": TOKEN, "HF_HUB_OFFLINE": "0"}


def _push(hub: Hub, root: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gen.push", str(root), *args], capture_output=True, text=True, env=_env(hub))


def _local_files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


def test_push_then_pull_back_and_load(object_dataset: Path, tmp_path: Path) -> None:
    with Hub() as hub:
        result = _push(hub, object_dataset, "repo_id=lab/object-demo", "private=true")
        assert result.returncode == 0, result.stderr
        assert TOKEN not in result.stdout + result.stderr
        repo = hub.repos["lab/object-demo"]
        assert repo.private
        assert set(repo.files) == _local_files(object_dataset)
        assert {f for f in repo.files if f.startswith(("data/", "videos/", "meta/"))} >= {
            "data/chunk-000/file-000.parquet",
            "meta/info.json",
            "meta/episodes/chunk-000/file-000.parquet",
            "meta/tasks.parquet",
            "meta/stats.json",
            "meta/scenes.parquet",
            "meta/audit.json",
            "videos/observation.images.agentview/chunk-000/file-000.mp4",
            "videos/observation.images.wrist/chunk-000/file-000.mp4",
        }
        assert repo.refs["v3.0"] == repo.refs["main"]
        assert all(r["auth"] == f"Bearer {TOKEN}" for r in hub.requests if r["method"] == "POST")
        card = repo.files["README.md"].decode()
        front = yaml.safe_load(card.split("---")[1])
        assert "LeRobot" in front["tags"] and front["task_categories"] == ["robotics"]
        assert front["configs"][0]["data_files"] == "data/*/*.parquet" and front["license"]
        assert "## Confound audit" in card and "referent spec hash" in card and "split=exam" in card
        assert "](preview.png)" in card and repo.files["preview.png"].startswith(b"\x89PNG")
        pulled = tmp_path / "pulled"
        code = (
            "from huggingface_hub import snapshot_download;"
            f"snapshot_download('lab/object-demo', repo_type='dataset', revision='v3.0', local_dir='{pulled}')"
        )
        subprocess.run([sys.executable, "-c", code], check=True, env=_env(hub), capture_output=True)
    ds = LeRobotDataset("lab/object-demo", root=pulled)
    assert ds.num_episodes == 4 and ds[0]["observation.images.agentview"].shape[0] == 3


def test_failed_upload_says_what_happened_and_retry_works(object_dataset: Path) -> None:
    with Hub() as hub:
        hub.fail_commits = 1
        failed = _push(hub, object_dataset, "repo_id=lab/flaky")
        assert failed.returncode == 1 and len(failed.stderr.strip().splitlines()) == 1
        assert "failed while uploading" in failed.stderr and "nothing was committed" in failed.stderr and "retry" in failed.stderr
        assert TOKEN not in failed.stderr and not hub.repos["lab/flaky"].files
        retried = _push(hub, object_dataset, "repo_id=lab/flaky")
        assert retried.returncode == 0, retried.stderr
        assert set(hub.repos["lab/flaky"].files) == _local_files(object_dataset)


def _pull(hub: Hub, repo_id: str, revision: str, into: Path) -> set[str]:
    """What a loader gets for `revision`: the files, downloaded the way lerobot does."""
    code = (
        "from huggingface_hub import snapshot_download;"
        f"snapshot_download({repo_id!r}, repo_type='dataset', revision={revision!r}, local_dir={str(into)!r})"
    )
    subprocess.run([sys.executable, "-c", code], check=True, env=_env(hub), capture_output=True)
    return _local_files(into) - {f for f in _local_files(into) if f.startswith(".cache/")}


def _same_bytes(a: Path, b: Path, files: set[str]) -> bool:
    return all((a / f).read_bytes() == (b / f).read_bytes() for f in files)


@pytest.mark.parametrize("kind", ["dataset", "exam"])
def test_a_second_push_moves_the_tag_to_the_new_data(kind: str, shared: Shared, tmp_path: Path) -> None:
    extra = ["split=exam", "n=1"] if kind == "exam" else ["n=2"]
    first, second = (shared.dataset(kind, *extra, "image_size=32", f"seed={seed}", "workers=1") for seed in (1, 2))
    tag = f"exam-v{EXAM_VERSION}" if kind == "exam" else "v3.0"
    with Hub() as hub:
        assert _push(hub, first, "repo_id=lab/again").returncode == 0
        result = _push(hub, second, "repo_id=lab/again")
        assert result.returncode == 0, result.stderr
        repo = hub.repos["lab/again"]
        assert len(repo.commits) == 2 and repo.refs[tag] == repo.commits[-1] == repo.refs["main"]
        assert f"commit {repo.commits[-1][:12]}, tag {tag}" in result.stdout
        pulled = _pull(hub, "lab/again", tag, tmp_path / "pulled")
    assert pulled == _local_files(second)
    assert _same_bytes(tmp_path / "pulled", second, pulled) and not _same_bytes(
        tmp_path / "pulled", first, pulled & _local_files(first)
    )


def test_refuses_incomplete_or_damaged_datasets(object_dataset: Path, tmp_path: Path) -> None:
    damaged = tmp_path / "damaged"
    shutil.copytree(object_dataset, damaged)
    (damaged / "meta/generation.json").unlink()
    with Hub() as hub:
        result = _push(hub, damaged, "repo_id=lab/bad")
        assert result.returncode == 1 and "refusing to push" in result.stderr
        assert not hub.requests


def test_a_video_that_cannot_be_decoded_fails_the_check_and_is_never_pushed(object_dataset: Path, tmp_path: Path) -> None:
    """2,000 bytes zeroed in the middle of one mp4: lerobot's loader cannot decode it, so gen.check
    names the file and the frame that fails, and gen.push, which it gates, sends nothing."""
    damaged = tmp_path / "damaged"
    shutil.copytree(object_dataset, damaged)
    video = next((damaged / "videos").rglob("*.mp4"))
    data = bytearray(video.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 2000] = bytes(2000)
    video.write_bytes(bytes(data))
    check = subprocess.run([sys.executable, "-m", "gen.check", str(damaged)], capture_output=True, text=True)
    assert check.returncode == 1 and len(check.stderr.strip().splitlines()) == 1, check.stderr
    assert str(video.relative_to(damaged)) in check.stderr and "cannot be decoded" in check.stderr
    assert re.search(r"frame \d+ \(episode \d+'s frame \d+\)", check.stderr), check.stderr
    with Hub() as hub:
        result = _push(hub, damaged, "repo_id=lab/bad")
        assert result.returncode == 1 and "refusing to push" in result.stderr and "cannot be decoded" in result.stderr
        assert not hub.requests


@pytest.fixture
def exam(shared: Shared) -> Path:
    return shared.dataset("exam", *ONE_TRIAL)


def test_exams_push_with_their_own_tag(exam: Path) -> None:
    with Hub() as hub:
        result = _push(hub, exam, "repo_id=lab/object-exam", "branch=v1")
        assert result.returncode == 0, result.stderr
        repo = hub.repos["lab/object-exam"]
        assert set(repo.files) == {"exam.json", "trials.parquet", "answers.parquet", "README.md"}
        assert f"exam-v{EXAM_VERSION}" in repo.refs and "v1" in repo.refs  # the format's tag; the branch asked for
        assert "trials.parquet" in yaml.safe_load(repo.files["README.md"].decode().split("---")[1])["configs"][0]["data_files"]


def test_an_unreachable_hub_is_named_in_one_line(object_dataset: Path) -> None:
    env = {**os.environ, "HF_ENDPOINT": "http://127.0.0.1:9", "HF_TOKEN": TOKEN, "HF_HUB_OFFLINE": "0"}
    result = subprocess.run(
        [sys.executable, "-m", "gen.push", str(object_dataset), "repo_id=lab/x"], capture_output=True, text=True, env=env
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 1 and len(lines) == 1 and "cannot reach the hub (127.0.0.1:9)" in lines[0], result.stderr
    assert "Retry" not in lines[0] and "nothing was committed" in lines[0]
