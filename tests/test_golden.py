"""The generator's output is pinned byte for byte: refactors must not change a single byte.

The hashes were recorded with the code as it stood before the package restructuring (commit
2f5bc96); the same options and seed must give the same data parquet, videos and scene records.
A change that means to alter the output updates them in the same commit and says why: the
exam's files changed once, when exam format 2 split the answer key out of trials.parquet (the
rows' physics, initial states and horizons are the same).

Only the plan is the same on every machine: the episode specs and their scene records come from
seeded arithmetic alone. What the physics writes (actions, states, the oracle's retries, exam
horizons) is not: the same command at the same commit gave other data bytes on an AMD host
without AVX-512 than on the Intel and AMD hosts with it (MuJoCo's and numpy's floating point
follows the vector instructions they run on), while two runs on one host agree. So the plans
are pinned everywhere, the physics per CPU family where the family's hashes were recorded, and
on a family with none only same-seed determinism is checked (tests/test_dataset.py, and twice
here). Rendered pixels depend on the family too (Mesa's llvmpipe compiles its rasteriser for the
host's vector instructions): the videos and the per-episode image statistics in meta/episodes
are pinned per family the same way.

The videos changed once, on purpose: H.264 moved from crf to a constant quantiser (gen/video.py),
because x264's floating-point rate control gave different bytes for the same frames in one CI
run. Only this AMD family's videos could be re-recorded (no Intel host was at hand); the Intel
family keeps its per-episode records, and its videos are checked again once recorded there.
"""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import pytest

CASES = {
    "object": ("referent=object", "n=2", "image_size=32", "seed=3", "workers=1"),
    "goal": ("referent=goal", "n=2", "image_size=32", "seed=3", "workers=1"),
    "exam": ("referent=object", "split=exam", "n=2", "image_size=32", "seed=3", "workers=1"),
}
PLANS = {  # sha256 (first 40 hex digits) of the plan's meta/scenes.parquet (plan_only=true): the same everywhere
    "object": "7b392f9ff0356dd44e1b979da1d3f06b707d20b7",
    "goal": "f61b06f7b504df0a33d32f8bdde4ed81aec4da65",
}
SHA256 = {  # first 40 hex digits of each file's sha256, on the CPU families of PHYSICS_FAMILIES
    "object": {
        "data/chunk-000/file-000.parquet": "981d10232e2cf95345e6c7add7c299e43e27f5ae",
        "meta/scenes.parquet": "27cd44eb4f00eaccb64beb2e648701554123d1de",
    },
    "goal": {
        "data/chunk-000/file-000.parquet": "59680dd35e33fb3d75d3d6668f78ae5f6aec5a56",
        "meta/scenes.parquet": "ebf9d08f2aeb6712f49ee9bf1aac2e428d040df5",
    },
    "exam": {  # exam format 2 (the answer key moved to answers.parquet; trials.parquet is the policy's side)
        "trials.parquet": "02194649cf3731a68b8af8e684385d5d5fd4f194",
        "answers.parquet": "0c66b7ffe12b7fcdfc9249e8e49469f0243735f5",
    },
}
PHYSICS_FAMILIES = ("GenuineIntel avx512f amx_tile", "AuthenticAMD avx512f")  # where SHA256 was recorded (alike)
EPISODES, AGENTVIEW_MP4, WRIST_MP4 = (
    "meta/episodes/chunk-000/file-000.parquet",
    "videos/observation.images.agentview/chunk-000/file-000.mp4",
    "videos/observation.images.wrist/chunk-000/file-000.mp4",
)
RENDERED = {  # CPU family -> case -> rendered files' hashes
    "GenuineIntel avx512f amx_tile": {  # recorded at commit 2f5bc96; its videos were not re-recorded (see above)
        "object": {
            EPISODES: "a1a71da3bb8ac17bf49f94b094ff2af0df7fb6c2",
        },
        "goal": {
            EPISODES: "9efca67f9dbecbc0629828313198fc38d43cfe49",
        },
    },
    "AuthenticAMD avx512f": {  # on an AMD EPYC with AVX-512; videos re-recorded for the constant quantiser
        "object": {
            EPISODES: "a938e7ef68e594ce66e0396c3341cdcfcdad1475",
            AGENTVIEW_MP4: "bffd9dc3259c671eb200f6c99dfc20ab0821af47",
            WRIST_MP4: "90365546db22b46fc00333ab3854b698243b7bc5",
        },
        "goal": {
            EPISODES: "ff9e08358e660c1a10f5629f09db58f14ee9fc6f",
            AGENTVIEW_MP4: "b33f2fddfc8515a56ef376dd5361e691238b1dda",
            WRIST_MP4: "81de54e289e3a12b2bd558818e499ab54bac5687",
        },
    },
}


