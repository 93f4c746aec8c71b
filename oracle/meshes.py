"""Lighter visual meshes for the robot, so that CPU rendering stops paying for invisible detail.

robosuite's Panda, gripper and mount are drawn with ~170,000 triangles; at the 96-224 px our
cameras render, most are smaller than a pixel, and on the CPU rasteriser (llvmpipe) they were
about 80% of a frame's cost (README: Performance). Every purely visual mesh (a geom that
collides with nothing) above `MAX_FACES` triangles is decimated (quadric edge collapse,
deterministic) to that many and written inline into the MJCF. Collision meshes, and so the
physics, are untouched; objects are small meshes and stay as they are. Results are cached on
disk (`~/.cache/deconfound/meshes`, keyed by the file's bytes), since parsing and decimating
take seconds and every worker process builds its own scene.
"""

from __future__ import annotations

import functools
import hashlib
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from core import cache_dir

MAX_FACES = 2000
ROBOT_PREFIXES = ("robot0_", "gripper0_", "fixed_mount0_")


def lighten(root: ET.Element) -> None:
    """Replace the robot's large visual-only meshes in an MJCF tree by decimated inline meshes."""
    used, collides = set(), set()
    for geom in root.iter("geom"):
        if geom.get("mesh"):
            used.add(geom.get("mesh"))
            if not (geom.get("contype") == "0" and geom.get("conaffinity") == "0"):
                collides.add(geom.get("mesh"))
    for mesh in root.iter("mesh"):
        name, file = mesh.get("name", ""), mesh.get("file")
        if not file or not name.startswith(ROBOT_PREFIXES) or name not in used or name in collides:
            continue
        light = decimated(file)
        if light is None:
            continue
        vertices, faces = light
        del mesh.attrib["file"]
        mesh.set("vertex", " ".join(f"{v:.6g}" for v in vertices.ravel()))
        mesh.set("face", " ".join(map(str, faces.ravel())))


@functools.cache
def decimated(file: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(vertices, faces) of the mesh file cut to `MAX_FACES` triangles, or None if it is smaller."""
    data = Path(file).read_bytes()
    cache = cache_dir() / "meshes" / f"{hashlib.sha256(data).hexdigest()[:24]}-{MAX_FACES}.npz"
    try:
        with np.load(cache) as npz:
            return (npz["vertices"], npz["faces"]) if len(npz["faces"]) else None
    except (OSError, ValueError, KeyError):  # absent or damaged: compute it again
        pass
    light = _decimate(Path(file))
    vertices, faces = light if light is not None else (np.zeros((0, 3)), np.zeros((0, 3), np.int64))
    try:  # the cache only saves time: an unwritable home must not stop a run
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(tmp, vertices=vertices, faces=faces)
        tmp.replace(cache)
    except OSError:
        pass
    return light


def _decimate(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    import fast_simplification

    vertices, faces = _read(path)
    if len(faces) <= MAX_FACES:
        return None
    # Weld vertices that the file repeats per normal/uv, so the surface is connected.
    unique, inverse = np.unique(np.round(vertices, 6), axis=0, return_inverse=True)
    faces = inverse.reshape(-1)[faces]
    faces = faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]
    points, triangles = fast_simplification.simplify(unique, faces, target_count=MAX_FACES)
    return np.asarray(points, np.float64), np.asarray(triangles, np.int64)


def _read(path: Path) -> tuple[np.ndarray, np.ndarray]:
    if path.suffix.lower() == ".stl":
        return _read_stl(path)
    if path.suffix.lower() == ".obj":
        return _read_obj(path)
    raise ValueError(f"{path}: only .stl and .obj meshes can be lightened")


def _read_stl(path: Path) -> tuple[np.ndarray, np.ndarray]:
    data = path.read_bytes()
    count = int(np.frombuffer(data, np.uint32, 1, 80)[0])
    if 84 + 50 * count != len(data):
        raise ValueError(f"{path}: not a binary STL file")
    record = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    triangles = np.frombuffer(data, record, count, 84)["v"].astype(np.float64)
    return triangles.reshape(-1, 3), np.arange(3 * count).reshape(-1, 3)


def _read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            vertices.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            corners = [int(token.split("/")[0]) for token in line.split()[1:]]
            corners = [c - 1 if c > 0 else len(vertices) + c for c in corners]
            faces += [[corners[0], corners[i], corners[i + 1]] for i in range(1, len(corners) - 1)]
    return np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
