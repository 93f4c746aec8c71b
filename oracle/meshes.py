"""Lighter visual meshes, so that CPU rendering stops paying for invisible detail.

robosuite's Panda, gripper and mount are drawn with ~170,000 triangles; at the 96-224 px our
cameras render, most are smaller than a pixel, and on the CPU rasteriser (llvmpipe) they were
about 80% of a frame's cost (docs/GENERATE.md: Performance). Every purely visual mesh (a geom that
collides with nothing) of the robot above `MAX_FACES` triangles is decimated (quadric edge
collapse, deterministic) to that many and written inline into the MJCF. LIBERO's scanned
objects are textured meshes of 14,000-66,000 triangles each (`objects=True`): they are cut to
`OBJECT_FACES` keeping every surviving vertex's texture coordinate (vertices are only merged,
never moved, so the texture stays where it was). Collision meshes, and so the physics, are
untouched; robosuite's own objects are small and stay as they are. Results are cached on disk
(`~/.cache/deconfound/meshes`, keyed by the file's bytes), since parsing and decimating take
seconds and every worker process builds its own scene.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np

from core import derived_file, keep

MAX_FACES = 2000
OBJECT_FACES = 3000
ROBOT_PREFIXES = ("robot0_", "gripper0_", "fixed_mount0_")


def lighten(root: ET.Element, objects: bool = False, faces: dict[str, int] | None = None, robot_faces: int = MAX_FACES) -> None:
    """Replace the robot's large visual-only meshes in an MJCF tree by decimated inline meshes,
    and (`objects`) the objects' textured ones too: to `OBJECT_FACES` triangles, or to
    `faces[folder]` for the meshes under a folder (an object whose detail shows: LIBERO's woven
    basket)."""
    used, collides = set(), set()
    for geom in root.iter("geom"):
        if geom.get("mesh"):
            used.add(geom.get("mesh"))
            if not (geom.get("contype") == "0" and geom.get("conaffinity") == "0"):
                collides.add(geom.get("mesh"))
    for mesh in root.iter("mesh"):
        name, file = mesh.get("name", ""), mesh.get("file")
        if not file or name not in used or name in collides:
            continue
        robot = name.startswith(ROBOT_PREFIXES)
        if not robot and not (objects and file.endswith(".msh")):
            continue
        target = next((n for folder, n in (faces or {}).items() if file.startswith(folder)), OBJECT_FACES)
        light = decimated(file, robot_faces) if robot else textured(file, target)
        if light is None:
            continue
        del mesh.attrib["file"]
        mesh.set("vertex", " ".join(f"{v:.6g}" for v in light["vertices"].ravel()))
        if "texcoords" in light:
            mesh.set("texcoord", " ".join(f"{v:.6g}" for v in light["texcoords"].ravel()))
        mesh.set("face", " ".join(map(str, light["faces"].ravel())))


def _cached(file: str, tag: str, make: Callable[[Path], dict[str, np.ndarray] | None]) -> dict[str, np.ndarray] | None:
    """`make(file)`, kept on disk under the file's content hash and `tag`; None: nothing to lighten."""
    cache = derived_file("meshes", Path(file), tag, ".npz")
    try:
        with np.load(cache) as npz:
            return {k: npz[k] for k in npz.files} if len(npz["faces"]) else None
    except (OSError, ValueError, KeyError):  # absent or damaged: compute it again
        pass
    light = make(Path(file))
    arrays = light if light is not None else {"vertices": np.zeros((0, 3)), "faces": np.zeros((0, 3), np.int64)}
    keep(cache, lambda tmp: np.savez(tmp, **arrays))
    return light


@functools.cache
def decimated(file: str, faces: int = MAX_FACES) -> dict[str, np.ndarray] | None:
    """{vertices, faces} of the mesh file cut to `faces` triangles, or None if it is smaller."""
    return _cached(file, str(faces), functools.partial(_decimate, faces=faces))


@functools.cache
def textured(file: str, faces: int = OBJECT_FACES) -> dict[str, np.ndarray] | None:
    """{vertices, texcoords, faces} of a textured MuJoCo .msh file cut to `faces` triangles, or
    None if it is smaller."""
    return _cached(file, f"uv{faces}", functools.partial(_decimate_textured, faces=faces))


def _decimate(path: Path, faces: int) -> dict[str, np.ndarray] | None:
    import fast_simplification

    vertices, triangles = _read(path)
    if len(triangles) <= faces:
        return None
    # Weld vertices that the file repeats per normal/uv, so the surface is connected.
    unique, inverse = np.unique(np.round(vertices, 6), axis=0, return_inverse=True)
    triangles = _proper(inverse.reshape(-1)[triangles])
    points, triangles = fast_simplification.simplify(unique, triangles, target_count=faces)
    return {"vertices": np.asarray(points, np.float64), "faces": np.asarray(triangles, np.int64)}


def _decimate_textured(path: Path, faces: int) -> dict[str, np.ndarray] | None:
    """Quadric edge collapses chosen on the surface welded by position and texture coordinate,
    then replayed by merging each collapsed vertex into its survivor: survivors keep their own
    position and texture coordinate, and texture seams (a position with two coordinates) stay
    open borders that collapses keep."""
    import fast_simplification

    vertices, texcoords, triangles = _read_msh(path)
    if len(triangles) <= faces:
        return None
    key = np.concatenate([np.round(vertices, 6), np.round(texcoords, 6)], axis=1)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    vertices, texcoords = vertices[first], texcoords[first]
    triangles = _proper(inverse.reshape(-1)[triangles])
    _, _, collapses = fast_simplification.simplify(
        np.ascontiguousarray(vertices), np.ascontiguousarray(triangles), target_count=faces, return_collapses=True
    )
    survivor = np.arange(len(vertices))
    for kept, gone in collapses:
        survivor[gone] = kept
    while not np.array_equal(survivor[survivor], survivor):  # follow chains of collapses to their end
        survivor = survivor[survivor]
    triangles = _proper(survivor[triangles])
    used, triangles = np.unique(triangles, return_inverse=True)
    return {"vertices": vertices[used], "texcoords": texcoords[used], "faces": triangles.reshape(-1, 3).astype(np.int64)}


def _proper(faces: np.ndarray) -> np.ndarray:
    """The faces whose three corners are distinct."""
    return faces[(faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])]


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


def _read_msh(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MuJoCo's binary .msh: four int32 counts (vertices, normals, texture coordinates, faces),
    then float32 vertices, normals and texture coordinates and int32 faces."""
    data = path.read_bytes()
    nv, nn, nt, nf = (int(v) for v in np.frombuffer(data, np.int32, 4))
    offsets = np.cumsum([16, 12 * nv, 12 * nn, 8 * nt])
    if nt != nv or offsets[-1] + 12 * nf != len(data):
        raise ValueError(f"{path}: not a textured .msh file (one texture coordinate per vertex)")
    vertices = np.frombuffer(data, np.float32, 3 * nv, offsets[0]).reshape(-1, 3).astype(np.float64)
    texcoords = np.frombuffer(data, np.float32, 2 * nt, offsets[2]).reshape(-1, 2).astype(np.float64)
    faces = np.frombuffer(data, np.int32, 3 * nf, offsets[3]).reshape(-1, 3).astype(np.int64)
    return vertices, texcoords, faces
