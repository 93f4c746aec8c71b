"""A bad referent spec file gets one line naming the field, before anything is simulated."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from referents.registry import HERE

BASE = yaml.safe_load((HERE / "color.yaml").read_text())


def _write(tmp_path: Path, data: dict) -> Path:
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _gen(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "gen", *args], capture_output=True, text=True)


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda d: d.pop("templates"), "templates: missing field"),
        (lambda d: d.pop("naming"), "naming: missing field"),
        (
            lambda d: d["objects"][0]["attributes"].update(color=["red", "mauve"]),
            "objects[0].attributes.color: unknown color 'mauve'",
        ),
        (lambda d: d["objects"][0].update(kind="spaceship"), "objects[0].kind: unknown kind 'spaceship'"),
        (lambda d: d.update(objects_per_scene=9), "objects_per_scene: 9 objects cannot fit in the 6 slots"),
        (lambda d: d["layout"]["slots"].append([0.9, 0.0]), "layout.slots[6]: (0.9, 0.0) is off the workspace of world native"),
        (lambda d: d.update(holdout=["chartreuse"]), "holdout: 'chartreuse' names no object"),
        (lambda d: d.update(confound="lighting"), "confound: unknown confound 'lighting'"),
    ],
)
def test_bad_spec_named_in_one_line(tmp_path: Path, edit, field: str) -> None:
    data = yaml.safe_load(yaml.safe_dump(BASE))
    edit(data)
    out = tmp_path / "out"
    result = _gen(f"spec={_write(tmp_path, data)}", "referent=color", f"out={out}", "n=4")
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0], result.stderr
    assert not out.exists()


def test_too_few_values_for_a_scene(tmp_path: Path) -> None:
    data = yaml.safe_load(yaml.safe_dump(BASE))
    data["objects"] = [{"kind": "block", "name": "block", "attributes": {"color": ["red", "blue"]}}]
    result = _gen(f"spec={_write(tmp_path, data)}", f"out={tmp_path / 'out'}", "n=4")
    assert result.returncode == 2 and "objects: needs 4 different color values per scene, has 2" in result.stderr


def test_plan_only_writes_records_and_audit(tmp_path: Path) -> None:
    out = tmp_path / "plan"
    result = _gen("referent=relation", "n=300", "plan_only=true", f"out={out}")
    assert result.returncode == 0, result.stderr
    assert "confound audit: no leak" in result.stdout
    assert sorted(p.name for p in (out / "meta").iterdir()) == ["audit.json", "generation.json", "scenes.parquet"]
    assert not (out / "data").exists()
    confounded = _gen("referent=object", "n=300", "plan_only=true", "confound=position", f"out={tmp_path / 'conf'}")
    assert confounded.returncode == 0 and "leak: slot" in confounded.stdout
