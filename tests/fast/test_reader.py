"""The LeRobot reader beside the writer: it finds each (episode, camera)'s video file and frame
range where lerobot's own metadata says they are, and decodes the frames the writer wrote."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from ledataset.datasets.lerobot_dataset import LeRobotDatasetMetadata
from test_writer import FPS, SIZE, synthetic_episode

from gen.lerobot.reader import LeRobotReader, frame_count
from gen.lerobot.writer import LeRobotWriter, Recording

LENGTHS = [7, 12, 9, 5]


def _written(root: Path) -> LeRobotReader:
    """Four episodes, one file each, two files a chunk: spans cross files and chunks."""
    recording = Recording(FPS, SIZE, ("cam",), ("a", "b", "c"), ("u", "v"))
    writer = LeRobotWriter(root, recording, data_files_size_in_mb=0, video_files_size_in_mb=0, chunks_size=2)
    for ep, length in enumerate(LENGTHS):
        writer.add(synthetic_episode(ep, length))
    writer.finalize()
    return LeRobotReader(root)


def _matches(frame: np.ndarray, ep: int, k: int) -> bool:
    """synthetic_episode encodes the frame index in red and the episode in green."""
    return abs(float(frame[..., 0].mean()) - k * 8 % 256) < 4 and abs(float(frame[..., 1].mean()) - ep * 60) < 4


def test_spans_are_where_lerobot_looks(tmp_path: Path) -> None:
    reader = _written(tmp_path)
    meta = LeRobotDatasetMetadata("local/synthetic", root=tmp_path)
    assert reader.cameras == ["cam"]
    for ep, length in enumerate(LENGTHS):
        span = reader.span(ep, "cam")
        assert span.path == tmp_path / meta.get_video_file_path(ep, "observation.images.cam")
        assert span.length == length and span.path.is_file()
        assert frame_count(span.path) >= span.first + span.length
    assert [s.episode for s in reader.spans("cam", [3, 1])] == [1, 3]


def test_decoded_frames_are_the_written_ones(tmp_path: Path) -> None:
    reader = _written(tmp_path)
    for ep, length in enumerate(LENGTHS):
        frames = reader.episode_frames(ep, "cam")
        assert frames.shape == (length, SIZE, SIZE, 3)
        assert all(_matches(frames[k], ep, k) for k in range(length))
    firsts = reader.first_frames("cam", [2, 0])
    assert sorted(firsts) == [0, 2] and _matches(firsts[2], 2, 0) and _matches(firsts[0], 0, 0)
    every = reader.camera_frames("cam")
    assert len(every) == sum(LENGTHS) == len(reader.data)
    for row in reader.data.itertuples():
        assert _matches(every[row.index], row.episode_index, row.frame_index)
