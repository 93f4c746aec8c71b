"""The episode spec: plain, versioned, hashable data that round-trips through JSON."""

from __future__ import annotations

import json

import pytest

from core.spec import EpisodeSpec, Setup, SpecError
from gen.planning.plan import plan
from referents import registry


@pytest.fixture(scope="module")
def specs() -> list[EpisodeSpec]:
    return plan(registry.load("object"), 12, seed=3, setup=Setup())


def test_json_round_trip_is_exact(specs: list[EpisodeSpec]) -> None:
    for spec in specs:
        again = EpisodeSpec.from_json(spec.to_json())
        assert again == spec
        assert again.hash == spec.hash
        assert again.to_json() == spec.to_json()


def test_hash_tracks_content(specs: list[EpisodeSpec]) -> None:
    assert len({s.hash for s in specs}) == len(specs)
    data = json.loads(specs[0].to_json())
    data["instruction"] = "pick up the other thing"
    changed = EpisodeSpec.from_dict(data)
    assert changed.hash != specs[0].hash
    assert changed.scene_hash == specs[0].scene_hash  # same objects and poses


def test_version_and_shape_are_checked(specs: list[EpisodeSpec]) -> None:
    data = json.loads(specs[0].to_json())
    with pytest.raises(SpecError, match="version 99"):
        EpisodeSpec.from_dict({**data, "version": 99})
    del data["objects"]
    with pytest.raises(SpecError, match="objects"):
        EpisodeSpec.from_dict(data)
    with pytest.raises(SpecError, match="not valid JSON"):
        EpisodeSpec.from_json("{nope")


@pytest.mark.parametrize("name", ["libero_spatial", "libero_goal"])
def test_a_libero_scene_record_names_every_fixture_and_its_pose(name: str) -> None:
    """The cabinet, the stove, the rack: an episode is rebuilt in LIBERO's environment from its record alone."""
    from core import worlds
    from gen.planning.plan import default_setup, plan
    from referents.registry import load

    referent = load(name)
    record = plan(referent, 1, 0, default_setup(referent))[0].scene_record()
    world = worlds.world(referent.config.world)
    assert {f["instance"]: f["pos"] for f in record["fixtures"]} == {f.name: list(f.pos) for f in world.fixtures}
    assert {"wooden_cabinet_1", "flat_stove_1"} <= {f["instance"] for f in record["fixtures"]}
    assert all(len(f["quat"]) == 4 and f["kind"] for f in record["fixtures"])
