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

A partial run is locked while a process works on it (an flock on its folder, which the kernel
releases when that process ends, however it ends): a second run on the same `out` is told that
another run is using it, instead of resuming or discarding the files under the first one's feet.
The exam battery keeps its finished rollouts in a partial run of its own the same way.
"""

from __future__ import annotations

import fcntl
import json
import os
import pickle
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from core.products import GENERATION_PATH
from jobs import faults
from jobs.cli import UserError

EPISODES = "episodes"
ASSEMBLED = "dataset"


class Partial:
    """The partial run of `out`, its finished items (episodes, rollouts) kept one file each."""

    def __init__(self, out: Path, items: str = EPISODES) -> None:
        self.out = out
        self.root = out.parent / f".{out.name}.partial"
        self.items = self.root / items
        self._lock: int | None = None

    def __getstate__(self) -> dict:
        """Worker processes get a copy to save items with; only the process that started the run holds the lock."""
        return {**self.__dict__, "_lock": None}

    def __enter__(self) -> Partial:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    @property
    def dataset(self) -> Path:
        return self.root / ASSEMBLED

    def start(self, run: dict, resume: bool, discard: bool = False) -> int:
        """Lock the partial run, then create it, reopen it (`resume`) or empty it (`discard`);
        returns how many leading items are done. Refused with one line while another process holds
        it, or when an interrupted run is there and neither `resume` nor `discard` asks what to do."""
        self.root.mkdir(parents=True, exist_ok=True)
        self._lock = os.open(self.root, os.O_RDONLY)
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self.release()
            raise UserError(
                f"out={self.out}: another run is using {self.root} right now; wait for it to end, or choose another out"
            ) from None
        record = self.root / "run.json"
        if record.is_file() and not resume:
            if not discard:
                raise UserError(
                    f"out={self.out}: an interrupted run left {self.root}; "
                    "pass resume=true to continue it, or overwrite=true to discard it"
                )
            for entry in self.root.iterdir():  # the folder itself stays: it carries the lock
                if entry.is_dir():
                    shutil.rmtree(entry)
                else:
                    entry.unlink()
        run = json.loads(json.dumps(run))  # as the record holds it (tuples as lists)
        if record.is_file():
            previous = json.loads(record.read_text())
            if previous != run:
                changed = "; ".join(changes(previous, run)) or "its record differs"
                raise UserError(f"resume=true, but the interrupted run at {self.root} used other options ({changed})")
        else:
            self.items.mkdir(exist_ok=True)
            tmp = record.with_suffix(".tmp")
            tmp.write_text(json.dumps(run, indent=2, sort_keys=True))
            tmp.replace(record)
        for stray in self.items.glob("*.tmp"):
            stray.unlink()  # an item that was being written when the run died
        done = 0
        while self._path(done).is_file():
            done += 1
        return done

    def _path(self, index: int) -> Path:
        return self.items / f"{index:06d}.pkl"

    def saved(self) -> set[int]:
        """The indices of the items finished so far, in any order."""
        return {int(p.stem) for p in self.items.glob("*.pkl")}

    def save(self, index: int, item: object) -> None:
        path = self._path(index)
        tmp = path.with_suffix(".tmp")
        with open(tmp, "wb") as f:
            pickle.dump(item, f, protocol=pickle.HIGHEST_PROTOCOL)
            faults.point(f"save:{index}")
        tmp.replace(path)

    def load(self, index: int) -> Any:
        with open(self._path(index), "rb") as f:
            return pickle.load(f)

    def episodes(self, n: int) -> Iterator[Any]:
        for i in range(n):
            yield self.load(i)

    def fresh_dataset(self) -> Path:
        """An empty folder to assemble into (whatever a killed assembly left is discarded)."""
        shutil.rmtree(self.dataset, ignore_errors=True)
        (self.dataset / "meta").mkdir(parents=True)
        return self.dataset

    def publish(self) -> None:
        publish(self.dataset, self.out)
        self.finish()

    def finish(self) -> None:
        """The product is at `out`: the partial run goes, and its lock with it."""
        shutil.rmtree(self.root)
        self.release()

    def release(self) -> None:
        if self._lock is not None:
            os.close(self._lock)
            self._lock = None


UNSET = object()


def changes(before: dict, now: dict, prefix: str = "") -> list[str]:
    """What differs between two run records, option by option (a nested record's by dotted key), an
    option on one side only included: `key was X, now Y`."""
    found = []
    for key in sorted(set(before) | set(now)):
        old, new = before.get(key, UNSET), now.get(key, UNSET)
        if old == new:
            continue
        if isinstance(old, dict) and isinstance(new, dict):
            found += changes(old, new, f"{prefix}{key}.")
        else:
            found.append(f"{prefix}{key} was {_shown(old)}, now {_shown(new)}")
    return found


def _shown(value: Any) -> str:
    """A recorded value, briefly: long lists by their ends and length, long texts by their start and length."""
    if value is UNSET:
        return "unset"
    if isinstance(value, list) and len(value) > 4:
        return f"[{_shown(value[0])}, {_shown(value[1])}, ..., {_shown(value[-1])}] ({len(value)} items)"
    text = json.dumps(value, sort_keys=True)
    if len(text) > 40:
        return f"{text[:30]}... ({len(value) if isinstance(value, str) else len(text)} characters)"
    return text


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
