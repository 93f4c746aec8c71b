"""LeRobot v3.0 dataset reader: the writer's counterpart.

Everything that reads a dataset back — `gen.check`, `gen.verify`, `gen.preview`, training —
finds an (episode, camera)'s video file and frame range here, from the dataset's own metadata
(info.json's `video_path` template, the episodes table's chunk/file indices and time span),
never by formatting paths itself. Decoding reads each mp4 once, in order, and stops at the last
frame asked for: seeking in these many-episodes-per-file videos costs more than reading on.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import av
import numpy as np
import pandas as pd

from core import parquet
from core.products import EPISODES_DIR, INFO_PATH, STATS_PATH, TASKS_PATH
from core.profiles import IMAGE_PREFIX


@dataclass(frozen=True)
class VideoSpan:
    """Where one episode's frames of one camera sit: `length` frames from frame `first` of `path`."""

    episode: int
    path: Path
    first: int
    length: int
    from_timestamp: float
    to_timestamp: float


class LeRobotReader:
    """A LeRobot v3.0 dataset folder, read through its metadata. Attributes load on first use."""

    def __init__(self, root: Path | str) -> None:
        self.root = Path(root)

    @cached_property
    def info(self) -> dict:
        return json.loads((self.root / INFO_PATH).read_text())

    @property
    def fps(self) -> int:
        return self.info["fps"]

    @cached_property
    def episodes(self) -> pd.DataFrame:
        """The episodes table, one row per episode, in episode order."""
        return parquet.read(self.root / EPISODES_DIR).sort_values("episode_index").reset_index(drop=True)

    @cached_property
    def data(self) -> pd.DataFrame:
        """Every frame's row (state, action, indices), in dataset order."""
        return parquet.read(self.root / "data").sort_values("index").reset_index(drop=True)

    @cached_property
    def tasks(self) -> pd.DataFrame:
        """Indexed by the task string, with its `task_index`."""
        return parquet.read(self.root / TASKS_PATH)

    @cached_property
    def stats(self) -> dict:
        return json.loads((self.root / STATS_PATH).read_text())

    @property
    def video_keys(self) -> list[str]:
        return [k for k, f in self.info["features"].items() if f["dtype"] == "video"]

    @property
    def cameras(self) -> list[str]:
        return [k.removeprefix(IMAGE_PREFIX) for k in self.video_keys]

    def _row(self, episode: int) -> dict:
        return self.episodes.iloc[int(np.searchsorted(self.episodes["episode_index"].to_numpy(), episode))].to_dict()

    def span(self, episode: int, camera: str, row: dict | None = None) -> VideoSpan:
        """The video file and frame range of `episode` for `camera` (a name, not a feature key)."""
        row = self._row(episode) if row is None else row
        key = IMAGE_PREFIX + camera
        start, end = float(row[f"videos/{key}/from_timestamp"]), float(row[f"videos/{key}/to_timestamp"])
        path = self.root / self.info["video_path"].format(
            video_key=key, chunk_index=int(row[f"videos/{key}/chunk_index"]), file_index=int(row[f"videos/{key}/file_index"])
        )
        return VideoSpan(int(row["episode_index"]), path, int(round(start * self.fps)), int(row["length"]), start, end)

    def spans(self, camera: str, episodes: Iterable[int] | None = None) -> list[VideoSpan]:
        """The spans of `episodes` (default: all), in episode order."""
        rows = self.episodes.to_dict("records")
        if episodes is not None:
            wanted = set(episodes)
            rows = [r for r in rows if int(r["episode_index"]) in wanted]
        return [self.span(int(r["episode_index"]), camera, r) for r in rows]

    def decode(
        self, camera: str, episodes: Iterable[int] | None = None, limit: int | None = None
    ) -> Iterator[tuple[int, int, np.ndarray]]:
        """(episode, frame index in the episode, RGB frame) for the first `limit` frames (default:
        all) of each of `episodes`, decoding every file once, in file order."""
        by_file: dict[Path, dict[int, tuple[int, int]]] = {}
        for s in self.spans(camera, episodes):
            for k in range(s.length if limit is None else min(limit, s.length)):
                by_file.setdefault(s.path, {})[s.first + k] = (s.episode, k)
        for path, wanted in by_file.items():
            last = max(wanted)
            with av.open(str(path)) as container:
                for i, frame in enumerate(container.decode(container.streams.video[0])):
                    if i in wanted:
                        yield (*wanted[i], frame.to_ndarray(format="rgb24"))
                    if i >= last:
                        break

    def episode_frames(self, episode: int, camera: str) -> np.ndarray:
        """All frames of one episode's camera, (length, H, W, 3) uint8."""
        return np.stack([frame for _, _, frame in self.decode(camera, [episode])])

    def first_frames(self, camera: str, episodes: Iterable[int]) -> dict[int, np.ndarray]:
        return {ep: frame for ep, _, frame in self.decode(camera, episodes, limit=1)}

    def camera_shape(self, camera: str) -> tuple[int, int, int, int]:
        """(total_frames, H, W, 3): what `camera_frames` fills."""
        height, width, _ = self.info["features"][IMAGE_PREFIX + camera]["shape"]
        return (self.info["total_frames"], height, width, 3)

    def camera_frames(self, camera: str, out: np.ndarray | None = None) -> np.ndarray:
        """Every frame of a camera in dataset order, (total_frames, H, W, 3) uint8, into `out` if
        given (e.g. a memory-mapped file: a big dataset's frames need not fit in memory)."""
        out = np.empty(self.camera_shape(camera), np.uint8) if out is None else out
        starts = dict(zip(self.episodes["episode_index"].astype(int), self.episodes["dataset_from_index"].astype(int)))
        for ep, k, frame in self.decode(camera):
            out[starts[ep] + k] = frame
        return out


def frame_count(path: Path) -> int:
    """Frames in an mp4, counted from its packets without decoding."""
    with av.open(str(path)) as container:
        return sum(1 for p in container.demux(container.streams.video[0]) if p.size)
