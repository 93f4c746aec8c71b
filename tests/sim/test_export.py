"""`python -m gen.export <dataset> format=v2.1`: the same episodes as a LeRobot v2.1 dataset, loaded
by lerobot 0.3.3's own `LeRobotDataset` (the last release of that format, in its own environment
`.venv-v21`, made by `make setup`) with the same frames count, the same actions and first frames
that decode within 3/255 of the v3.0 dataset's."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gen.lerobot.reader import LeRobotReader

ROOT = Path(__file__).resolve().parents[2]
V21_PYTHON = ROOT / ".venv-v21" / "bin" / "python"

# Runs in .venv-v21: everything lerobot 0.3.3 hands a trainer, saved for the comparison.
LOAD_V21 = """
import sys, numpy as np, lerobot
from lerobot.datasets.lerobot_dataset import LeRobotDataset
assert lerobot.__version__ == "0.3.3", lerobot.__version__
ds = LeRobotDataset("local/export", root=sys.argv[1])
firsts = [int(i) for i in ds.episode_data_index["from"]]
out = {"version": np.array(ds.meta.info["codebase_version"]), "frames": np.array(ds.num_frames),
       "episodes": np.array(ds.num_episodes), "action": np.stack([ds.hf_dataset[i]["action"].numpy() for i in range(len(ds))])}
for key in ds.meta.video_keys:
    out[key] = np.stack([(ds[i][key].numpy().transpose(1, 2, 0) * 255).round() for i in firsts])
out["tasks"] = np.array([ds[i]["task"] for i in firsts])
np.savez(sys.argv[2], **out)
"""


def _export(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gen.export", *args], capture_output=True, text=True, cwd=ROOT)


@pytest.fixture(scope="module")
def exported(object_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("v21") / "object-v21"
    done = _export(str(object_dataset), "format=v2.1", f"out={out}")
    assert done.returncode == 0, done.stderr
    return out


def test_the_v21_export_loads_in_lerobot_v21_with_the_same_frames_and_actions(
    exported: Path, object_dataset: Path, tmp_path: Path
) -> None:
    loaded = subprocess.run(
        [str(V21_PYTHON), "-c", LOAD_V21, str(exported), str(tmp_path / "v21.npz")],
        capture_output=True,
        text=True,
        env={"HF_HUB_OFFLINE": "1", "PATH": "/usr/bin:/bin"},
    )
    assert loaded.returncode == 0, loaded.stderr[-3000:]
    v21 = np.load(tmp_path / "v21.npz")
    source = LeRobotReader(object_dataset)
    assert str(v21["version"]) == "v2.1"
    assert int(v21["frames"]) == source.info["total_frames"] and int(v21["episodes"]) == len(source.episodes)
    np.testing.assert_array_equal(v21["action"], np.stack(source.data["action"].to_numpy()))
    episodes = source.episodes["episode_index"].tolist()
    for camera, key in zip(source.cameras, source.video_keys):
        firsts = source.first_frames(camera, episodes)
        ours = np.stack([firsts[ep] for ep in episodes]).astype(np.float64)
        assert np.abs(v21[key] - ours).max() <= 3, key
    assert list(v21["tasks"]) == [t[0] for t in source.episodes["tasks"]]
    lines = (exported / "meta" / "episodes_stats.jsonl").read_text().splitlines()
    assert len(lines) == len(episodes) and set(json.loads(lines[0])["stats"]) >= {
        "action",
        "observation.state",
        *source.video_keys,
    }


def test_bad_exports_are_refused_and_rerunning_is_safe(exported: Path, object_dataset: Path, tmp_path: Path) -> None:
    again = _export(str(object_dataset), "format=v2.1", f"out={exported}")
    assert again.returncode == 2
    assert again.stderr.strip() == f"error: out={exported} is not empty; pass overwrite=true to replace it"
    info = (exported / "meta" / "info.json").read_text()
    replaced = _export(str(object_dataset), "format=v2.1", f"out={exported}", "overwrite=true")
    assert replaced.returncode == 0 and (exported / "meta" / "info.json").read_text() == info
    assert not exported.with_name(exported.name + ".exporting").exists()
    inside = _export(str(object_dataset), "format=v2.1", f"out={object_dataset / 'v21'}")
    assert inside.returncode == 2 and "inside the source dataset" in inside.stderr
    unknown = _export(str(object_dataset), "format=v1.6", f"out={tmp_path / 'x'}")
    assert unknown.returncode == 2 and unknown.stderr.strip() == "error: format must be one of v2.1, got 'v1.6'"
    missing = _export(str(tmp_path / "nothing"), f"out={tmp_path / 'y'}")
    assert missing.returncode == 2 and "cannot export" in missing.stderr and not (tmp_path / "y").exists()


def test_overwrite_replaces_only_an_earlier_export_and_never_a_users_files(
    exported: Path, object_dataset: Path, tmp_path: Path
) -> None:
    """overwrite=true replaces an earlier export; a v3.0 dataset, an exam holding the user's analysis,
    an export the user added notes to, or a file are refused in one line, every byte left in place."""
    import shutil

    dataset = tmp_path / "dataset"
    shutil.copytree(object_dataset, dataset)
    (dataset / "NOTES.txt").write_text("mine")
    exam = tmp_path / "exam"
    exam.mkdir()
    (exam / "exam.json").write_text(json.dumps({"format": "deconfound-exam", "version": 2}))
    (exam / "analysis.txt").write_text("mine")
    noted = tmp_path / "noted"
    shutil.copytree(exported, noted)
    (noted / "NOTES.txt").write_text("mine")
    for out, says in (
        (dataset, f"out={dataset} holds a dataset made here; overwrite=true replaces only an export"),
        (exam, f"out={exam} holds an exam made here; overwrite=true replaces only an export"),
        (noted, "files this project did not write (NOTES.txt)"),
    ):
        before = sorted((p.relative_to(out), p.read_bytes() if p.is_file() else b"") for p in out.rglob("*"))
        refused = _export(str(object_dataset), "format=v2.1", f"out={out}", "overwrite=true")
        assert refused.returncode == 2 and len(refused.stderr.strip().splitlines()) == 1, refused.stderr
        assert says in refused.stderr
        assert sorted((p.relative_to(out), p.read_bytes() if p.is_file() else b"") for p in out.rglob("*")) == before
    a_file = tmp_path / "a-file"
    a_file.write_text("mine")
    refused = _export(str(object_dataset), "format=v2.1", f"out={a_file}")
    assert refused.returncode == 2 and refused.stderr.strip() == f"error: out={a_file} exists and is not a folder"
    assert a_file.read_text() == "mine"
