"""LIBERO's own frames and ours at the same initial state of a LIBERO suite, side by side (docs/LIBERO.md's
picture): `python scripts/libero_side_by_side.py [world=libero_object] [task=0] [state=0] [out=docs/<world>_side_by_side.png]`.

Both cameras, as a policy sees them (LIBERO's frames turned 180 degrees, as lerobot's
LiberoProcessorStep and openpi's client turn them; ours as the libero profile stores them), with
the mean absolute difference of each pair printed under it.
"""

from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jobs.cli import UserError, main  # noqa: E402


@dataclass
class SideBySideOptions:
    world: str = "libero_object"  # a LIBERO world: libero_object, libero_spatial or libero_goal
    task: int = 0  # the suite's task (0..9)
    state: int = 0  # its initial state (0..49)
    out: str | None = None  # default docs/<world>_side_by_side.png


def picture(options: SideBySideOptions) -> None:
    from libero_objects_side_by_side import liberos_frames, our_frames
    from PIL import Image, ImageDraw

    from core.profiles import LIBERO

    if not (0 <= options.task < 10 and 0 <= options.state < 50):
        raise UserError(f"task must be in 0..9 and state in 0..49, got {options.task} and {options.state}")
    size, cases = LIBERO.image_size, [[options.task, options.state]]
    with tempfile.TemporaryDirectory() as tmp:
        theirs = np.load(liberos_frames(options.world, cases, Path(tmp) / "f.npz"), allow_pickle=True)
        frames = our_frames(options.world, cases, theirs, labels=False)
    ours = {c: frames[f"{options.task}-{options.state}-{c}"] for c in LIBERO.cameras}
    sheet = Image.new("RGB", (4 * size, size + 40), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (camera, model_camera) in enumerate(LIBERO.cameras.items()):
        reference = theirs[f"{options.task}-{options.state}-{model_camera}"][::-1, ::-1]
        diff = np.abs(ours[camera].astype(int) - reference.astype(int)).mean()
        sheet.paste(Image.fromarray(reference), (2 * i * size, 0))
        sheet.paste(Image.fromarray(ours[camera]), ((2 * i + 1) * size, 0))
        draw.text((2 * i * size + 4, size + 4), f"LIBERO's {model_camera}", fill="black")
        draw.text(((2 * i + 1) * size + 4, size + 4), f"ours ({camera}); mean |diff| {diff:.2f}/255", fill="black")
    out = options.out or f"docs/{options.world}_side_by_side.png"
    sheet.save(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    sys.exit(main("python scripts/libero_side_by_side.py", SideBySideOptions, picture, doc=__doc__))
