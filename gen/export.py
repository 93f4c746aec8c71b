"""`python -m gen.export <dataset> format=v2.1 out=<dir>`: the same episodes as a LeRobot v2.1
dataset, for openpi's trainer and lerobot releases before 0.4 (openpi pins a lerobot commit that
reads v2.1 only).

v2.1 keeps one parquet file and one mp4 per camera for each episode
(`data/chunk-000/episode_000000.parquet`, `videos/chunk-000/<camera key>/episode_000000.mp4`)
and its metadata as JSON lines (`meta/episodes.jsonl`, `meta/tasks.jsonl`,
`meta/episodes_stats.jsonl`) beside `meta/info.json`. The rows are copied as they are; each
episode's video packets are cut out of the v3.0 file without re-encoding, so the frames decode
identically; the per-episode stats are v3.0's own. The export is written to a staging folder
and moved into place when whole, so an interrupted export leaves nothing half-written.
"""

from __future__ import annotations

import shutil
import sys
from dataclasses import dataclass
from pathlib import Path

from gen.check import Broken, check
from gen.lerobot.v21 import export_v21
from jobs.cli import UserError, main
from jobs.output import check_output

FORMATS = ("v2.1",)


@dataclass
class ExportOptions:
    dataset: str = ""  # a generated LeRobot v3.0 dataset
    format: str = "v2.1"  # v2.1: per-episode files and JSON-lines metadata (openpi, lerobot < 0.4)
    out: str = ""  # the new dataset's folder; must not exist unless overwrite=true
    overwrite: bool = False  # replace an earlier export at out (a dataset, or a folder with other files, is refused)


def export(options: ExportOptions) -> None:
    if options.format not in FORMATS:
        raise UserError(f"format must be one of {', '.join(FORMATS)}, got {options.format!r}")
    if not options.out:
        raise UserError("out=<dir> is required: where the exported dataset goes")
    source, out = Path(options.dataset), Path(options.out)
    if out.resolve() == source.resolve() or out.resolve().is_relative_to(source.resolve()):
        raise UserError(f"out={out} is inside the source dataset {source}; export somewhere else")
    check_output(out, options.overwrite, replaces=("export",))
    try:
        check(source)
    except Broken as exc:
        raise UserError(f"cannot export: {exc}") from None
    staging = out.with_name(out.name + ".exporting")
    shutil.rmtree(staging, ignore_errors=True)
    try:
        info = export_v21(source, staging)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    if out.exists():
        shutil.rmtree(out)
    staging.replace(out)
    print(
        f"wrote {out}: LeRobot {info['codebase_version']}, {info['total_episodes']} episodes, "
        f"{info['total_frames']} frames, {info['total_videos']} videos"
    )


if __name__ == "__main__":
    sys.exit(main("python -m gen.export", ExportOptions, export, doc=__doc__, positional="dataset"))
