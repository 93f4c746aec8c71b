"""The LeRobot writer on its own: files rotate by size and every frame decodes where the loader
expects it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from ledataset.datasets.lerobot_dataset import LeRobotDataset

from core import parquet
from gen.lerobot.stats import image_histogram, image_stats
from gen.lerobot.video import encode_episode
from gen.lerobot.writer import Episode, LeRobotWriter, Recording

FPS, SIZE = 20, 32


def synthetic_episode(ep: int, length: int) -> Episode:
    """Frames whose red channel encodes the frame index and green the episode."""
    frames = np.zeros((length, SIZE, SIZE, 3), np.uint8)
    frames[..., 0] = (np.arange(length) * 8 % 256)[:, None, None]
    frames[..., 1] = ep * 60
    states = np.tile(np.arange(3, dtype=np.float32), (length, 1)) + ep
    actions = np.full((length, 2), ep, np.float32)
    return Episode(
        task=f"task {ep % 2}",
        states=states,
        actions=actions,
        videos={"cam": encode_episode(frames, FPS)},
        histograms={"cam": image_histogram(frames)},
    )


def test_rotation_and_decoding(tmp_path: Path) -> None:
    recording = Recording(FPS, SIZE, ("cam",), ("a", "b", "c"), ("u", "v"))
    writer = LeRobotWriter(tmp_path, recording, data_files_size_in_mb=0, video_files_size_in_mb=0, chunks_size=2)
    lengths = [7, 12, 9]
    for ep, length in enumerate(lengths):
        writer.add(synthetic_episode(ep, length))
    writer.finalize()
    # size limits of 0 put every episode in a file of its own, two files per chunk
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.glob("data/*/*.parquet")) == [
        "data/chunk-000/file-000.parquet",
        "data/chunk-000/file-001.parquet",
        "data/chunk-001/file-000.parquet",
    ]
    ds = LeRobotDataset("local/synthetic", root=tmp_path)
    assert len(ds) == sum(lengths)
    for ep, length in enumerate(lengths):
        start = ds.meta.episodes[ep]["dataset_from_index"]
        for k in range(length):
            item = ds[start + k]
            frame = item["observation.images.cam"]
            assert abs(float(frame[0].mean()) * 255 - (k * 8 % 256)) < 4
            assert abs(float(frame[1].mean()) * 255 - ep * 60) < 4
            assert item["task"] == f"task {ep % 2}"
            assert float(item["action"][0]) == ep
    episodes = parquet.read(tmp_path / "meta/episodes")
    assert list(episodes["length"]) == lengths


def test_image_stats_from_histograms_are_exact() -> None:
    rng = np.random.default_rng(0)
    frames = rng.integers(0, 256, size=(5, 8, 8, 3), dtype=np.uint8)
    s = image_stats(image_histogram(frames), len(frames))
    pixels = frames.reshape(-1, 3) / 255.0
    np.testing.assert_allclose(s["mean"].ravel(), pixels.mean(0), atol=1e-12)
    np.testing.assert_allclose(s["std"].ravel(), pixels.std(0), atol=1e-9)
    np.testing.assert_allclose(s["min"].ravel(), pixels.min(0))
    np.testing.assert_allclose(s["max"].ravel(), pixels.max(0))
    np.testing.assert_allclose(s["q50"].ravel(), np.quantile(pixels, 0.5, axis=0, method="inverted_cdf"))
    assert s["count"].tolist() == [5]
