"""Byte digests of what the generator writes for a fixed list of commands: every native type and
every LIBERO world (dataset, exam, plan), the other types in LIBERO's scenes, canonical exams and a
mix, at fixed seeds and small sizes.

    python scripts/digests.py <digests.json> [only=<name>,...]

The products are made by the checkout this script is in (its folder on PYTHONPATH), so a worktree
of another commit digests that commit's. Run it before and after a change that must not alter any
product (a refactor), then compare: `python scripts/digests.py --compare before.json after.json`
lists every file that differs. Each
command runs in a fresh folder with a relative `out`, so the records that name it agree; a run's
wall time and the spec file's absolute path (meta/generation.json, exam.json) are left out of its
digest.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

NATIVE = ("object", "color", "category", "ordinal", "relation", "negation", "composition", "goal", "verb")
LIBERO_TYPES = ("libero_object", "libero_spatial", "libero_goal")
IN_LIBERO = (("color", "libero_spatial"), *((t, "libero_object") for t in ("category", "negation", "composition", "ordinal")))
SMALL = ("n=2", "image_size=32", "seed=3", "workers=1")
ROOT = Path(__file__).resolve().parents[1]  # the checkout whose generator runs (a worktree of another commit, say)


def commands() -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for name in (*NATIVE, *LIBERO_TYPES):
        out[f"{name}-dataset"] = ["gen", f"referent={name}", *SMALL]
        out[f"{name}-exam"] = ["gen", f"referent={name}", "split=exam", *SMALL]
        out[f"{name}-plan"] = ["gen", f"referent={name}", "n=20", "seed=3", "plan_only=true"]
    for name, world in IN_LIBERO:
        out[f"{name}@{world}-dataset"] = ["gen", f"referent={name}", f"world={world}", *SMALL]
        out[f"{name}@{world}-plan"] = ["gen", f"referent={name}", f"world={world}", "n=20", "seed=3", "plan_only=true"]
    for world in LIBERO_TYPES:
        out[f"{world}-canonical"] = ["gen.canonical", f"world={world}", "states=1", "tasks=2", "image_size=32"]
    out["libero_object_lan-canonical"] = ["gen.canonical", "suite=libero_object_lan", "states=1", "tasks=2", "image_size=32"]
    out["mix"] = ["gen", "referent=[object@libero_object,color@libero_spatial]", *SMALL]
    return out


def _digest(path: Path) -> str:
    data = path.read_bytes()
    if path.name == "exam.json":  # where the spec file lies is the checkout's, not the exam's
        record = json.loads(data)
        (record.get("referent_spec") or {}).pop("path", None)
        data = json.dumps(record, sort_keys=True).encode()
    if path.name == "generation.json":  # what differs between identical runs, or machines
        record = json.loads(data)
        record.pop("seconds", None)
        spec = record.get("referent_spec") or {}
        for one in [spec, *(v for v in spec.values() if isinstance(v, dict) and "path" in v)]:
            one.pop("path", None)
        data = json.dumps(record, sort_keys=True).encode()
    return hashlib.sha256(data).hexdigest()[:40]


def digests(only: set[str] | None = None) -> dict[str, dict[str, str]]:
    found = {}
    for name, argv in commands().items():
        if only and name not in only:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            env = {**os.environ, "PYTHONPATH": str(ROOT)}
            argv = [sys.executable, "-m", *argv, f"out=products/{name}"]
            done = subprocess.run(argv, cwd=tmp, capture_output=True, text=True, env=env)
            if done.returncode:
                found[name] = {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else str(done.returncode)}
                continue
            root = Path(tmp) / "products" / name
            found[name] = {str(p.relative_to(root)): _digest(p) for p in sorted(root.rglob("*")) if p.is_file()}
        print(f"{name}: {len(found[name])} files", file=sys.stderr)
    return found


def compare(before: dict, after: dict) -> list[str]:
    differ = []
    for name in sorted(set(before) | set(after)):
        a, b = before.get(name, {}), after.get(name, {})
        for file in sorted(set(a) | set(b)):
            if a.get(file) != b.get(file):
                differ.append(f"{name}/{file}: {a.get(file, 'missing')} -> {b.get(file, 'missing')}")
    return differ


def main(argv: list[str]) -> int:
    if argv[:1] == ["--compare"]:
        before, after = (json.loads(Path(p).read_text()) for p in argv[1:3])
        differ = compare(before, after)
        print("\n".join(differ) or f"the same bytes: {sum(map(len, before.values()))} files of {len(before)} products")
        return 1 if differ else 0
    only = {n for a in argv[1:] if a.startswith("only=") for n in a.removeprefix("only=").split(",")}
    Path(argv[0]).write_text(json.dumps(digests(only or None), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
