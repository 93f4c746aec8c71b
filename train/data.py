"""Generated LeRobot datasets in memory, for training on a CPU: one, or the union of several
(what lerobot users know as a multi-dataset).

Videos are decoded once (PyAV, sequentially) into uint8 arrays cached on disk, keyed by the
dataset's content, and read back memory-mapped (a 1,400-episode set at 128 px is 18 GB of frames:
two such runs side by side share the page cache instead of each holding its own copy; a union's
sets stay mapped, joined without a copy); decoding
frame by frame through the loader would dominate every step.
Everything a training run relies on is checked first, so a bad dataset, or datasets that
disagree on their features, rate or frame size, fail in one line before any step is taken.
The union's normalisation statistics are computed over all its frames (exactly, from each
dataset's own), and each frame remembers its dataset and its episode's referent type, so batches
can be balanced across both (the types of one mixed dataset, gen/planning/mix.py, too).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core import cache_dir, parquet
from core.products import EPISODES_PATH, GENERATION_PATH, INFO_PATH, SCENES_PATH, TASKS_PATH
from core.profiles import ACTION_KEY, PROFILES, STATE_KEY, Profile
from core.worlds import MAX_IMAGE_SIZE
from gen.lerobot.reader import LeRobotReader

REACH_BIN = 0.02  # m: how finely `reach_alike` matches the hand's distance from its target at the switches


class DatasetError(ValueError):
    """The dataset cannot be trained on; the message says why."""


class Joined:
    """Several datasets' frames of one camera read as one (N, H, W, 3) array without copying them:
    each part stays memory-mapped, and indexing gathers the frames asked for. A union of sets that
    fill the page cache would otherwise be one more copy in memory (three LIBERO-Object sets at
    128 px: 15 GB)."""

    def __init__(self, parts: list[np.ndarray]) -> None:
        self.parts = parts
        self.offsets = np.cumsum([0] + [len(p) for p in parts])
        self.shape = (int(self.offsets[-1]), *parts[0].shape[1:])
        self.dtype = parts[0].dtype

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, index: int | np.ndarray) -> np.ndarray:
        """One frame (an integer), or the frames at an array of indices, in its order."""
        wanted = np.asarray(index, np.int64)
        if np.any((wanted < -self.shape[0]) | (wanted >= self.shape[0])):
            raise IndexError(f"frame index out of range for {self.shape[0]} frames")
        wanted = np.where(wanted < 0, wanted + self.shape[0], wanted)  # from the end, as an array's index is
        part = np.searchsorted(self.offsets, wanted, side="right") - 1
        if wanted.ndim == 0:
            return self.parts[int(part)][int(wanted - self.offsets[part])]
        out = np.empty((len(wanted), *self.shape[1:]), self.dtype)
        for p in np.unique(part):
            taken = part == p
            out[taken] = self.parts[p][wanted[taken] - self.offsets[p]]
        return out


@dataclass
class Frames:
    """All frames of a dataset: images per camera (N, H, W, 3) uint8, state (N, state size), action
    (N, action size), episode index, frame index, task index per frame; tasks; episode bounds;
    the profile they were recorded in."""

    images: dict[str, np.ndarray | Joined]  # memory-mapped: one set's cache, or several sets' joined
    state: np.ndarray
    action: np.ndarray
    episode: np.ndarray
    task: np.ndarray
    tasks: list[str]
    starts: np.ndarray  # first frame of each episode
    ends: np.ndarray  # one past the last frame of each episode
    stats: dict[str, dict[str, np.ndarray]]
    target: np.ndarray | None  # (aims, 3) where each target starts, from meta/scenes.parquet: one per episode, one more
    target_world: np.ndarray | None  # (aims,) per switched episode (its second); the world of each target's scene
    aim: np.ndarray | None  # (N,) each frame's row of `target`: what its instruction names at that frame
    referent: np.ndarray | None  # (episodes,) each episode's referent type (a mix's differ), from meta/scenes.parquet
    source: np.ndarray  # the dataset each frame comes from (index into `sources`)
    sources: list[str]
    profile: str
    world: str  # the world of the (first) dataset's scenes (core/worlds/)

    @property
    def image_size(self) -> int:
        return next(iter(self.images.values())).shape[1]

    def __len__(self) -> int:
        return len(self.action)


def profile_of(features: dict, root: Path) -> Profile:
    """The profile (core/profiles.py) a dataset's features are: its cameras, state and action."""
    missing = {p.name: [k for k in (*p.image_keys, STATE_KEY, ACTION_KEY) if k not in features] for p in PROFILES.values()}
    for candidate in PROFILES.values():
        if not missing[candidate.name]:
            return candidate
    said = "; ".join(f"{name} misses {', '.join(repr(k) for k in keys)}" for name, keys in missing.items())
    raise DatasetError(f"{root}: its features fit no profile the tiny policy reads ({said})")


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
    profile = profile_of(features, root)
    needed = {key: None for key in profile.image_keys} | {STATE_KEY: profile.state_size, ACTION_KEY: profile.action_size}
    for key, dim in needed.items():
        if dim is not None and list(features[key]["shape"]) != [dim]:
            raise DatasetError(f"{root}: feature {key!r} has shape {features[key]['shape']}, expected [{dim}] ({profile.name})")
    sizes = {tuple(features[key]["shape"]) for key in profile.image_keys}
    if len(sizes) != 1:
        raise DatasetError(f"{root}: cameras have different image sizes {sorted(sizes)}")
    height, width, _ = sizes.pop()
    if height != width:
        raise DatasetError(f"{root}: frames are {height}x{width}; the tiny policy takes square frames")
    if image_size is not None and image_size != height:
        makeable = 16 <= image_size <= MAX_IMAGE_SIZE and image_size % 2 == 0
        advice = (
            f"or regenerate the dataset with image_size={image_size}"
            if makeable
            else f"({image_size} px is not a size python -m gen makes: an even number in [16, {MAX_IMAGE_SIZE}])"
        )
        raise DatasetError(f"{root}: frames are {height} px but image_size={image_size}; train with image_size={height} {advice}")
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


