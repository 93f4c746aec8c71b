"""A dataset under construction, built so that a killed run resumes to identical bytes.

    .<name>.partial/            beside `out`
        run.json                the options that determine the data (resume must match them)
        episodes/000000.pkl     one file per finished episode, each written atomically
        dataset/                assembled from the episode files at the end, then moved to `out`

Every episode is produced independently and kept whole in its own file, so SIGKILL at any
moment loses at most the episodes in flight; `resume=true` produces only the missing ones.
The LeRobot files are assembled from the episode files only after all exist (a kill during
assembly just means assembling again), and the dataset becomes visible at `out` in one rename
with `meta/generation.json` (`"complete": true`) already inside it.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from gen import faults

if TYPE_CHECKING:
    from gen.produce import Produced

GENERATION_PATH = "meta/generation.json"  # written last: its presence marks a dataset complete
EPISODES = "episodes"
ASSEMBLED = "dataset"


class Partial:
    def __init__(self, out: Path) -> None:
        self.out = out
        self.root = out.parent / f".{out.name}.partial"

    @property
    def exists(self) -> bool:
        return self.root.is_dir()

    @property
    def dataset(self) -> Path:
        return self.root / ASSEMBLED

    def start(self, run: dict, resume: bool) -> int:
        """Create or reopen the partial run; returns how many leading episodes are done."""
        record = self.root / "run.json"
        if self.exists:
            if not resume:
                raise FileExistsError(
                    f"out={self.out}: an interrupted run left {self.root}; pass resume=true to continue it, or delete it"
                )
            previous = json.loads(record.read_text()) if record.is_file() else None
            if previous != run:
                changed = sorted(k for k in run if previous is None or previous.get(k) != run[k])
                raise ValueError(f"resume=true, but the interrupted run at {self.root} used other options ({', '.join(changed)})")
        else:
            (self.root / EPISODES).mkdir(parents=True)
            tmp = record.with_suffix(".tmp")
            tmp.write_text(json.dumps(run, indent=2, sort_keys=True))
            tmp.replace(record)
        for stray in (self.root / EPISODES).glob("*.tmp"):
            stray.unlink()  # an episode that was being written when the run died
        done = 0
        while (self.root / EPISODES / f"{done:06d}.pkl").is_file():
            done += 1
        return done

    def save(self, index: int, produced: Produced) -> None:
        path = self.root / EPISODES / f"{index:06d}.pkl"
        tmp = path.with_suffix(".tmp")
        with open(tmp, "wb") as f:
            pickle.dump(produced, f, protocol=pickle.HIGHEST_PROTOCOL)
            faults.point(f"save:{index}")
        tmp.replace(path)

    def episodes(self, n: int) -> Iterator[Produced]:
        for i in range(n):
            with open(self.root / EPISODES / f"{i:06d}.pkl", "rb") as f:
                yield pickle.load(f)

    def fresh_dataset(self) -> Path:
        """An empty folder to assemble into (whatever a killed assembly left is discarded)."""
        shutil.rmtree(self.dataset, ignore_errors=True)
        (self.dataset / "meta").mkdir(parents=True)
        return self.dataset

    def publish(self) -> None:
        publish(self.dataset, self.out)
        shutil.rmtree(self.root)


def completed(out: Path) -> dict | None:
    """The generation record of a finished dataset or plan at `out`, or None if there is none."""
    record = out / GENERATION_PATH
    try:
        generation = json.loads(record.read_text())
    except (OSError, ValueError):
        return None
    return generation if isinstance(generation, dict) and generation.get("complete") is True else None


def publish(built: Path, out: Path) -> None:
    """Move a finished folder to `out` in one rename; an old `out` is removed only after it."""
    out.parent.mkdir(parents=True, exist_ok=True)
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        out.rename(old)
    built.rename(out)
    if old is not None:
        shutil.rmtree(old)


@contextmanager
def staging(out: Path) -> Iterator[Path]:
    """A throwaway folder beside `out` for products cheap to redo (exams, plans): published to
    `out` when the block succeeds, removed either way."""
    root = out.parent / f".{out.name}.staging-{os.getpid()}"
    shutil.rmtree(root, ignore_errors=True)
    try:
        yield root
        publish(root, out)
    finally:
        shutil.rmtree(root, ignore_errors=True)
