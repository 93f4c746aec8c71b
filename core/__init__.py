"""The simulator-free core at the bottom of the import graph.

Plain data and pure functions every other layer speaks: the episode spec (`spec`), the
recorded features (`layout`), the fixed world (`world`), the object catalog (`catalog`), the
contact geometry (`contact`) and success predicates (`success`), the exam format (`exam`),
rates with intervals (`rates`) and parquet reading (`parquet`), and where caches live. Nothing here imports MuJoCo,
robosuite or mink, nor any package above it (referents, oracle, gen, eval, train).
"""

import os
from pathlib import Path

__version__ = "0.1.0"


def cache_dir() -> Path:
    """Where derived files (decimated meshes, decoded frames) are kept between runs (XDG-aware)."""
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "deconfound"
