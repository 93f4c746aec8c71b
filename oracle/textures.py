"""Smaller textures, so that a scene of scanned objects compiles and starts rendering in a
fraction of the time.

LIBERO's groceries carry 2048 x 2048 texture maps, its basket a 4096 x 4096 one and its arena
file 1270 x 1270 cube textures; decoding those PNG files was most of the 2.1 s a LIBERO-Object
scene took to compile, and building their mipmaps most of the 2 s a renderer took to start, in
every worker process. At the frame sizes we render (256 px by default) an object spans a few
hundred pixels, so the sampler reads a mipmap level well below the full size anyway. Every
texture image wider or taller than `TEXTURE_SIDE` is halved by averaging 2 x 2 texels (the box
filter that builds mipmap levels) until it fits, so the levels that remain are the ones the
renderer would have sampled. The results are cached on disk (`~/.cache/deconfound/textures`,
keyed by the file's bytes). A halved copy keeps its original's colour space: MuJoCo reads a PNG
that declares sRGB (LIBERO's salad dressing) as sRGB, and the copy, which does not declare it,
would otherwise be drawn lighter.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from core import derived_file, keep

TEXTURE_SIDE = 1024  # texels: the largest side a texture image keeps


def shrink(root: ET.Element, side: int = TEXTURE_SIDE) -> None:
    """Point every texture image in an MJCF tree (2-D maps, cube faces) that is larger than
    `side` at a halved copy."""
    for texture in root.iter("texture"):
        file = texture.get("file")
        if file and texture.get("type") in ("2d", "cube"):
            small = halved(file, side)
            if small != Path(file) and texture.get("colorspace", "auto") == "auto" and _srgb(file):
                texture.set("colorspace", "sRGB")
            texture.set("file", str(small))


def _srgb(file: str) -> bool:
    """Whether a PNG file declares the sRGB colour space (its sRGB chunk: how MuJoCo's `auto` reads it)."""
    from PIL import Image

    with Image.open(file) as image:  # reads the header only
        return "srgb" in image.info


def halved(file: str, side: int = TEXTURE_SIDE) -> Path:
    """The image file, or a cached copy of it halved (2 x 2 box) until no side exceeds `side`."""
    from PIL import Image

    with Image.open(file) as image:  # reads the header only
        if max(image.size) <= side:
            return Path(file)
    cache = derived_file("textures", Path(file), str(side), ".png")
    if cache.is_file():
        return cache
    with Image.open(file) as image:
        image = image.convert("RGBA" if "A" in image.getbands() else "RGB")
        while max(image.size) > side:
            image = image.reduce(2)
    return cache if keep(cache, image.save) else Path(file)
