"""`python -m gen.verify <dataset> [episodes=3]`: regenerate a sample of episodes from their
recorded specs and compare them with the dataset.

Each sampled episode is demonstrated again from its spec (same attempt, same poses) and must
reproduce, bit for bit, its actions and states in the data parquet and its scene record; its
frames are rendered again and must match the decoded video within codec tolerance (mean
absolute difference below 3 of 255 per frame). Exit code 1 names the first mismatch.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import av
import numpy as np

from core.profiles import ACTION_KEY, STATE_KEY
from core.spec import EpisodeSpec
from gen.lerobot.reader import LeRobotReader
from gen.products import scenes
from jobs.cli import Failed, UserError, main

FRAME_TOLERANCE = 3.0  # mean |difference| per frame, in 0..255 units


class Mismatch(Exception):
    pass


def verify(root: Path, sample: int = 3) -> list[int]:
    """Raises Mismatch on the first difference; returns the episodes checked."""
    from gen.products.produce import Producer
    from oracle.episode import demonstrate
    from referents import registry

    dataset = LeRobotReader(root)
    records = scenes.read(root).sort_values("episode_index").reset_index(drop=True)
    data = dataset.data
    chosen = sorted({int(i) for i in np.linspace(0, len(records) - 1, min(sample, len(records)))})
    producers: dict[tuple, Producer] = {}
    for ep in chosen:
        rec = records.iloc[ep]
        spec = EpisodeSpec.from_json(rec["spec"])
        key = (spec.assets, spec.setup)
        if key not in producers:
            producers[key] = Producer(None, spec.setup, assets=spec.assets)
        producer = producers[key]
        demo = demonstrate(producer.scene, producer.ik, spec, registry.demo_of(spec.referent))
        rows = data[data.episode_index == ep].sort_values("frame_index")
        if not demo.success:
            raise Mismatch(f"episode {ep}: its spec no longer yields a successful demo")
        recorded = np.stack(rows[ACTION_KEY].to_numpy())
        if recorded.shape != demo.actions.shape or not np.array_equal(recorded, demo.actions):
            raise Mismatch(f"episode {ep}: actions differ from a regeneration")
        produced = producer.record(demo, [])
        if not np.array_equal(np.stack(rows[STATE_KEY].to_numpy()), produced.episode.states):
            raise Mismatch(f"episode {ep}: {STATE_KEY} differs from a regeneration")
        fresh = scenes.row(ep, spec, produced, switched="switch" in rec)
        for column in ("scene", "counterfactuals", "spec", "initial_state", "outcome", *(("switch",) if "switch" in rec else ())):
            if column == "initial_state":
                same = np.array_equal(np.asarray(rec[column]), np.asarray(fresh[column]))
            else:  # a null (an episode that never switches) reads back as NaN
                same = (rec[column] if isinstance(rec[column], str) else None) == fresh[column]
            if not same:
                raise Mismatch(f"episode {ep}: scene record column {column!r} differs from a regeneration")
        for camera, mp4 in produced.episode.videos.items():
            rendered = _frames_of(mp4)
            decoded = dataset.episode_frames(ep, camera)
            if rendered.shape != decoded.shape:
                raise Mismatch(f"episode {ep}: {camera} video has {len(decoded)} frames, regeneration has {len(rendered)}")
            worst = float(np.abs(rendered.astype(int) - decoded.astype(int)).mean(axis=(1, 2, 3)).max())
            if worst > FRAME_TOLERANCE:
                raise Mismatch(f"episode {ep}: {camera} frames differ from a regeneration by {worst:.1f}/255")
    for producer in producers.values():
        producer.close()
    return chosen


def _frames_of(mp4: bytes) -> np.ndarray:
    import io

    with av.open(io.BytesIO(mp4)) as container:
        return np.stack([f.to_ndarray(format="rgb24") for f in container.decode(container.streams.video[0])])


@dataclass
class VerifyOptions:
    dataset: str = ""  # the dataset folder to verify
    episodes: int = 3  # how many episodes, spread over the dataset, to regenerate


def run(options: VerifyOptions) -> None:
    root = Path(options.dataset)
    if not root.is_dir():
        raise UserError(f"{root} is not a folder" if root.exists() else f"{root} does not exist")
    if options.episodes < 1:
        raise UserError(f"episodes must be at least 1, got {options.episodes}")
    try:
        checked = verify(root, options.episodes)
    except Mismatch as exc:
        raise Failed(f"{root}: {exc}") from None
    except (OSError, KeyError, ValueError) as exc:
        raise UserError(f"{root}: cannot verify ({type(exc).__name__}: {exc})") from None
    print(f"ok: {root}: episodes {checked} regenerate identically (video within {FRAME_TOLERANCE:g}/255)")


if __name__ == "__main__":
    sys.exit(main("python -m gen.verify", VerifyOptions, run, doc=__doc__, positional="dataset"))
