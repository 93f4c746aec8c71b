"""Generated datasets load with lerobot's own loader, pass lerobot-doctor, carry exact stats and
scene records, and are byte-for-byte reproducible from (spec, seed)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from ledataset.datasets.lerobot_dataset import LeRobotDataset

from core import parquet
from core.spec import EpisodeSpec
from gen.products import scenes
from helpers import make_dataset


def test_lerobot_loader_decodes_every_episode(object_dataset: Path) -> None:
    ds = LeRobotDataset("local/object", root=object_dataset)
    info = json.loads((object_dataset / "meta/info.json").read_text())
    assert info["codebase_version"] == "v3.0"
    assert ds.num_episodes == info["total_episodes"] == 4
    assert len(ds) == info["total_frames"]
    records = scenes.read(object_dataset)
    episodes = ds.meta.episodes
    for ep in range(ds.num_episodes):
        start, end = episodes[ep]["dataset_from_index"], episodes[ep]["dataset_to_index"]
        for idx in (start, (start + end) // 2, end - 1):
            item = ds[idx]
            assert int(item["episode_index"]) == ep
            for cam in ("agentview", "wrist"):
                frame = item[f"observation.images.{cam}"]
                assert tuple(frame.shape) == (3, 64, 64)
                assert 0.0 <= float(frame.min()) and float(frame.max()) <= 1.0 and float(frame.std()) > 0.02
            assert item["task"] == records.loc[records.episode_index == ep, "instruction"].item()
            assert tuple(item["observation.state"].shape) == (16,) and tuple(item["action"].shape) == (8,)


def test_action_chunks_load(object_dataset: Path) -> None:
    ds = LeRobotDataset("local/object", root=object_dataset, delta_timestamps={"action": [i / 20 for i in range(10)]})
    last = ds.meta.episodes[0]["dataset_to_index"] - 1
    item = ds[last]
    assert tuple(item["action"].shape) == (10, 8)
    assert bool(item["action_is_pad"][1:].all()) and not bool(item["action_is_pad"][0])


def test_lerobot_doctor_finds_no_failure(object_dataset: Path) -> None:
    doctor = Path(sys.executable).with_name("lerobot-doctor")
    result = subprocess.run([str(doctor), "check", str(object_dataset), "--json"], capture_output=True, text=True)
    report = json.loads(result.stdout)
    failures = [m for c in report["checks"] for m in c["messages"] if m["severity"] == "FAIL"]
    assert not failures, failures
    assert report["overall_severity"] in ("PASS", "WARN")


def test_stats_are_exact_and_images_vary(object_dataset: Path) -> None:
    stats = json.loads((object_dataset / "meta/stats.json").read_text())
    data = parquet.read(object_dataset / "data")
    actions = np.stack(data["action"].to_numpy())
    np.testing.assert_allclose(stats["action"]["mean"], actions.mean(0), rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(stats["action"]["std"], actions.std(0), rtol=1e-5, atol=1e-7)
    for cam in ("agentview", "wrist"):
        s = stats[f"observation.images.{cam}"]
        assert np.asarray(s["std"]).shape == (3, 1, 1)
        assert min(np.ravel(s["std"])) > 0.05, "image std must not collapse to 0"
        assert all(0.0 <= v <= 1.0 for v in np.ravel(s["mean"]))
    episodes = parquet.read(object_dataset / "meta/episodes")
    assert {"dataset_from_index", "dataset_to_index", "videos/observation.images.wrist/from_timestamp"} <= set(episodes)


def test_tasks_are_indexed_by_instruction(object_dataset: Path) -> None:
    tasks = parquet.read(object_dataset / "meta/tasks.parquet")
    records = scenes.read(object_dataset)
    assert set(tasks.index) == set(records["instruction"])
    assert sorted(tasks["task_index"]) == list(range(len(tasks)))


def test_scene_records_schema(object_dataset: Path) -> None:
    records = scenes.read(object_dataset)
    assert list(records["episode_index"]) == list(range(4))
    for _, rec in records.iterrows():
        scene = json.loads(rec["scene"])
        ids = {o["id"] for o in scene["objects"]}
        assert rec["target"] in ids
        for obj in scene["objects"]:
            assert {"id", "name", "slot", "pos"} <= set(obj) and len(obj["pos"]) == 3
        cfs = json.loads(rec["counterfactuals"])
        assert {c["target"] for c in cfs} == ids - {rec["target"]}
        spec = EpisodeSpec.from_json(rec["spec"])
        assert spec.hash == rec["spec_hash"] and spec.instruction == rec["instruction"]


def test_same_seed_same_bytes(tmp_path: Path) -> None:
    """Made in this process and by a pool of fresh workers: the same bytes."""
    a = make_dataset(tmp_path / "a", "n=2", "image_size=32", "seed=3")
    b = make_dataset(tmp_path / "b", "n=2", "image_size=32", "seed=3", "workers=2")
    for rel in (
        "meta/scenes.parquet",
        "data/chunk-000/file-000.parquet",
        "meta/stats.json",
        "videos/observation.images.agentview/chunk-000/file-000.mp4",
    ):
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    c = make_dataset(tmp_path / "c", "n=2", "image_size=32", "seed=4")
    assert (a / "meta/scenes.parquet").read_bytes() != (c / "meta/scenes.parquet").read_bytes()


def test_contact_sheet(object_dataset: Path, tmp_path: Path) -> None:
    import cv2

    from gen.products.sheet import contact_sheet

    sheet = cv2.imread(str(contact_sheet(object_dataset, tmp_path / "sheet.png", n=4)))
    assert sheet.shape == (256 + 54, 4 * 256, 3)
    assert sheet[:256].std() > 10  # real frames, not blank tiles
    plan = make_dataset(tmp_path / "plan", "referent=negation", "n=3", "plan_only=true")
    rendered = cv2.imread(str(contact_sheet(plan, tmp_path / "plan.png")))
    assert rendered.shape[0] == 256 + 54 and rendered[:256, :256].std() > 10
