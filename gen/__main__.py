"""Generate a deconfounded LeRobot v3.0 dataset (or, with split=exam, an exam) from a referent spec.

python -m gen referent=object n=20 seed=0 out=datasets/object image_size=128 fps=20
"""

from __future__ import annotations

import sys

from gen.config import GenConfig, validate
from jobs.cli import Failed, main


def generate(cfg: GenConfig) -> None:
    validate(cfg)
    from gen.products.run import generate  # the simulator stack loads only for valid input

    try:
        summary = generate(cfg)
    except KeyboardInterrupt:
        raise KeyboardInterrupt(_kept(cfg)) from None
    print(summary)
    if cfg.push_to_hub:
        from gen.push import PushError, push

        try:
            pushed = push(summary.out, cfg.repo_id or "")
        except PushError as exc:
            raise Failed(str(exc)) from None
        print(f"pushed {len(pushed.files)} files to {pushed.url} (tag {pushed.tag})")


def _kept(cfg: GenConfig) -> str:
    """What an interrupted run leaves: the finished episodes its partial run keeps (jobs/partial.py)."""
    from pathlib import Path

    from jobs.partial import Partial

    partial = Partial(Path(cfg.out or ""))
    kept = len(partial.saved()) if partial.items.is_dir() else 0
    if not kept:
        return "interrupted before any episode was finished; nothing was written to out"
    return (
        f"interrupted: {kept} of {cfg.n} episodes kept in {partial.root}, nothing written to out yet; "
        "rerun the same command with resume=true to continue"
    )


if __name__ == "__main__":
    sys.exit(main("python -m gen", GenConfig, generate, doc=__doc__))
