"""The code's shape: imports run one way, down, with no circle, and feature names live in one module."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

from core.profiles import PROFILES

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts/import_graph.py"
PACKAGES = ("core", "jobs", "referents", "oracle", "gen", "eval", "train", "bench")


def test_no_import_runs_upward_or_round_a_circle() -> None:
    result = subprocess.run([sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout


def test_the_architecture_page_shows_the_current_import_graph() -> None:
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import import_graph
    finally:
        sys.path.remove(str(SCRIPT.parent))
    assert import_graph.block(import_graph.imports()) in import_graph.PAGE.read_text()


def test_camera_names_and_feature_keys_live_only_in_the_profiles_module() -> None:
    """core/profiles.py names them; LIBERO's side (eval/sims/libero_env/), which imports numpy and
    LIBERO only, names LIBERO's own cameras."""
    names = set()
    for profile in PROFILES.values():
        names |= {*profile.cameras, *profile.cameras.values(), *profile.image_keys}
    found = []
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            if path == ROOT / "core/profiles.py" or (ROOT / "eval/sims/libero_env") in path.parents:
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {node.value!r}")
    assert not found, "\n".join(found)


def test_the_referents_page_shows_the_contract_as_the_code_writes_it() -> None:
    """The type contract is written once, in referents/contract.py (TypeModule); the docs render it."""
    sys.path.insert(0, str(SCRIPT.parent))
    try:
        import contract_doc
    finally:
        sys.path.remove(str(SCRIPT.parent))
    assert contract_doc.block() in contract_doc.PAGE.read_text()
    assert len(contract_doc.rows()) == len(__import__("referents.contract").contract.CONTRACT)