def cpu_family() -> str:
    """Vendor and the vector-instruction sets llvmpipe's code generation depends on."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return "unknown"
    vendor = next((line.split(":")[1].strip() for line in text.splitlines() if line.startswith("vendor_id")), "unknown")
    flags = set(next((line.split(":")[1].split() for line in text.splitlines() if line.startswith("flags")), []))
    return " ".join([vendor, *(f for f in ("avx512f", "amx_tile") if f in flags)])


def _hashes(root: Path, files: dict[str, str]) -> dict[str, str]:
    return {rel: hashlib.sha256((root / rel).read_bytes()).hexdigest()[:40] for rel in files}


@pytest.fixture(scope="module")
def outputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Each output made by the command itself, in a fresh process, as a user would run it."""
    base = tmp_path_factory.mktemp("golden")
    for case, options in CASES.items():
        made = subprocess.run([sys.executable, "-m", "gen", *options, f"out={base / case}"], capture_output=True, text=True)
        assert made.returncode == 0, made.stderr
    return {case: base / case for case in CASES}


@pytest.mark.parametrize("case", CASES)
def test_output_bytes_are_unchanged(case: str, outputs: dict[str, Path]) -> None:
    family = cpu_family()
    if family not in PHYSICS_FAMILIES:
        pytest.skip(f"no physics hashes recorded for CPU family {family!r}; its plans and determinism are checked")
    assert _hashes(outputs[case], SHA256[case]) == SHA256[case]


@pytest.mark.parametrize("case", PLANS)
def test_plans_are_unchanged_on_every_machine(case: str, tmp_path: Path) -> None:
    """The plan behind each case (specs, scene records, no physics) is the same bytes on any host."""
    options = [o for o in CASES[case] if not o.startswith(("image_size", "workers"))]
    made = subprocess.run(
        [sys.executable, "-m", "gen", *options, "plan_only=true", f"out={tmp_path}/plan"], capture_output=True, text=True
    )
    assert made.returncode == 0, made.stderr
    assert _hashes(tmp_path / "plan", {"meta/scenes.parquet": ""}) == {"meta/scenes.parquet": PLANS[case]}


def test_physics_is_deterministic_on_this_machine(outputs: dict[str, Path], tmp_path: Path) -> None:
    """Whatever the family, the same command on one host writes the same bytes twice."""
    made = subprocess.run(
        [sys.executable, "-m", "gen", *CASES["object"], f"out={tmp_path / 'again'}"], capture_output=True, text=True
    )
    assert made.returncode == 0, made.stderr
    files = {rel: "" for rel in SHA256["object"]}
    assert _hashes(tmp_path / "again", files) == _hashes(outputs["object"], files)


@pytest.mark.parametrize("case", ["object", "goal"])
def test_rendered_bytes_are_unchanged(case: str, outputs: dict[str, Path]) -> None:
    family = cpu_family()
    if family not in RENDERED:
        pytest.skip(f"no rendered hashes recorded for CPU family {family!r} (llvmpipe's pixels depend on it)")
    assert _hashes(outputs[case], RENDERED[family][case]) == RENDERED[family][case]
