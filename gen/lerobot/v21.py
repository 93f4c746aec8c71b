"""LeRobot v2.1 (openpi's trainer, lerobot before 0.4): one parquet file and one mp4 per camera for
each episode (`data/chunk-000/episode_000000.parquet`, `videos/chunk-000/<camera key>/episode_000000.mp4`)
and its metadata as JSON lines (`meta/episodes.jsonl`, `meta/tasks.jsonl`, `meta/episodes_stats.jsonl`)
beside `meta/info.json`. Written from one of our v3.0 datasets: the rows copied as they are, each
episode's video packets cut out of the v3.0 file without re-encoding (the frames decode
identically), the per-episode stats v3.0's own."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq
from tqdm import tqdm

from core.products import INFO_PATH
from core.products import V21_DATA_PATH as DATA_PATH
from core.products import V21_VIDEO_PATH as VIDEO_PATH
from gen.lerobot.reader import LeRobotReader
from gen.lerobot.video import cut
from jobs.cli import Failed

CHUNKS_SIZE = 1000  # episodes per chunk folder, as lerobot v2.1 writes them
V21_STATS = ("min", "max", "mean", "std", "count")  # v3.0 adds quantiles, which v2.1 readers do not expect


def _stats(row: dict, features: list[str]) -> dict:
    """An episode's v2.1 stats from its v3.0 episodes-table row (nested lists, as jsonl holds them)."""
    out = {}
    for key in features:
        out[key] = {s: np.stack(_nested(row[f"stats/{key}/{s}"])).tolist() for s in V21_STATS if f"stats/{key}/{s}" in row}
    return out


def _nested(value: object) -> object:
    """A parquet cell of arrays of arrays -> one numpy array."""
    if isinstance(value, np.ndarray) and value.dtype == object:
        return np.stack([_nested(v) for v in value])
    return np.asarray(value)


def export_v21(source: Path, staging: Path) -> dict:
    """Write the v2.1 dataset of `source` into `staging`; returns its info.json."""
    reader = LeRobotReader(source)
    info, episodes = reader.info, reader.episodes
    table = pq.read_table(source / "data").sort_by("index")
    meta = staging / "meta"
    meta.mkdir(parents=True)
    stats_features = [k for k in info["features"] if f"stats/{k}/mean" in episodes.columns]
    with (meta / "episodes.jsonl").open("w") as eps, (meta / "episodes_stats.jsonl").open("w") as stats:
        for row in tqdm(episodes.to_dict("records"), desc="export v2.1", unit="episode"):
            ep, chunk = int(row["episode_index"]), int(row["episode_index"]) // CHUNKS_SIZE
            frames = table.slice(int(row["dataset_from_index"]), int(row["length"]))  # the table is in index order
            if pc.any(pc.not_equal(frames["episode_index"], ep)).as_py() or len(frames) != int(row["length"]):
                raise Failed(f"{source}: rows {row['dataset_from_index']}.. are not all of episode {ep}'s {row['length']}")
            path = staging / DATA_PATH.format(episode_chunk=chunk, episode_index=ep)
            path.parent.mkdir(parents=True, exist_ok=True)
            pq.write_table(frames.replace_schema_metadata(None), path)
            for camera, key in zip(reader.cameras, reader.video_keys):
                span = reader.span(ep, camera, row)
                target = staging / VIDEO_PATH.format(episode_chunk=chunk, video_key=key, episode_index=ep)
                if cut(span.path, span.first, span.length, reader.fps, target) != span.length:
                    raise Failed(f"{span.path}: episode {ep} does not hold {span.length} frames from frame {span.first}")
            eps.write(json.dumps({"episode_index": ep, "tasks": list(row["tasks"]), "length": int(row["length"])}) + "\n")
            stats.write(json.dumps({"episode_index": ep, "stats": _stats(row, stats_features)}) + "\n")
    with (meta / "tasks.jsonl").open("w") as tasks:
        for task, index in reader.tasks["task_index"].sort_values().items():
            tasks.write(json.dumps({"task_index": int(index), "task": task}) + "\n")
    for extra in ("scenes.parquet", "generation.json", "audit.json"):  # our own records travel along
        if (source / "meta" / extra).is_file():
            shutil.copy2(source / "meta" / extra, meta / extra)
    n = len(episodes)
    v21 = {
        "codebase_version": "v2.1",
        "robot_type": info.get("robot_type"),
        "total_episodes": n,
        "total_frames": info["total_frames"],
        "total_tasks": info["total_tasks"],
        "total_videos": n * len(reader.video_keys),
        "total_chunks": (n + CHUNKS_SIZE - 1) // CHUNKS_SIZE,
        "chunks_size": CHUNKS_SIZE,
        "fps": info["fps"],
        "splits": info["splits"],
        "data_path": DATA_PATH,
        "video_path": VIDEO_PATH,
        "features": info["features"],
    }
    (staging / INFO_PATH).write_text(json.dumps(v21, indent=4))
    return v21
