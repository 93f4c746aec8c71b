"""The category axis on LIBERO-Object's floor (`referent=category world=libero_object`): the
category type's own design, LIBERO's groceries and basket brought by the world's spec
(referents/in_worlds/libero_object/category.yaml), against LIBERO's own environment as the
LIBERO-Object world is (tests/test_libero_world.py): recorded actions that LIBERO's
`check_success()` accepts, the audit, lerobot's loader, and the exam's reference policies."""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset  # before any GL context (README: torchvision)

import referents
from core import worlds
from core.exam import read
from eval.battery import take
from eval.registry import make
from gen import scenes
from gen.plan import default_sim, plan
from helpers import liberos_own, liberos_replay, make_dataset

WORLD = "libero_object"
OPTIONS = ("referent=category", f"world={WORLD}")


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_dataset(tmp_path_factory.mktemp("category") / "ds", *OPTIONS, "n=6", "image_size=64", "seed=1", "workers=2")


def test_the_axis_is_the_category_types_design_in_liberos_scene() -> None:
    """Every category is asked for equally often, one grocery of each category stands in each
    scene, the basket in LIBERO's bin region, and every target is carried into it; the plan's
    audit finds no leak."""
    referent = referents.load("category", world=WORLD)
    assert referent.name == "category" and referent.config.world == WORLD
    specs = plan(referent, 60, 0, default_sim(referent))
    asked = Counter(spec.object(spec.target).attributes["category"] for spec in specs)
    assert set(asked.values()) == {20} and len(asked) == 3
    for spec in specs:
        groceries = [o for o in spec.objects if o.kind != "basket"]
        assert sorted(o.attributes["category"] for o in groceries) == sorted(asked)
        assert spec.task.program == "pick_place" and spec.object(spec.task.params["destination"]).kind == "basket"
    from gen.audit import audit

    assert not audit(referent, specs)["leaks"]


def test_the_object_axis_in_liberos_world_is_libero_object() -> None:
    """`referent=object world=libero_object` is what `referent=libero_object` makes."""
    alias, own = referents.load("object", world=WORLD), referents.load("libero_object")
    assert plan(alias, 12, 3, default_sim(alias)) == plan(own, 12, 3, default_sim(own))


def test_recorded_actions_succeed_in_liberos_own_environment(dataset: Path, tmp_path: Path) -> None:
    """Each episode rebuilt in LIBERO's environment from its record alone: LIBERO's `check_success()`
    (the grocery In the basket) accepts the recorded actions (the README's figure is n=20)."""
    request = liberos_replay(dataset, worlds.world(WORLD))
    results = json.loads(liberos_own("replay", request, tmp_path / "replay.json").read_text())
    succeeded = sum(r["success"] for r in results)
    assert len(results) == 6 and succeeded >= 5, f"LIBERO's check_success() accepted {succeeded}/6"


def test_lerobot_reads_it_and_the_written_audit_finds_no_leak(dataset: Path) -> None:
    ds = LeRobotDataset("local/category", root=dataset)
    assert ds.meta.total_episodes == 6
    record = json.loads(scenes.read(dataset)["scene"].iloc[0])
    assert record["world"] == WORLD and {o["kind"] for o in record["objects"]} >= {"basket"}
    audit = json.loads((dataset / "meta/audit.json").read_text())["written"]
    assert not audit["leaks"], audit["verdict"]
    doctor = Path(sys.executable).with_name("lerobot-doctor")
    report = json.loads(subprocess.run([str(doctor), "check", str(dataset), "--json"], capture_output=True, text=True).stdout)
    assert not [m for c in report["checks"] for m in c["messages"] if m["severity"] == "FAIL"]


def test_its_exam_separates_the_reference_policies(tmp_path: Path) -> None:
    """The oracle does the task and obeys every swap; `position` obeys at chance; `nothing` scores 0."""
    exam = read(make_dataset(tmp_path / "exam", *OPTIONS, "n=4", "split=exam", "image_size=32", "seed=2"))
    faces = {
        p: take(exam, exam.trials, make(p), tmp_path / p, workers=2, policy_name=p, baseline=False)[0]["faces"]
        for p in ("oracle", "position")
    }
    assert faces["oracle"]["task"]["rate"] == 1.0 and faces["oracle"]["obeyed_name"]["rate"] == 1.0
    obeyed = faces["position"]["obeyed_name"]
    assert obeyed["ci"][0] <= obeyed["chance"] <= obeyed["ci"][1]
    one = exam.trials[exam.trials["trial"] == 0]  # `nothing` runs every row to its horizon: one trial is enough
    nothing = take(exam, one, make("nothing"), tmp_path / "nothing", policy_name="nothing", baseline=False)[0]["faces"]
    assert all(f["k"] == 0 for f in nothing.values())
