"""Contact sheet: one PNG grid of episodes' first agentview frames, each with its instruction.

    python -m gen.preview <dataset> [out=<png>] [n=16] [camera=agentview]

Frames come from the dataset's videos; a plan (`plan_only=true`) has none, so its scenes are
rendered from their specs instead.
"""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import av
import cv2
import numpy as np

from core import parquet
from core.layout import AGENTVIEW
from core.spec import EpisodeSpec
from gen import scenes

TILE = 256
CAPTION = 54


def video_frames(root: Path, camera: str, episodes: list[int]) -> dict[int, np.ndarray]:
    """First frame of each episode, decoded from the dataset's mp4 files."""
    meta = parquet.read(root / "meta/episodes").set_index("episode_index")
    key = f"videos/observation.images.{camera}"
    wanted: dict[Path, dict[int, int]] = {}
    fps = None
    for ep in episodes:
        row = meta.loc[ep]
        path = (
            root
            / f"videos/observation.images.{camera}"
            / f"chunk-{int(row[key + '/chunk_index']):03d}/file-{int(row[key + '/file_index']):03d}.mp4"
        )
        wanted.setdefault(path, {})[ep] = row[key + "/from_timestamp"]
    out: dict[int, np.ndarray] = {}
    for path, starts in wanted.items():
        with av.open(str(path)) as container:
            stream = container.streams.video[0]
            fps = float(stream.average_rate)
            by_index = {int(round(t * fps)): ep for ep, t in starts.items()}
            last = max(by_index)
            for i, frame in enumerate(container.decode(stream)):
                if i in by_index:
                    out[by_index[i]] = frame.to_ndarray(format="rgb24")
                if i >= last:
                    break
    return out


def rendered_frames(specs: list[EpisodeSpec], camera: str) -> dict[int, np.ndarray]:
    """First frames rendered from the specs (for plans, which have no video)."""
    from oracle.render import Cameras
    from oracle.scene import scene_for

    out = {}
    for spec in specs:
        scene = scene_for(spec.assets)
        scene.reset(spec)
        cams = Cameras(scene, spec.sim.image_size, (camera,))
        out[spec.index] = cams.render()[camera].copy()
        cams.close()
    return out


def tile(frame: np.ndarray, caption: str) -> np.ndarray:
    image = cv2.resize(frame, (TILE, TILE), interpolation=cv2.INTER_AREA)
    panel = np.full((CAPTION, TILE, 3), 255, np.uint8)
    for i, line in enumerate(textwrap.wrap(caption, 34)[:3]):
        cv2.putText(panel, line, (4, 15 + 16 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (20, 20, 20), 1, cv2.LINE_AA)
    return np.concatenate([image, panel], axis=0)


def contact_sheet(root: Path, out: Path, n: int = 16, camera: str = AGENTVIEW, columns: int = 4) -> Path:
    records = scenes.read(root).head(n)
    specs = [EpisodeSpec.from_json(s) for s in records["spec"]]
    episodes = list(records["episode_index"])
    has_video = (root / f"videos/observation.images.{camera}").is_dir()
    frames = video_frames(root, camera, episodes) if has_video else rendered_frames(specs, camera)
    tiles = [tile(frames[ep], f"{ep}: {spec.instruction}") for ep, spec in zip(episodes, specs)]
    while len(tiles) % columns:
        tiles.append(np.full_like(tiles[0], 255))
    rows = [np.concatenate(tiles[i : i + columns], axis=1) for i in range(0, len(tiles), columns)]
    sheet = np.concatenate(rows, axis=0)
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR))
    return out


def main(argv: list[str]) -> int:
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip().splitlines()[2].strip())
        return 0 if argv else 2
    root = Path(argv[0])
    try:
        opts = dict(a.split("=", 1) for a in argv[1:])
    except ValueError:
        print("error: options are key=value (out=, n=, camera=)", file=sys.stderr)
        return 2
    if not (root / scenes.SCENES_PATH).is_file():
        print(f"error: {root} has no {scenes.SCENES_PATH}: not a dataset made by python -m gen", file=sys.stderr)
        return 2
    out = Path(opts.get("out", root / "preview.png"))
    path = contact_sheet(root, out, int(opts.get("n", 16)), opts.get("camera", AGENTVIEW))
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
