"""Every repo path the README, docs/ and the code's text name exists: a moved module leaves no
reader looking for it under its old name."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# Named but not in the repo, each for its reason.
NOT_OURS = {
    "bench/libero": "a LeRobot repo id bench/compare.py gives its throwaway dataset",
    "bench/naive": "a LeRobot repo id bench/compare.py gives its throwaway dataset",
    "docs/checkpoints/libero_object-switch-lora": "written by python -m train.course",
    "docs/results_course.json": "written by python -m train.course",
    "docs/switch_course.png": "drawn by scripts/switch_picture.py once train.course has its checkpoint",
    "scripts/compute_norm_stats.py": "openpi's, run in its checkout (docs/GPU_RECIPE.md)",
    "scripts/train.py": "openpi's, run in its checkout (docs/GPU_RECIPE.md)",
    "scripts/serve_policy.py": "openpi's, run in its checkout (docs/GPU_RECIPE.md)",
    "tests/libero/test_libero_": "a pattern, test_libero_<name>.py (docs/ARCHITECTURE.md's checklists)",
    "core/worlds/libero_10_": "what LIBERO-10 will add (docs/ARCHITECTURE.md's checklists)",
    "tests/libero/test_libero_10.py": "what LIBERO-10 will add (docs/ARCHITECTURE.md's checklists)",
}
TEXT = (".py", ".md", ".yaml", ".toml", ".txt")


def _tracked() -> list[str]:
    return subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()


def named_paths() -> dict[str, set[str]]:
    """Each path-like word that starts with one of the repo's top folders -> the files naming it."""
    files = _tracked()
    tops = sorted({f.split("/")[0] for f in files if "/" in f} - {"datasets"})  # datasets/<name>: a command's output
    word = re.compile(rf"(?<![\w./-])((?:{'|'.join(map(re.escape, tops))})/[\w./*-]*[\w/*])")
    found: dict[str, set[str]] = {}
    for name in files:
        if name.endswith(TEXT) or name == "Makefile":
            for match in word.finditer((ROOT / name).read_text(errors="replace")):
                found.setdefault(match.group(1).rstrip("."), set()).add(name)
    return found


def test_every_named_path_exists() -> None:
    named = named_paths()
    assert len(named) > 100, "the scan found too few paths to mean anything"
    missing = {p: sorted(w) for p, w in named.items() if p not in NOT_OURS and not any(ROOT.glob(p))}
    assert not missing, f"{len(missing)} named paths do not exist: {missing}"
    assert set(NOT_OURS) <= set(named), f"no longer named, drop from NOT_OURS: {set(NOT_OURS) - set(named)}"
