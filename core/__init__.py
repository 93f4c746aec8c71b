"""The simulator-free core at the bottom of the import graph.

Plain data and pure functions every other layer speaks: the episode spec (`spec`), the
recorded features (`layout`), the fixed world (`world`), the object catalog (`catalog`), the
contact geometry (`contact`) and success predicates (`success`), the exam format (`exam`),
rates with intervals (`rates`) and parquet reading (`parquet`), and where caches live. Nothing here imports MuJoCo,
robosuite or mink, nor any package above it (referents, oracle, gen, eval, train).
"""

import hashlib
import os
from collections.abc import Callable
from pathlib import Path

__version__ = "0.1.0"


def cache_dir() -> Path:
    """Where derived files (decimated meshes, decoded frames) are kept between runs (XDG-aware)."""
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "deconfound"


def derived_file(folder: str, source: Path, tag: str, suffix: str) -> Path:
    """Where a file derived from `source` is cached: keyed by the source's bytes and `tag`."""
    digest = hashlib.sha256(source.read_bytes()).hexdigest()[:24]
    return cache_dir() / folder / f"{digest}-{tag}{suffix}"


def keep(cache: Path, write: Callable[[Path], None]) -> bool:
    """`write` a cache file to a per-process temporary beside it, then rename it into place, so a
    worker never reads another's half-written file. False where it cannot be written: a cache only
    saves time, and an unwritable home must not stop a run."""
    try:
        cache.parent.mkdir(parents=True, exist_ok=True)
        tmp = cache.with_name(f"{cache.stem}.{os.getpid()}.tmp{cache.suffix}")
        write(tmp)
        tmp.replace(cache)
    except OSError:
        return False
    return True
