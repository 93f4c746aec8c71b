"""Contact sheet: one PNG grid of episodes' first agentview frames, each with its instruction.

    python -m gen.preview <dataset> [out=<png>] [n=16] [camera=<camera>]

Frames come from the dataset's videos; a plan (`plan_only=true`) has none, so its scenes are
rendered from their specs instead.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import cv2

from core.products import PREVIEW_PATH, SCENES_PATH
from gen.products.sheet import contact_sheet
from jobs.cli import UserError, main


@dataclass
class PreviewOptions:
    dataset: str = ""  # the dataset (or plan) folder
    out: str | None = None  # the image to write (.png); default <dataset>/preview.png
    n: int = 16  # how many episodes, from the first
    camera: Optional[str] = None  # which camera's first frame; default the profile's front camera


def run(options: PreviewOptions) -> None:
    root = Path(options.dataset)
    if not (root / SCENES_PATH).is_file():
        raise UserError(f"{root} has no {SCENES_PATH}: not a dataset made by python -m gen")
    if options.n < 1:
        raise UserError(f"n must be at least 1, got {options.n}")
    out = Path(options.out) if options.out else root / PREVIEW_PATH
    check_out(out)
    try:
        print(f"wrote {contact_sheet(root, out, options.n, options.camera)}")
    except ValueError as exc:
        raise UserError(str(exc)) from None
    except OSError as exc:  # e.g. a file where a folder of the path should be, or no permission
        raise UserError(f"out={out}: cannot write the sheet there ({exc.strerror or exc})") from None


def check_out(out: Path) -> None:
    """`out` must name an image file in a folder (or one to be made): checked before any frame
    is decoded or rendered, since cv2 cannot write into a folder or a name without an image
    extension."""
    if out.is_dir():
        raise UserError(f"out={out} is a folder; name the image to write, e.g. out={out / PREVIEW_PATH}")
    if not cv2.haveImageWriter(str(out)):
        raise UserError(f"out={out} is not an image file name; end it in .png (or another image extension, e.g. .jpg)")
    folder = out.parent
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise UserError(f"out={out}: {folder} is a file, not a folder the sheet can go in")


if __name__ == "__main__":
    sys.exit(main("python -m gen.preview", PreviewOptions, run, doc=__doc__, positional="dataset"))
