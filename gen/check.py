"""`python -m gen.check <dataset>`: is this dataset whole and self-consistent?

Checks, in order, and stops at the first problem (exit code 1, one line naming it):
completion marker and format; episode counts across info.json, the episodes table and the scene
records; frame index continuity and each episode's frame range; timestamps; every frame of every
video file decoded (a file that stops decoding is named with the frame, and the episode it
belongs to) at the recorded frame size, and each episode's span inside it; stats recomputed from
the data; scene records against tasks. An exam or a plan (`plan_only=true`) is not a dataset: it is refused with one
line saying what it is and what checks it.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import av
import numpy as np

from core.products import INFO_PATH
from core.profiles import ACTION_KEY, STATE_KEY
from gen.lerobot.reader import LeRobotReader
from gen.lerobot.stats import vector_stats
from gen.products import scenes
from jobs.cli import Failed, UserError, main
from jobs.output import product_in


class Broken(Exception):
    """The first problem found; the message names it."""


def _require(condition: bool, problem: str) -> None:
    if not condition:
        raise Broken(problem)


def check(root: Path) -> dict:
    """Raises Broken with the first problem; returns info.json when all is well."""
    _require((root / INFO_PATH).is_file(), f"{root}: no {INFO_PATH}")
    generation = root / "meta/generation.json"
    _require(generation.is_file(), f"{root}: no meta/generation.json: not a complete generated dataset")
    _require(
        json.loads(generation.read_text()).get("complete") is True, f"{root}: meta/generation.json does not mark it complete"
    )
    dataset = LeRobotReader(root)
    info = dataset.info
    _require(info.get("codebase_version") == "v3.0", f"codebase_version is {info.get('codebase_version')!r}, not v3.0")
    episodes = dataset.episodes
    records = scenes.read(root)
    n = info["total_episodes"]
    _require(len(episodes) == n, f"info.json says {n} episodes, meta/episodes has {len(episodes)}")
    _require(list(episodes["episode_index"]) == list(range(n)), "meta/episodes: episode_index is not 0..n-1")
    _require(len(records) == n, f"info.json says {n} episodes, meta/scenes.parquet has {len(records)}")
    data = dataset.data
    total = info["total_frames"]
    _require(len(data) == total, f"info.json says {total} frames, data has {len(data)}")
    _require(np.array_equal(data["index"].to_numpy(), np.arange(total)), "data: index is not continuous 0..total_frames-1")
    fps = info["fps"]
    for ep in episodes.itertuples():
        rows = data[data.episode_index == ep.episode_index]
        start, end = ep.dataset_from_index, ep.dataset_to_index
        _require(len(rows) == ep.length == end - start, f"episode {ep.episode_index}: {len(rows)} frames, expected {ep.length}")
        _require(
            np.array_equal(rows["index"].to_numpy(), np.arange(start, end)), f"episode {ep.episode_index}: frames out of range"
        )
        _require(
            np.array_equal(rows["frame_index"].to_numpy(), np.arange(ep.length)), f"episode {ep.episode_index}: frame_index gaps"
        )
        _require(
            np.allclose(rows["timestamp"].to_numpy(), np.arange(ep.length) / fps, atol=1e-4),
            f"episode {ep.episode_index}: timestamps are not frame_index / fps",
        )
    for key, camera in zip(dataset.video_keys, dataset.cameras):
        files: dict[Path, dict[int, tuple[int, int]]] = {}  # file -> its frame -> (episode, the episode's frame)
        for s in dataset.spans(camera):
            span = (s.to_timestamp - s.from_timestamp) * fps
            _require(abs(span - s.length) < 1e-3, f"{key}: episode {s.episode} spans {span:.1f} frames, not {s.length}")
            files.setdefault(s.path, {}).update({s.first + k: (s.episode, k) for k in range(s.length)})
        for path, owners in files.items():
            _require(path.is_file(), f"{key}: missing video {path.relative_to(root)}")
            count = _decoded(path, tuple(info["features"][key]["shape"][:2]), owners, f"{key}: {path.relative_to(root)}")
            needed = max(owners) + 1
            _require(count >= needed, f"{key}: {path.relative_to(root)} has {count} frames, episodes need {needed}")
    stats = dataset.stats
    for key in (STATE_KEY, ACTION_KEY):
        values = np.stack(data[key].to_numpy())
        fresh = vector_stats(values)
        for name in ("mean", "std", "min", "max"):
            _require(
                np.allclose(stats[key][name], fresh[name], rtol=1e-5, atol=1e-6),
                f"stats.json: {key} {name} does not match the data",
            )
    for key in dataset.video_keys:
        _require(min(np.ravel(stats[key]["std"])) > 0, f"stats.json: {key} std is 0")
    tasks = dataset.tasks
    by_index = {int(i): t for t, i in zip(tasks.index, tasks["task_index"])}
    first = data.groupby("episode_index")["task_index"].first()
    for rec in records.itertuples():
        _require(
            by_index.get(int(first[rec.episode_index])) == rec.instruction,
            f"episode {rec.episode_index}: its task is not the instruction in meta/scenes.parquet",
        )
    return info


def _decoded(path: Path, shape: tuple[int, int], owners: dict[int, tuple[int, int]], name: str) -> int:
    """Decode every frame of a video file (as a loader would, which stops at the first frame it
    cannot decode); returns how many there are, or raises Broken naming the frame that fails."""
    n = 0
    try:
        with av.open(str(path)) as container:
            for frame in container.decode(container.streams.video[0]):
                _require((frame.height, frame.width) == shape, f"{name}: frame {n} is {frame.height}x{frame.width}, not {shape}")
                n += 1
    except (av.error.FFmpegError, OSError) as exc:
        episode, k = owners.get(n, (None, None))
        where = f" (episode {episode}'s frame {k})" if episode is not None else ""
        raise Broken(f"{name}: frame {n}{where} cannot be decoded ({exc})") from None
    return n


@dataclass
class CheckOptions:
    dataset: str = ""  # the dataset folder to check


def run(options: CheckOptions) -> None:
    root = Path(options.dataset)
    if not root.is_dir():
        raise UserError(f"{root} is not a folder" if root.exists() else f"{root} does not exist")
    product = product_in(root)
    if product == "exam":
        raise UserError(
            f"{root} is an exam, not a dataset: gen.check checks datasets; an exam's files (format, version, columns, rows) "
            "are checked by whatever reads it: python -m eval, python -m eval.score, python -m gen.push"
        )
    if product == "plan":
        raise UserError(f"{root} is a plan (plan_only=true): scene records and an audit, no episodes for gen.check to check")
    try:
        info = check(root)
    except Broken as exc:
        raise Failed(str(exc)) from None
    except (OSError, KeyError, ValueError) as exc:
        raise Failed(f"{root}: unreadable ({type(exc).__name__}: {exc})") from None
    print(f"ok: {root}: {info['total_episodes']} episodes, {info['total_frames']} frames, all checks passed")


if __name__ == "__main__":
    sys.exit(main("python -m gen.check", CheckOptions, run, doc=__doc__, positional="dataset"))
