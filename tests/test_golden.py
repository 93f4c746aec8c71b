"""The generator's output is pinned byte for byte: refactors must not change a single byte.

The hashes were recorded with the code as it stood before the package restructuring (commit
2f5bc96); the same options and seed must give the same data parquet, videos and scene records.
A change that means to alter the output updates them in the same commit and says why.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from helpers import make_dataset

CASES = {
    "object": ("referent=object", "n=2", "image_size=32", "seed=3", "workers=1"),
    "goal": ("referent=goal", "n=2", "image_size=32", "seed=3", "workers=1"),
    "exam": ("referent=object", "split=exam", "n=2", "image_size=32", "seed=3", "workers=1"),
}
SHA256 = {  # first 40 hex digits of each file's sha256
    "object": {
        "data/chunk-000/file-000.parquet": "981d10232e2cf95345e6c7add7c299e43e27f5ae",
        "meta/episodes/chunk-000/file-000.parquet": "a1a71da3bb8ac17bf49f94b094ff2af0df7fb6c2",
        "meta/scenes.parquet": "27cd44eb4f00eaccb64beb2e648701554123d1de",
        "videos/observation.images.agentview/chunk-000/file-000.mp4": "319b232b4ab427be382cf9b801db0393df29d978",
        "videos/observation.images.wrist/chunk-000/file-000.mp4": "e3e9fec80a4d7333ee814ddf33bcae000ef3913f",
    },
    "goal": {
        "data/chunk-000/file-000.parquet": "59680dd35e33fb3d75d3d6668f78ae5f6aec5a56",
        "meta/episodes/chunk-000/file-000.parquet": "9efca67f9dbecbc0629828313198fc38d43cfe49",
        "meta/scenes.parquet": "ebf9d08f2aeb6712f49ee9bf1aac2e428d040df5",
        "videos/observation.images.agentview/chunk-000/file-000.mp4": "1fdefa321c70a1ccba0fc3e5e158d64329bc117b",
        "videos/observation.images.wrist/chunk-000/file-000.mp4": "d1208cec7bb846bc22ed4faadce5f4b93bf2c051",
    },
    "exam": {
        "trials.parquet": "1e2593577e589c95ba509472641aa8c2ed0f9fc9",
    },
}


@pytest.mark.parametrize("case", CASES)
def test_output_bytes_are_unchanged(case: str, tmp_path: Path) -> None:
    root = make_dataset(tmp_path / case, *CASES[case])
    got = {rel: hashlib.sha256((root / rel).read_bytes()).hexdigest()[:40] for rel in SHA256[case]}
    assert got == SHA256[case]
