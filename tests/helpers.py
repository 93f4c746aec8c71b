"""Helpers shared by the tests (importable because pytest puts tests/ on the path)."""

from __future__ import annotations

from pathlib import Path

from gen.config import parse
from gen.run import generate


def make_dataset(out: Path, *overrides: str) -> Path:
    """Generate a dataset through the real CLI config and pipeline."""
    generate(parse([f"out={out}", *overrides]), progress=False)
    return out