def roots(dataset: str | list[str] | tuple[str, ...]) -> list[Path]:
    """`dataset=` as folders: one folder, or a list of them."""
    folders = [dataset] if isinstance(dataset, (str, Path)) else list(dataset)
    if not folders or not all(isinstance(f, (str, Path)) and str(f) for f in folders):
        raise DatasetError(f"dataset must be a folder or a list of folders, got {dataset!r}")
    if len(set(map(str, folders))) != len(folders):
        raise DatasetError(f"dataset lists a folder twice: {folders}")
    return [Path(f) for f in folders]


def check_all(folders: list[Path], image_size: int | None = None) -> None:
    """Each dataset trainable, and all of them alike in what one policy reads: features (names
    and shapes), rate and frame size. The first disagreement is named in one line."""
    infos = [check(root, image_size) for root in folders]
    first = infos[0]
    for root, info in zip(folders[1:], infos[1:]):
        if info.get("fps") != first.get("fps"):
            raise DatasetError(
                f"{root} has fps {info.get('fps')}, {folders[0]} has {first.get('fps')}: one policy trains at one rate"
            )
        ours, base = info.get("features", {}), first.get("features", {})
        for key in sorted(set(ours) | set(base)):
            if key not in ours or key not in base:
                has, lacks = (folders[0], root) if key in base else (root, folders[0])
                raise DatasetError(f"{has} has feature {key!r} and {lacks} does not: the datasets must share their features")
            if list(ours[key].get("shape", [])) != list(base[key].get("shape", [])):
                what = "frame size" if ours[key].get("dtype") == "video" else "shape"
                raise DatasetError(
                    f"{root} feature {key!r} has {what} {ours[key]['shape']}, {folders[0]} has {base[key]['shape']}"
                )
            if ours[key].get("names") != base[key].get("names"):
                raise DatasetError(
                    f"{root} feature {key!r} names {ours[key].get('names')}, {folders[0]} {base[key].get('names')}"
                )


def load(dataset: str | Path | list[str], image_size: int | None = None) -> Frames:
    """One dataset's frames, or the union of several (checked alike first)."""
    folders = roots(str(dataset) if isinstance(dataset, Path) else dataset)
    check_all(folders, image_size)
    if len(folders) == 1:
        return _load(folders[0])
    return union([_load(root) for root in folders])


