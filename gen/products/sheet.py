"""A contact sheet: one PNG grid of episodes' first agentview frames, each under its instruction
(the card's `preview.png`, and `python -m gen.preview`). Frames come from the dataset's videos; a
plan (`plan_only=true`) has none, so its scenes are rendered from their specs instead."""

from __future__ import annotations

import textwrap
from pathlib import Path

import cv2
import numpy as np

from core.products import INFO_PATH
from core.spec import EpisodeSpec
from gen.lerobot.reader import LeRobotReader
from gen.products import scenes

TILE = 256
CAPTION = 54


def rendered_frames(specs: list[EpisodeSpec], camera: str) -> dict[int, np.ndarray]:
    """First frames rendered from the specs (for plans, which have no video)."""
    from oracle.render import Cameras
    from oracle.scene import spec_scene

    out = {}
    for spec in specs:
        scene = spec_scene(spec)
        scene.reset(spec)
        cams = Cameras(scene, spec.setup.image_size, (camera,))
        out[spec.index] = cams.render()[camera].copy()
        cams.close()
    return out


def tile(frame: np.ndarray, caption: str) -> np.ndarray:
    image = cv2.resize(frame, (TILE, TILE), interpolation=cv2.INTER_AREA)
    panel = np.full((CAPTION, TILE, 3), 255, np.uint8)
    for i, line in enumerate(textwrap.wrap(caption, 34)[:3]):
        cv2.putText(panel, line, (4, 15 + 16 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (20, 20, 20), 1, cv2.LINE_AA)
    return np.concatenate([image, panel], axis=0)


def contact_sheet(root: Path, out: Path, n: int = 16, camera: str | None = None, columns: int = 4) -> Path:
    """The sheet of the first `n` episodes' first frames of `camera` (default: the profile's
    front camera); a ValueError names a camera the dataset's profile does not have."""
    records = scenes.read(root).head(n)
    specs = [EpisodeSpec.from_json(s) for s in records["spec"]]
    episodes = list(records["episode_index"])
    features = specs[0].setup.interface
    camera = camera or features.camera_names[0]
    if camera not in features.cameras:
        raise ValueError(f"camera must be one of {', '.join(features.camera_names)} (profile {features.name}), got {camera!r}")
    dataset = LeRobotReader(root)
    has_video = (root / INFO_PATH).is_file() and camera in dataset.cameras
    frames = dataset.first_frames(camera, episodes) if has_video else rendered_frames(specs, camera)
    tiles = [tile(frames[ep], f"{ep}: {spec.instruction}") for ep, spec in zip(episodes, specs)]
    while len(tiles) % columns:
        tiles.append(np.full_like(tiles[0], 255))
    rows = [np.concatenate(tiles[i : i + columns], axis=1) for i in range(0, len(tiles), columns)]
    sheet = np.concatenate(rows, axis=0)
    out.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(out), cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR)):
        raise OSError(f"cannot write {out}")
    return out
