"""A generated LeRobot dataset in memory, for training on a CPU.

Videos are decoded once (PyAV, sequentially) into uint8 arrays and cached on disk, keyed by the
dataset's content; decoding frame by frame through the loader would dominate every step.
Everything a training run relies on is checked first, so a bad dataset fails in one line
before any step is taken.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core import cache_dir, parquet
from core.layout import ACTION_KEY, NATIVE, STATE_KEY
from gen.lerobot_reader import INFO_PATH, TASKS_PATH, LeRobotReader
from gen.lerobot_writer import EPISODES_PATH
from gen.partial import GENERATION_PATH
from gen.scenes import SCENES_PATH

CAMERAS = NATIVE.camera_names
STATE_DIM, ACTION_DIM = NATIVE.state_size, NATIVE.action_size


class DatasetError(ValueError):
    """The dataset cannot be trained on; the message says why."""


@dataclass
class Frames:
    """All frames of a dataset: images per camera (N, H, W, 3) uint8, state (N, 16), action
    (N, 8), episode index, frame index, task index per frame; tasks; episode bounds."""

    images: dict[str, np.ndarray]
    state: np.ndarray
    action: np.ndarray
    episode: np.ndarray
    task: np.ndarray
    tasks: list[str]
    starts: np.ndarray  # first frame of each episode
    ends: np.ndarray  # one past the last frame of each episode
    stats: dict[str, dict[str, np.ndarray]]
    target: np.ndarray | None  # (episodes, 3) where each episode's target starts, from meta/scenes.parquet

    @property
    def image_size(self) -> int:
        return self.images[CAMERAS[0]].shape[1]

    def __len__(self) -> int:
        return len(self.action)


def check(root: Path, image_size: int | None = None) -> dict:
    """Validate a dataset for training; returns its info.json."""
    info_path = root / INFO_PATH
    if not info_path.is_file():
        raise DatasetError(f"{root} is not a LeRobot dataset (no {INFO_PATH})")
    try:
        info = json.loads(info_path.read_text())
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{info_path} is corrupt: {exc}") from None
    generation = root / GENERATION_PATH
    if (root / SCENES_PATH).is_file() and (
        not generation.is_file() or json.loads(generation.read_text()).get("complete") is not True
    ):
        raise DatasetError(f"{root} is an incomplete generated dataset (no completion marker); resume its generation first")
    if info.get("codebase_version") != "v3.0":
        raise DatasetError(f"{root}: codebase_version {info.get('codebase_version')!r}; training reads v3.0 datasets")
    features = info.get("features", {})
    needed = {NATIVE.image_key(c): None for c in CAMERAS} | {STATE_KEY: STATE_DIM, ACTION_KEY: ACTION_DIM}
    for key, dim in needed.items():
        if key not in features:
            raise DatasetError(f"{root}: missing feature {key!r}; the tiny policy needs {', '.join(needed)}")
        if dim is not None and list(features[key]["shape"]) != [dim]:
            raise DatasetError(f"{root}: feature {key!r} has shape {features[key]['shape']}, expected [{dim}]")
    sizes = {tuple(features[NATIVE.image_key(c)]["shape"]) for c in CAMERAS}
    if len(sizes) != 1:
        raise DatasetError(f"{root}: cameras have different image sizes {sorted(sizes)}")
    height, width, _ = sizes.pop()
    if height != width:
        raise DatasetError(f"{root}: frames are {height}x{width}; the tiny policy takes square frames")
    if image_size is not None and image_size != height:
        raise DatasetError(
            f"{root}: frames are {height} px but image_size={image_size}; "
            f"train with image_size={height} or regenerate the dataset with image_size={image_size}"
        )
    tasks = parquet.read(root / TASKS_PATH)
    if len(tasks) < 2:
        raise DatasetError(
            f"{root}: no instruction diversity: every episode has the same instruction, so nothing could teach "
            "the policy to read it"
        )
    return info


def _key(root: Path) -> str:
    digest = hashlib.sha256()
    for rel in (INFO_PATH, EPISODES_PATH):
        digest.update((root / rel).read_bytes())
    return digest.hexdigest()[:20]


def load(root: Path | str, image_size: int | None = None) -> Frames:
    root = Path(root)
    check(root, image_size)
    dataset = LeRobotReader(root)
    data, episodes = dataset.data, dataset.episodes
    tasks = dataset.tasks.sort_values("task_index")
    stats = {k: {s: np.asarray(v) for s, v in d.items()} for k, d in dataset.stats.items()}
    cache = cache_dir() / f"{_key(root)}.npz"
    if cache.is_file():
        with np.load(cache) as npz:
            images = {c: npz[c] for c in CAMERAS}
    else:
        images = {c: dataset.camera_frames(c) for c in CAMERAS}
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(".tmp.npz")
        np.savez(tmp, **images)
        tmp.replace(cache)
    return Frames(
        images=images,
        state=np.stack(data[STATE_KEY].to_numpy()).astype(np.float32),
        action=np.stack(data[ACTION_KEY].to_numpy()).astype(np.float32),
        episode=data["episode_index"].to_numpy(np.int64),
        task=data["task_index"].to_numpy(np.int64),
        tasks=list(tasks.index),
        starts=episodes["dataset_from_index"].to_numpy(np.int64),
        ends=episodes["dataset_to_index"].to_numpy(np.int64),
        stats=stats,
        target=_targets(root),
    )


def _targets(root: Path) -> np.ndarray | None:
    """Start position of each episode's target object (None for datasets without scene records)."""
    path = root / SCENES_PATH
    if not path.is_file():
        return None
    records = parquet.read(path).sort_values("episode_index")
    out = []
    for scene, target in zip(records["scene"], records["target"]):
        objects = {o["id"]: o["pos"] for o in json.loads(scene)["objects"]}
        out.append(objects[target])
    return np.asarray(out, np.float32)


def chunk_indices(frames: Frames, index: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
    """For frames `index`, the indices of their next `horizon` actions (clamped to the episode's
    last frame) and a mask of which are real."""
    ends = frames.ends[frames.episode[index]]
    steps = index[:, None] + np.arange(horizon)[None, :]
    mask = steps < ends[:, None]
    return np.minimum(steps, ends[:, None] - 1), mask