def union(parts: list[Frames]) -> Frames:
    """Several datasets as one: frames, episodes and tasks renumbered, statistics over all frames."""
    tasks = list(dict.fromkeys(t for part in parts for t in part.tasks))
    remap = [np.array([tasks.index(t) for t in part.tasks], np.int64) for part in parts]
    frame_offsets = np.cumsum([0] + [len(p) for p in parts])
    episode_offsets = np.cumsum([0] + [len(p.starts) for p in parts])
    targets = [p.target for p in parts]
    scene_worlds = [p.target_world for p in parts]
    aim_offsets = np.cumsum([0] + [0 if p.target is None else len(p.target) for p in parts])
    referents = [p.referent for p in parts]
    images = {c: Joined([p.images[c] for p in parts]) for c in parts[0].images}  # still memory-mapped, not copied
    return Frames(
        images=images,
        state=np.concatenate([p.state for p in parts]),
        action=np.concatenate([p.action for p in parts]),
        episode=np.concatenate([p.episode + off for p, off in zip(parts, episode_offsets)]),
        task=np.concatenate([m[p.task] for p, m in zip(parts, remap)]),
        tasks=tasks,
        starts=np.concatenate([p.starts + off for p, off in zip(parts, frame_offsets)]),
        ends=np.concatenate([p.ends + off for p, off in zip(parts, frame_offsets)]),
        stats=_pooled({STATE_KEY: [p.state for p in parts], ACTION_KEY: [p.action for p in parts]}),
        target=None if any(t is None for t in targets) else np.concatenate(targets),
        target_world=None if any(w is None for w in scene_worlds) else np.concatenate(scene_worlds),
        aim=None if any(t is None for t in targets) else np.concatenate([p.aim + off for p, off in zip(parts, aim_offsets)]),
        referent=None if any(r is None for r in referents) else np.concatenate(referents),
        source=np.concatenate([np.full(len(p), i, np.int64) for i, p in enumerate(parts)]),
        sources=[s for p in parts for s in p.sources],
        profile=parts[0].profile,
        world=parts[0].world,
    )


def _pooled(vectors: dict[str, list[np.ndarray]]) -> dict[str, dict[str, np.ndarray]]:
    """Mean, std, min and max over the frames of all the datasets together."""
    out = {}
    for key, parts in vectors.items():
        every = np.concatenate(parts).astype(np.float64)
        out[key] = {"mean": every.mean(0), "std": every.std(0), "min": every.min(0), "max": every.max(0)}
    return out


def groups(frames: Frames) -> np.ndarray:
    """Each frame's balance group: its dataset and, where episodes record it, its referent type
    (numbered in order of first appearance)."""
    if frames.referent is None:
        return frames.source
    _, kind = np.unique(frames.referent, return_inverse=True)
    pair = frames.source * (kind.max() + 1) + kind[frames.episode]
    _, first, inverse = np.unique(pair, return_index=True, return_inverse=True)
    return np.argsort(np.argsort(first))[inverse]


def favoured(frames: Frames, group: np.ndarray, types: list[str], share: float) -> np.ndarray:
    """Each balance group's chance of being drawn when the groups of the referent `types` together
    take `share` of every batch, split equally among them, and the other groups the rest, equally:
    more of a type that lags, the mix's others still in every batch."""
    if frames.referent is None:
        raise DatasetError(f"favour={types} needs a mix whose episodes record their referent type (meta/scenes.parquet)")
    kind = frames.referent[frames.episode[np.unique(group, return_index=True)[1]]]
    missing = sorted(set(types) - set(kind))
    if missing or set(types) == set(kind):
        held = ", ".join(sorted(set(kind)))
        raise DatasetError(f"favour={types} must name some, not all, of the referent types the data holds ({held})")
    chosen = np.isin(kind, types)
    return np.where(chosen, share / chosen.sum(), (1 - share) / (~chosen).sum())


def first_aims(frames: Frames) -> np.ndarray:
    """(N,) the row of `target` each frame's episode names first: a switch comes after an episode's
    first frame, and in a union of datasets these rows are not the episodes' numbers."""
    assert frames.aim is not None, "aims need the datasets' scene records"
    return frames.aim[frames.starts[frames.episode]]


def after_switches(frames: Frames) -> np.ndarray:
    """(N,) whether each frame comes after its episode's switch (its instruction names the second target)."""
    return frames.aim != first_aims(frames) if frames.aim is not None else np.zeros(len(frames), bool)


