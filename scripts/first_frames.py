"""A dataset's first frames, one per referent type, each under its instruction (docs/GENERATE.md's picture
of a mixed dataset): `python scripts/first_frames.py <dataset> [camera=] [out=<dataset>-first_frames.png]`.

What a policy sees at the start of an episode of each type, and what it is told: the quickest
check that the words name what the picture shows (a color word is what a person would call the
object there).
"""

from __future__ import annotations

import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

from jobs.cli import UserError, main  # noqa: E402

LABEL_HEIGHT = 44  # pixels under each frame for the type, its world and the instruction


@dataclass
class FirstFramesOptions:
    dataset: str = ""  # a finished dataset (python -m gen ...)
    camera: str | None = None  # an image key's camera (image, wrist_image, ...); default the dataset's first
    out: str | None = None  # default <dataset>-first_frames.png, beside the dataset (not in it: gen.push would upload it)


def picture(options: FirstFramesOptions) -> None:
    from lerobot.datasets.lerobot_dataset import LeRobotDataset
    from PIL import Image, ImageDraw

    from gen.products import scenes
    from jobs.partial import completed

    root = Path(options.dataset)
    if completed(root) is None:
        raise UserError(f"{root} is not a finished dataset (no complete meta/generation.json): make one with python -m gen")
    records = scenes.read(root)
    ds = LeRobotDataset("local/first_frames", root=root)
    keys = list(ds.meta.camera_keys)
    key = keys[0] if options.camera is None else f"observation.images.{options.camera}"
    if key not in keys:
        raise UserError(f"camera={options.camera}: the dataset's cameras are {', '.join(k.rsplit('.', 1)[-1] for k in keys)}")
    firsts = records.groupby("referent", sort=False).head(1)
    tiles = []
    for _, record in firsts.iterrows():
        frame = ds[ds.meta.episodes[int(record["episode_index"])]["dataset_from_index"]][key]
        tiles.append((Image.fromarray((frame.permute(1, 2, 0).numpy() * 255).round().astype("uint8")), record))
    size = max(192, tiles[0][0].width)
    sheet = Image.new("RGB", (size * len(tiles), size + LABEL_HEIGHT), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (tile, record) in enumerate(tiles):
        sheet.paste(tile.resize((size, size), Image.NEAREST), (i * size, 0))
        where = f" @ {record['world']}" if "world" in record and record["world"] else ""
        text = f"{record['referent']}{where}\n" + "\n".join(textwrap.wrap(record["instruction"], width=size // 6)[:2])
        draw.multiline_text((i * size + 3, size + 2), text, fill="black", spacing=1)
    out = Path(options.out or root.parent / f"{root.name}-first_frames.png")
    sheet.save(out)
    print(f"wrote {out} ({len(tiles)} types, camera {key.rsplit('.', 1)[-1]})")


if __name__ == "__main__":
    sys.exit(main("python scripts/first_frames.py", FirstFramesOptions, picture, doc=__doc__, positional="dataset"))
