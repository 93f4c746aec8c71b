"""LeRobot v3.0 dataset writer.

Writes what lerobot's own loader reads (lerobot 0.4.x, `codebase_version: "v3.0"`):

    meta/info.json  meta/stats.json  meta/tasks.parquet  meta/episodes/chunk-000/file-000.parquet
    data/chunk-XXX/file-YYY.parquet          many episodes per file, one row group each
    videos/<key>/chunk-XXX/file-YYY.mp4      many episodes per file, remuxed (see gen/lerobot/video.py)

Episodes arrive whole and already verified; the writer never sees a failed demo. Nothing here
knows about scenes or referents: gen/ adds its own meta files beside these.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from core.products import DATA_PATH, EPISODES_PATH, VIDEO_PATH
from core.profiles import IMAGE_PREFIX
from gen.lerobot import stats as st
from gen.lerobot.video import VideoFile, video_info

CODEBASE_VERSION = "v3.0"
DEFAULT_FEATURES = {
    "timestamp": {"dtype": "float32", "shape": [1], "names": None},
    "frame_index": {"dtype": "int64", "shape": [1], "names": None},
    "episode_index": {"dtype": "int64", "shape": [1], "names": None},
    "index": {"dtype": "int64", "shape": [1], "names": None},
    "task_index": {"dtype": "int64", "shape": [1], "names": None},
}


@dataclass(frozen=True)
class Recording:
    """The features of a dataset: camera keys (video), state and action names, rate, size."""

    fps: int
    image_size: int
    cameras: tuple[str, ...]
    state_names: tuple[str, ...]
    action_names: tuple[str, ...]
    codec: str = "h264"

    def video_key(self, camera: str) -> str:
        return IMAGE_PREFIX + camera

    def features(self) -> dict[str, dict]:
        size = self.image_size
        feats: dict[str, dict] = {
            self.video_key(cam): {
                "dtype": "video",
                "shape": [size, size, 3],
                "names": ["height", "width", "channels"],
                "info": video_info(self.codec, size, self.fps),
            }
            for cam in self.cameras
        }
        feats["observation.state"] = {"dtype": "float32", "shape": [len(self.state_names)], "names": list(self.state_names)}
        feats["action"] = {"dtype": "float32", "shape": [len(self.action_names)], "names": list(self.action_names)}
        return {**feats, **DEFAULT_FEATURES}

    def arrow_schema(self) -> pa.Schema:
        return pa.schema(
            [
                ("observation.state", pa.list_(pa.float32(), len(self.state_names))),
                ("action", pa.list_(pa.float32(), len(self.action_names))),
                ("timestamp", pa.float32()),
                ("frame_index", pa.int64()),
                ("episode_index", pa.int64()),
                ("index", pa.int64()),
                ("task_index", pa.int64()),
            ]
        )


@dataclass
class Episode:
    """One verified episode: T frames of state, action and one mp4 per camera."""

    task: str
    states: np.ndarray  # (T, S) float32
    actions: np.ndarray  # (T, A) float32
    videos: dict[str, bytes]  # camera -> mp4 of this episode alone
    histograms: dict[str, np.ndarray]  # camera -> (3, 256) pixel counts
    switch: tuple[int, str] | None = None  # (frame, task from that frame on): the instruction changed mid-course

    @property
    def length(self) -> int:
        return len(self.actions)


@dataclass
class _Rotating:
    """Chunk/file indices of the file currently written, moving on when it grows too big."""

    chunks_size: int
    chunk: int = 0
    file: int = 0

    def next(self) -> None:
        self.file += 1
        if self.file >= self.chunks_size:
            self.chunk, self.file = self.chunk + 1, 0


@dataclass
class LeRobotWriter:
    root: Path
    recording: Recording
    robot_type: str = "panda"
    chunks_size: int = 1000
    data_files_size_in_mb: int = 100
    video_files_size_in_mb: int = 200
    tasks: dict[str, int] = field(default_factory=dict)
    episodes: list[dict] = field(default_factory=list)
    frames: int = 0

    def __post_init__(self) -> None:
        self.root.mkdir(parents=True, exist_ok=True)
        self._data_at = _Rotating(self.chunks_size)
        self._data: pq.ParquetWriter | None = None
        self._data_path: Path | None = None
        self._video_at = {cam: _Rotating(self.chunks_size) for cam in self.recording.cameras}
        self._video: dict[str, VideoFile] = {}
        self._vectors: dict[str, list[np.ndarray]] = {}
        self._histograms = {cam: np.zeros((3, 256), np.int64) for cam in self.recording.cameras}

    def add(self, episode: Episode) -> int:
        """Append an episode; returns its episode_index."""
        index = len(self.episodes)
        length = episode.length
        task_index = np.full(length, self.tasks.setdefault(episode.task, len(self.tasks)), np.int64)
        tasks = [episode.task]
        if episode.switch is not None:  # each frame holds the instruction it was shown
            step, then = episode.switch
            task_index[step:] = self.tasks.setdefault(then, len(self.tasks))
            tasks.append(then)
        columns = {
            "observation.state": episode.states.astype(np.float32),
            "action": episode.actions.astype(np.float32),
            "timestamp": (np.arange(length) / self.recording.fps).astype(np.float32),
            "frame_index": np.arange(length, dtype=np.int64),
            "episode_index": np.full(length, index, np.int64),
            "index": np.arange(self.frames, self.frames + length, dtype=np.int64),
            "task_index": task_index,
        }
        row: dict = {"episode_index": index, "tasks": tasks, "length": length}
        row.update(self._write_data(columns))
        for cam in self.recording.cameras:
            row.update(self._write_video(cam, episode.videos[cam]))
        row["dataset_from_index"] = self.frames
        row["dataset_to_index"] = self.frames + length
        row["meta/episodes/chunk_index"] = 0
        row["meta/episodes/file_index"] = 0
        episode_stats = {k: st.vector_stats(v) for k, v in columns.items()}
        for cam in self.recording.cameras:
            episode_stats[self.recording.video_key(cam)] = st.image_stats(episode.histograms[cam], length)
            self._histograms[cam] += episode.histograms[cam]
        for key, s in episode_stats.items():
            for name, value in s.items():
                row[f"stats/{key}/{name}"] = np.asarray(value).tolist()
        for key, value in columns.items():
            self._vectors.setdefault(key, []).append(value)
        self.episodes.append(row)
        self.frames += length
        return index

    def _write_data(self, columns: dict[str, np.ndarray]) -> dict:
        table = pa.Table.from_pydict(
            {
                k: (pa.FixedSizeListArray.from_arrays(pa.array(v.reshape(-1)), v.shape[1]) if v.ndim == 2 else v)
                for k, v in columns.items()
            },
            schema=self.recording.arrow_schema(),
        )
        if self._data is not None and self._data_path is not None:
            if self._data_path.stat().st_size / 1e6 >= self.data_files_size_in_mb:
                self._data.close()
                self._data = None
                self._data_at.next()
        if self._data is None:
            at = self._data_at
            self._data_path = self.root / DATA_PATH.format(chunk_index=at.chunk, file_index=at.file)
            self._data_path.parent.mkdir(parents=True, exist_ok=True)
            self._data = pq.ParquetWriter(self._data_path, table.schema, compression="snappy")
        self._data.write_table(table)
        return {"data/chunk_index": self._data_at.chunk, "data/file_index": self._data_at.file}

    def _write_video(self, camera: str, mp4: bytes) -> dict:
        at = self._video_at[camera]
        current = self._video.get(camera)
        if current is not None and current.size_mb() >= self.video_files_size_in_mb:
            current.close()
            current = None
            at.next()
        if current is None:
            path = self.root / VIDEO_PATH.format(
                video_key=self.recording.video_key(camera), chunk_index=at.chunk, file_index=at.file
            )
            current = self._video[camera] = VideoFile(path, self.recording.fps)
        start, end = current.append(mp4)
        key = self.recording.video_key(camera)
        return {
            f"videos/{key}/chunk_index": at.chunk,
            f"videos/{key}/file_index": at.file,
            f"videos/{key}/from_timestamp": start,
            f"videos/{key}/to_timestamp": end,
        }

    def finalize(self) -> dict:
        """Close the files and write meta/: episodes, tasks, stats, info. Returns info."""
        if self._data is not None:
            self._data.close()
        for video in self._video.values():
            video.close()
        meta = self.root / "meta"
        (meta / "episodes/chunk-000").mkdir(parents=True, exist_ok=True)
        pq.write_table(pa.Table.from_pylist(self.episodes), self.root / EPISODES_PATH)
        tasks = pd.DataFrame({"task_index": list(self.tasks.values())}, index=pd.Index(list(self.tasks), name="task"))
        pq.write_table(pa.Table.from_pandas(tasks), meta / "tasks.parquet")
        dataset_stats = {k: st.vector_stats(np.concatenate(v)) for k, v in self._vectors.items()}
        for cam in self.recording.cameras:
            dataset_stats[self.recording.video_key(cam)] = st.image_stats(self._histograms[cam], self.frames)
        (meta / "stats.json").write_text(json.dumps(st.to_json(dataset_stats), indent=2))
        info = {
            "codebase_version": CODEBASE_VERSION,
            "robot_type": self.robot_type,
            "total_episodes": len(self.episodes),
            "total_frames": self.frames,
            "total_tasks": len(self.tasks),
            "chunks_size": self.chunks_size,
            "data_files_size_in_mb": self.data_files_size_in_mb,
            "video_files_size_in_mb": self.video_files_size_in_mb,
            "fps": self.recording.fps,
            "splits": {"train": f"0:{len(self.episodes)}"},
            "data_path": DATA_PATH,
            "video_path": VIDEO_PATH,
            "features": self.recording.features(),
        }
        (meta / "info.json").write_text(json.dumps(info, indent=4))
        return info
