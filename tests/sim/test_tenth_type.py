"""A tenth referent type, added without touching the package: a spec file given by path brings
its module beside it, and the real pipeline generates it, in this process and in worker
processes. A module that strays from the contract is refused at load, in one line."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from core import parquet, programs
from core.spec import Setup
from gen.planning.plan import designs, plan
from gen.products import scenes
from helpers import make_dataset
from referents import registry
from referents.schema import ReferentSpecError

SPEC = {
    "type": "size",
    "naming": "size",
    "objects_per_scene": 2,
    "objects": [
        {"kind": "block_small", "name": "block", "attributes": {"size": "small", "color": "red"}},
        {"kind": "block_large", "name": "block", "attributes": {"size": "big", "color": "red"}},
    ],
    "layout": {"slots": [[-0.09, -0.2], [-0.09, 0.0], [-0.09, 0.2], [0.09, -0.2], [0.09, 0.0], [0.09, 0.2]], "canonical_slot": 1},
    "templates": ["pick up the {size} {name}", "grab the {size} {name}"],
    "task": {"program": "pick"},
}
MODULE = '''"""Size referent: "the big block" / "the small block"."""

from referents.balance import Balance
from referents.compose import naming_design
from referents.design import Design
from referents.schema import ReferentConfig

CONFOUNDS = ("position",)


def design(cfg: ReferentConfig, balance: Balance) -> Design:
    return naming_design(cfg, balance)
'''


TYPO = "def alternative(cfg, spec):\n    return []\n\n\n"  # misspelt `alternatives`


def assets_def(inventory: list) -> str:
    return f"\n\ndef assets(cfg):\n    return {inventory!r}\n"


def tenth_type(folder: Path, module: str = MODULE, spec: dict | None = None) -> Path:
    """`size.yaml` and `size.py` side by side in `folder`; returns the spec's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "size.py").write_text(module)
    path = folder / "size.yaml"
    path.write_text(yaml.safe_dump(spec or SPEC))
    return path


def test_a_type_beside_its_spec_plans_and_its_demo_is_found_by_path(tmp_path: Path) -> None:
    path = tenth_type(tmp_path)
    ref = registry.load("ignored", str(path))
    specs = plan(ref, 8, seed=0, setup=Setup())
    assert {s.referent for s in specs} == {"size"} and "size" not in registry.available()
    assert {s.object(s.target).attributes["size"] for s in specs} == {"small", "big"}
    assert ref.assets() == (("block_large", 1), ("block_small", 1))
    assert registry.demo_of("size", path) is programs.perform
    with pytest.raises(registry.UnknownReferent, match="needs that file's path"):
        registry.demo_of("size")


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda m: m.replace("def design(", TYPO + "def design("), "size.py: alternative: not part"),
        (lambda m: m.replace("def design(", "def _design("), "size.py: design: missing"),
        (lambda m: m.replace('("position",)', '("lighting",)'), "size.py: CONFOUNDS: must be a tuple of position"),
        (lambda m: m + "\nimport nonexistent_module\n", "size.py: cannot import: ModuleNotFoundError"),
        (lambda m: m + assets_def([("spaceship", 1)]), "size.yaml: assets: unknown kind 'spaceship'"),
        (lambda m: m + assets_def([("block_small", 1)]), "size.yaml: objects: kind 'block_large' has no body"),
    ],
)
def test_a_module_outside_the_contract_is_refused_in_one_line(tmp_path: Path, edit, message: str) -> None:
    path = tenth_type(tmp_path, edit(MODULE))
    with pytest.raises(ReferentSpecError, match=re.escape(message)) as error:
        registry.load("size", str(path))
    assert "\n" not in str(error.value)


def test_a_scene_beyond_the_inventory_fails_before_simulating(tmp_path: Path) -> None:
    spec = {**SPEC, "objects": [*SPEC["objects"], {"kind": "block_small", "name": "block", "attributes": {"size": "tiny"}}]}
    path = tenth_type(tmp_path, MODULE + assets_def([("block_small", 1), ("block_large", 1)]), {**spec, "objects_per_scene": 3})
    ref = registry.load("size", str(path))
    with pytest.raises(ReferentSpecError, match="assets: a scene holds 2 'block_small' objects"):
        designs(ref, 4, seed=0)


def test_a_module_beside_the_spec_cannot_redefine_a_builtin_type(tmp_path: Path) -> None:
    path = tenth_type(tmp_path, MODULE, {**SPEC, "type": "object"})
    (tmp_path / "object.py").write_text(MODULE)
    with pytest.raises(ReferentSpecError, match="type: 'object' is a built-in type"):
        registry.load("object", str(path))


def test_the_command_line_names_the_stray_module_name(tmp_path: Path) -> None:
    path = tenth_type(tmp_path, MODULE.replace("def design(", TYPO + "def design("))
    result = subprocess.run([sys.executable, "-m", "gen", f"spec={path}", f"out={tmp_path / 'out'}", "n=4"], capture_output=True)
    lines = result.stderr.decode().strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and "alternative: not part of the referent type contract" in lines[0]


def test_the_pipeline_generates_a_tenth_type_with_and_without_workers(tmp_path: Path) -> None:
    path = tenth_type(tmp_path / "types")
    roots = [
        make_dataset(tmp_path / f"w{workers}", f"spec={path}", "n=4", "image_size=32", "seed=2", f"workers={workers}")
        for workers in (1, 2)
    ]
    for root in roots:
        records = scenes.read(root)
        assert len(records) == 4 and set(records["referent"]) == {"size"}
        assert set(records["instruction"].str.split().str[-2]) <= {"small", "big"}
    one, two = (parquet.read(root / "data") for root in roots)
    assert np.array_equal(np.stack(one["action"].to_numpy()), np.stack(two["action"].to_numpy()))
