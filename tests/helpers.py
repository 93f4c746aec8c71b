"""Helpers shared by the tests (importable because pytest puts tests/ on the path)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import mujoco
import numpy as np

from core.layout import NATIVE
from gen.config import parse
from gen.run import generate
from oracle.scene import Scene

ROOT = Path(__file__).resolve().parent.parent
LIBERO_PYTHON = ROOT / ".venv-libero" / "bin" / "python"


def liberos_own(command: str, request: dict, out: Path) -> Path:
    """Run a command of scripts/libero_reference.py in LIBERO's own environment (`.venv-libero`)."""
    assert LIBERO_PYTHON.is_file(), f"{LIBERO_PYTHON} is missing: `make setup` builds LIBERO's reference environment"
    request_file = out.with_name(out.name + ".request.json")
    request_file.write_text(json.dumps(request))
    done = subprocess.run(
        [str(LIBERO_PYTHON), str(ROOT / "scripts" / "libero_reference.py"), command, str(request_file), str(out)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def make_dataset(out: Path, *overrides: str) -> Path:
    """Generate a dataset through the real CLI config and pipeline."""
    generate(parse([f"out={out}", *overrides]), progress=False)
    return out


def body_image(scene: Scene, camera: str, size: int = 128) -> np.ndarray:
    """The body id seen at each pixel of an upright render of `camera` (-1: none; collision geoms hidden)."""
    renderer = mujoco.Renderer(scene.model, size, size)
    renderer.enable_segmentation_rendering()
    option = mujoco.MjvOption()
    option.geomgroup[0] = False
    renderer.update_scene(scene.data, camera=NATIVE.cameras[camera], scene_option=option)
    seg = renderer.render()
    renderer.close()
    is_geom = seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM
    return np.where(is_geom, scene.model.geom_bodyid[np.where(is_geom, seg[..., 0], 0)], -1)


def visible_bodies(scene: Scene, camera: str, size: int = 128) -> dict[int, int]:
    """Pixels per body id in a segmentation render of `camera`."""
    image = body_image(scene, camera, size)
    bodies, counts = np.unique(image[image >= 0], return_counts=True)
    return dict(zip(bodies.tolist(), counts.tolist()))
