"""Where a command writes: an `out` that can be made and written, and never a folder of someone
else's files. `overwrite=true` replaces only a product this project wrote (core/products.py names
what each holds), and refuses one that also holds the user's files, naming them."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from core.exam import EXAM_FORMAT
from core.products import DATASET_ENTRIES, EXAM_PATH, GENERATION_PATH, INFO_PATH, PRODUCT_ENTRIES, PRODUCTS, SCENES_PATH
from jobs.cli import UserError


def check_output(out: Path, overwrite: bool, replaces: tuple[str, ...] = PRODUCTS) -> None:
    """`out` must be creatable and writable, and empty unless `overwrite`, which replaces only a
    folder this project wrote, of a kind in `replaces` (a dataset, a plan, an exam, an export): a
    product is published by renaming it to `out`, so `out` can be neither a folder of someone
    else's files nor the current one.

    A product folder that also holds files this project did not write is refused even with
    `overwrite`: replacing the folder would delete them.
    """
    if out.exists() and not out.is_dir():
        raise UserError(f"out={out} exists and is not a folder")
    here = Path.cwd().resolve()
    if out.resolve() == here or out.resolve() in here.parents:
        raise UserError(f"out={out} is the current folder (or holds it), which cannot be replaced; choose a folder inside it")
    if out.is_dir() and any(out.iterdir()):
        if not overwrite:
            raise UserError(f"out={out} is not empty; pass overwrite=true to replace it")
        found = sorted(p.name for p in out.iterdir())
        product = product_in(out)
        kinds = _a(" or ".join(", ".join(replaces).rsplit(", ", 1)))
        if product is None:
            raise UserError(
                f"out={out} holds files this project did not write ({listed(found)}); overwrite=true replaces only {kinds} "
                "made here: choose another out"
            )
        if product not in replaces:
            raise UserError(f"out={out} holds {_a(product)} made here; overwrite=true replaces only {kinds}: choose another out")
        strays = [name for name in found if name not in PRODUCT_ENTRIES[product]]
        if strays:  # e.g. an eval report kept inside its exam: replacing the exam would delete it
            raise UserError(
                f"out={out} holds {_a(product)} made here and files this project did not write ({listed(strays)}), "
                "which overwrite=true would delete: move them out of it, or choose another out"
            )
    check_writable(out)


def _a(words: str) -> str:
    return f"{'an' if words[:1] in 'aeiou' else 'a'} {words}"


def check_writable(out: Path, inside: bool = False) -> None:
    """Refuse an `out` that cannot be made (with `inside`: written into): a folder is created (and
    removed) beside it (in it), since permission bits alone say nothing for root or on read-only mounts."""
    parent = out.resolve() if inside else out.resolve().parent
    while not parent.exists():
        parent = parent.parent
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".deconfound-write-test-", dir=parent))
    except OSError as exc:
        raise UserError(f"out={out} is not writable ({exc.strerror or exc} in {parent})") from None


def listed(names: list[str]) -> str:
    """The first few of `names`, for a one-line message."""
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def product_in(folder: Path) -> str | None:
    """What this project wrote in `folder` ("dataset", "plan", "exam", "export"), or None if it
    holds anything else: a finished or partially assembled dataset or plan (LeRobot's meta files
    and our scene records), an exam (exam.json of our format), or a LeRobot v2.1 export of one of
    our datasets (gen/export.py: v2.1's info.json beside our generation record)."""
    try:
        generation = json.loads((folder / GENERATION_PATH).read_text())
        if generation.get("generator") == "deconfound":
            if _codebase_version(folder) == "v2.1":
                return "export"
            return "plan" if generation.get("plan_only") else "dataset"
    except (OSError, ValueError, AttributeError):
        pass
    try:
        if json.loads((folder / EXAM_PATH).read_text()).get("format") == EXAM_FORMAT:
            return "exam"
    except (OSError, ValueError, AttributeError):
        pass
    if (folder / SCENES_PATH).is_file() and {p.name for p in folder.iterdir()} <= DATASET_ENTRIES:
        return "dataset"
    return None


def _codebase_version(folder: Path) -> str | None:
    """The LeRobot format a folder's meta/info.json names, if it has one."""
    try:
        return json.loads((folder / INFO_PATH).read_text()).get("codebase_version")
    except (OSError, ValueError, AttributeError):
        return None
