"""Every referent type: balanced roles, counterfactuals that name something else, objects in
view, success that a do-nothing rollout cannot reach, and a clean confound audit."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from core import worlds
from core.programs import succeeded
from core.spec import EpisodeSpec
from gen.planning.audit import audit
from gen.planning.plan import default_setup, plan
from helpers import visible_bodies
from oracle.episode import replay
from oracle.scene import scene_for
from referents import registry

TYPES = registry.available()


def test_all_nine_types_exist_and_each_world_has_its_own() -> None:
    native = {"object", "color", "category", "ordinal", "relation", "negation", "composition", "goal", "verb"}
    assert set(registry.of_world("native")) == native
    libero_types = {"libero_object": "libero_object", "libero_spatial": "libero_spatial", "libero_goal": "libero_goal",
                    "libero_10": "libero_10_living_room"}  # fmt: skip
    assert set(TYPES) == native | set(libero_types)
    assert all(registry.of_world(world) == [t] for t, world in libero_types.items())


@pytest.fixture(scope="module", params=TYPES)
def planned(request: pytest.FixtureRequest) -> tuple[registry.Referent, list[EpisodeSpec]]:
    ref = registry.load(request.param)
    return ref, plan(ref, 300, seed=1, setup=default_setup(ref))


def test_every_value_is_target_and_distractor_across_slots(planned: tuple) -> None:
    ref, specs = planned
    table = audit(ref, specs)["balance"]
    world = worlds.world(ref.config.world)
    furniture = {c.name for c in ref.config.objects if world.kind(c.kind).is_site}  # places that never move
    placed = ref.config.naming == "relation"  # values that are places (LIBERO-Spatial's): one slot each, by definition
    # values asked where nothing else could be (LIBERO-Goal's knob, the front of its stove: a motion with one place)
    alone = {alts[0].value for alts in map(ref.alternatives, specs) if len(alts) == 1}
    assert len(table) >= 2
    for value, roles in table.items():
        assert sum(roles["target"].values()) > 0, f"{value} is never the target"
        assert sum(roles["distractor"].values()) > 0 or value in alone, f"{value} is never a distractor"
        assert len(roles["target"]) >= 2 or value in furniture or placed, f"{value} is the target in only one slot"
    # within scenes of one size, every value is the answer about equally often (of any goal: LIBERO-10's
    # "put both" brings the shorter grocery first, whichever it names first)
    by_size: dict[int, Counter] = {}
    for s in (goal for spec in specs for goal in spec.goals()):
        alts = ref.alternatives(s)
        answer = next(a.value for a in alts if a.id == ref.answer(s))
        by_size.setdefault(len(alts), Counter())[answer] += 1
    for counts in by_size.values():
        assert max(counts.values()) - min(counts.values()) <= 2, counts


def test_audit_finds_no_leak(planned: tuple) -> None:
    ref, specs = planned
    report = audit(ref, specs)
    assert report["verdict"] == "no leak", [v for v in report["variables"] if v["leak"]]
    assert {"slot", "identity"} <= {v["variable"].split(" and ")[0] for v in report["variables"]}


def test_counterfactuals_ask_for_something_else_in_the_scene(planned: tuple) -> None:
    """Every episode's swaps ask for something else in its scene; only an ask with nothing else it
    could name (LIBERO-Goal's "turn on the stove") has none."""
    ref, specs = planned
    for s in specs:
        ids = {o.id for o in s.objects}
        assert s.target in ids and (s.counterfactuals or len(ref.alternatives(s)) == 1)
        choices = {s.choice(c) for c in s.counterfactuals}
        assert s.choice() not in choices
        for c in s.counterfactuals:
            assert c.target in ids and c.instruction != s.instruction
            assert c.changed[0] != c.changed[1]


@pytest.mark.parametrize("name", TYPES)
def test_all_objects_in_view_and_do_nothing_fails(name: str) -> None:
    ref = registry.load(name)
    setup = default_setup(ref)
    scene = scene_for(ref.assets(), setup.profile, setup.world)
    for spec in plan(ref, 3, seed=4, setup=setup):
        scene.reset(spec)
        visible = visible_bodies(scene, "agentview")
        for obj in spec.objects:
            bodies = {int(scene.model.geom_bodyid[g]) for g in scene.placed[obj.id].geom_ids}
            assert sum(visible.get(b, 0) for b in bodies) >= 8, f"{name}: {obj.id} not visible"
        still = np.tile(setup.interface.hold_action(setup.robot_home), (30, 1))
        outcome = replay(scene, spec, still)
        assert not succeeded(spec, outcome)
        for cf in spec.counterfactuals:
            assert not succeeded(spec, outcome) and not _achieved(spec, outcome, cf)


def _achieved(spec: EpisodeSpec, outcome, cf) -> bool:
    from core.programs import achieved

    return achieved(spec, outcome, *spec.choice(cf))


def test_position_confound_is_flagged() -> None:
    ref = registry.load("object", overrides={"confound": "position"})
    specs = plan(ref, 200, seed=0, setup=default_setup(ref))
    assert {s.object(s.target).slot for s in specs} == {ref.config.layout.canonical_slot}
    report = audit(ref, specs)
    assert "slot" in report["leaks"] and report["verdict"].startswith("leak: ")
    assert not report["unexpected_leaks"]


def test_holdout_and_distractor_only() -> None:
    ref = registry.load("color", overrides={"holdout": ["purple"], "distractor_only": ["orange"]})
    specs = plan(ref, 120, seed=0, setup=default_setup(ref))
    colors = Counter(o.attributes["color"] for s in specs for o in s.objects)
    targets = Counter(s.object(s.target).attributes["color"] for s in specs)
    assert "purple" not in colors
    assert colors["orange"] > 0 and targets["orange"] == 0
    report = audit(ref, specs)
    assert report["vocabulary"] == {"holdout": ["purple"], "distractor_only": ["orange"], "targets": []}
    assert not report["unexpected_leaks"]


def test_restricted_targets_make_every_identity_leak_expected() -> None:
    """Families are declared with the features: the co-appearing categories of a category scene
    are identity, though no word in their name says so."""
    ref = registry.load("category", overrides={"targets": ["toy"]})
    report = audit(ref, plan(ref, 120, seed=0, setup=default_setup(ref)))
    leaked = {v["variable"]: v["expected"] for v in report["variables"] if v["leak"]}
    assert {"identity", "co-appearing categories"} <= set(leaked) and all(leaked.values())
    assert not report["unexpected_leaks"]


def test_unsupported_confound_is_refused() -> None:
    with pytest.raises(ValueError, match="confound"):
        registry.load("ordinal", overrides={"confound": "position"})


def test_tiny_plans_get_no_verdict() -> None:
    ref = registry.load("object")
    report = audit(ref, plan(ref, 5, seed=5, setup=default_setup(ref)))
    assert report["verdict"].startswith("too few episodes") and not report["leaks"]
