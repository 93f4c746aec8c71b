"""One process at a time: an exclusive lock on a file, held across processes (two experiment
processes on one `out`, or pytest's two workers, that both need the same product)."""

from __future__ import annotations

import fcntl
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def held(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on `path` (made, with its folder, if missing) until the block ends; a
    process that asks while another holds it waits. The kernel releases it however its holder ends."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