def switch_frames(frames: Frames) -> np.ndarray:
    """(episodes,) each episode's first frame after its switch; len(frames) for an episode that never switches."""
    later = after_switches(frames)
    switched_at = np.full(len(frames.starts), len(frames))
    np.minimum.at(switched_at, frames.episode[later], np.flatnonzero(later))
    return switched_at


def until_grasp(frames: Frames) -> np.ndarray:
    """Per frame, whether it comes before its episode's first closed-gripper action: while the
    target still stands where the episode's scene put it."""
    closing = frames.action[:, -1] > 0
    first = np.array([s + (np.argmax(closing[s:e]) if closing[s:e].any() else e - s) for s, e in zip(frames.starts, frames.ends)])
    return np.arange(len(frames)) < first[frames.episode]


def after_switch(
    frames: Frames,
    group: np.ndarray | None,
    chances: np.ndarray | None,
    share: float,
    first: int = 0,
    before: int = 0,
    stay: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """The balance groups (`groups`, or all frames one) with the switched episodes' frames from their
    switch on (`first`: only the first this many, where the hand turns) split off into a group of
    their own that takes `share` of every batch, the groups' chances (equal, or `favoured`) scaled
    to the rest: as they fall, those frames are too few (45 switched episodes of 300, their second
    halves) to outweigh the path under way, and the turn is a few frames of each. With `before`, the
    last this many frames before each switch (the same states under the first name, the hand still
    coming down) are a group of their own and the two halve `share`: weighed alone, the turn is
    learnt as what the hand does at a grocery, whichever one is named (docs/RESULTS_FACES.md). With
    `stay`, that other half is the unswitched episodes' frames before their grasp at the switches'
    reach (`reach_alike`): the states of the switches themselves under a name that stays, where the
    frames before a switch are higher up the descent than the switch."""
    later = after_switches(frames)
    if not later.any():
        raise DatasetError(f"switched_share={share} needs switched episodes (python -m gen ... switched=<share>)")
    switched_at = switch_frames(frames)[frames.episode]  # len(frames) in an episode that never switches
    since = np.arange(len(frames)) - switched_at  # negative before the episode's switch
    if first:
        later &= since < first
    base = np.zeros(len(frames), np.int64) if group is None else group
    n = int(base.max()) + 1
    prior = np.full(n, 1 / n) if chances is None else chances
    if stay:
        alike, weights = reach_alike(frames)
        return np.select([later, alike >= 0], [n, n + 1 + alike], base), np.concatenate(
            [prior * (1 - share), [share / 2], weights * share / 2]
        )
    if not before:
        return np.where(later, n, base), np.append(prior * (1 - share), share)
    leading = (switched_at < len(frames)) & (since < 0) & (since >= -before)
    return np.select([later, leading], [n, n + 1], base), np.append(prior * (1 - share), [share / 2, share / 2])


def reach_alike(frames: Frames, width: float = REACH_BIN) -> tuple[np.ndarray, np.ndarray]:
    """The unswitched episodes' frames before their grasp, binned by how far the hand is from their
    target (`width` m bins; -1: not such a frame), and each bin's weight: the share of the switches
    whose hand is that far from the first target, over the bins such frames reach (a switch
    nearer or farther than any is counted in the nearest that is)."""
    switched_at = switch_frames(frames)
    own = frames.target[first_aims(frames)]  # the first target, where each episode's scene put it
    reach = np.linalg.norm(frames.state[:, PROFILES[frames.profile].hand] - own, axis=1)
    bins = (reach // width).astype(np.int64)
    stays = until_grasp(frames) & (switched_at[frames.episode] == len(frames))
    held = np.unique(bins[stays])
    switches = bins[switched_at[switched_at < len(frames)]]
    nearest = np.abs(held[None] - switches[:, None]).argmin(1)
    weights = np.bincount(nearest, minlength=len(held)) / len(switches)
    return np.where(stays, np.searchsorted(held, bins), -1), weights


def sample(
    frames: Frames,
    rng: np.random.Generator,
    n: int,
    balance: bool,
    group: np.ndarray | None = None,
    chances: np.ndarray | None = None,
) -> np.ndarray:
    """`n` frame indices: uniform over all frames, or (`balance`) each from a group (`groups`: a
    dataset, a referent type of a mix) drawn uniformly, so a small one weighs as much as a large one,
    or with the groups' `chances` (`favoured`)."""
    group = groups(frames) if group is None and balance else group
    if not balance or group is None or group.max() == 0:
        return rng.integers(0, len(frames), n)
    members = np.argsort(group, kind="stable")
    counts = np.bincount(group)
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    which = rng.integers(0, len(counts), n) if chances is None else rng.choice(len(counts), n, p=chances)
    return members[offsets[which] + (rng.random(n) * counts[which]).astype(np.int64)]


def _load(root: Path) -> Frames:
    dataset = LeRobotReader(root)
    data, episodes = dataset.data, dataset.episodes
    tasks = dataset.tasks.sort_values("task_index")
    stats = {k: {s: np.asarray(v) for s, v in d.items()} for k, d in dataset.stats.items()}
    profile = profile_of(json.loads((root / INFO_PATH).read_text())["features"], root)
    images = {c: _frames(dataset, c, cache_dir() / "frames" / _key(root) / f"{c}.npy") for c in profile.camera_names}
    targets = _targets(root)
    episode = data["episode_index"].to_numpy(np.int64)
    starts, ends = episodes["dataset_from_index"].to_numpy(np.int64), episodes["dataset_to_index"].to_numpy(np.int64)
    aim = None
    if targets:
        aim = episode.copy()
        for ep, step, row in targets[3]:  # a switched episode's frames from its switch on aim at its second target
            aim[starts[ep] + step : ends[ep]] = row
    return Frames(
        images=images,
        state=np.stack(data[STATE_KEY].to_numpy()).astype(np.float32),
        action=np.stack(data[ACTION_KEY].to_numpy()).astype(np.float32),
        episode=episode,
        task=data["task_index"].to_numpy(np.int64),
        tasks=list(tasks.index),
        starts=starts,
        ends=ends,
        stats=stats,
        target=targets[0] if targets else None,
        target_world=targets[1] if targets else None,
        aim=aim,
        referent=targets[2] if targets else None,
        source=np.zeros(len(data), np.int64),
        sources=[str(root)],
        profile=profile.name,
        world=str(targets[1][0]) if targets else "native",  # the first episode's
    )


def _frames(dataset: LeRobotReader, camera: str, cache: Path) -> np.ndarray:
    """A camera's frames, memory-mapped from `cache`, decoded into it first if it is not there."""
    if not cache.is_file():
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(".tmp.npy")
        dataset.camera_frames(camera, np.lib.format.open_memmap(tmp, "w+", np.uint8, dataset.camera_shape(camera))).flush()
        tmp.replace(cache)
    return np.load(cache, mmap_mode="r")


def _targets(root: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[tuple[int, int, int]]] | None:
    """Start position of each episode's target object, then of each switched episode's second
    target, and the world each one's scene is in; each episode's referent type; and per switched
    episode (episode, switch step, its second target's row). None for datasets without scene records."""
    path = root / SCENES_PATH
    if not path.is_file():
        return None
    records = parquet.read(path).sort_values("episode_index")
    positions, scene_worlds, switched, seconds = [], [], [], []
    switches = records["switch"] if "switch" in records else [None] * len(records)
    for episode, scene, target, switch in zip(records["episode_index"], records["scene"], records["target"], switches):
        parsed = json.loads(scene)
        start = {o["id"]: o["pos"] for o in parsed["objects"]}
        positions.append(start[target])
        scene_worlds.append(parsed.get("world", "native"))
        if isinstance(switch, str):  # its second target's row comes after every episode's first
            then = json.loads(switch)
            switched.append((int(episode), int(then["step"]), len(records) + len(seconds)))
            seconds.append(start[then["target"]])
    positions += seconds
    scene_worlds += [scene_worlds[episode] for episode, _, _ in switched]
    return np.asarray(positions, np.float32), np.asarray(scene_worlds), records["referent"].to_numpy(str), switched


def chunk_indices(frames: Frames, index: np.ndarray, horizon: int) -> tuple[np.ndarray, np.ndarray]:
    """For frames `index`, the indices of their next `horizon` actions (clamped to the episode's
    last frame) and a mask of which are real."""
    ends = frames.ends[frames.episode[index]]
    steps = index[:, None] + np.arange(horizon)[None, :]
    mask = steps < ends[:, None]
    return np.minimum(steps, ends[:, None] - 1), mask
