"""`referent=libero_10`: LIBERO-10's "put both" in its living room, planned without a simulator:
two groceries named, each first, second and a distractor equally often in every slot; a swap per
distractor renaming one of the two names; both goals audited; LIBERO-10's own tasks laid out
(`canonical`) and what a policy that learnt them does (`shortcut`)."""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

from core import libero, worlds
from core.spec import THEN
from gen.planning.audit import audit
from gen.planning.plan import plan, world_setup
from referents import registry

N = 70  # 7 groceries x 5 slots x 2: every (grocery, slot) as first and as second


def _specs(n: int = N):  # noqa: ANN202
    referent = registry.load("libero_10")
    return referent, plan(referent, n, 0, world_setup(worlds.world(referent.config.world)))


def _second(spec) -> str:  # noqa: ANN001
    return spec.task.params[THEN][0]["target"]


def _named(spec) -> list[str]:  # noqa: ANN001
    """The two groceries' names in the order the instruction says them."""
    names = [spec.object(spec.target).name, spec.object(_second(spec)).name]
    return sorted(names, key=spec.instruction.index)


def _slots(spec) -> list[tuple[str, int]]:  # noqa: ANN001
    """(name, slot) of the two named, in the order the instruction says them."""
    slots = {o.name: o.slot for o in spec.objects}
    return [(name, slots[name]) for name in _named(spec)]


def test_each_grocery_is_first_second_and_distractor_equally_often_in_every_slot() -> None:
    referent, specs = _specs()
    groceries = [c.name for c in referent.config.objects if c.role != "destination"]
    first = Counter(_named(s)[0] for s in specs)
    second = Counter(_named(s)[1] for s in specs)
    assert set(first) == set(second) == set(groceries)
    assert max(first.values()) - min(first.values()) <= 2 and max(second.values()) - min(second.values()) <= 2
    slots = Counter((name, slot) for s in specs for name, slot in _slots(s)[:1])
    assert len(slots) >= 0.9 * 7 * 5, f"first named in {len(slots)} of 35 (grocery, slot) pairs"
    height = {o.id: worlds.kind(o.kind, s.setup.world).height for s in specs for o in s.objects}
    assert all(height[s.target] <= height[_second(s)] for s in specs), "the shorter is brought first"
    places = set(referent.config.extra["sites"].values())  # LIBERO's places for its other tasks, after the basket's
    assert {o.slot for s in specs for o in s.objects if o.kind == "basket"} == {min(places) - 1}


def test_a_swap_renames_one_of_the_two_names_and_each_distractor_once() -> None:
    _, specs = _specs(14)
    for spec in specs:
        named = {spec.target, _second(spec)}
        distractors = [o.id for o in spec.objects if o.id not in named and o.kind != "basket"]
        assert sorted(c.target for c in spec.counterfactuals) == sorted(distractors)
        assert sorted(c.goal for c in spec.counterfactuals) == [0, 1]
        for cf in spec.counterfactuals:
            old, new = cf.changed
            assert cf.instruction == spec.instruction.replace(old, new, 1) and cf.instruction != spec.instruction
            kept = spec.asking(cf.target, spec.task.program, cf.goal).goals()[1 - cf.goal]
            assert kept.target == (_second(spec) if cf.goal == 0 else spec.target), "the other goal is asked as it was"
    at = [g.task.params["at"] for g in specs[0].goals()]
    assert at[0] == [-v for v in at[1]] and any(at[0]), "the two stand side by side in the basket"


def test_both_goals_are_audited_and_a_leak_of_the_second_is_found() -> None:
    referent, specs = _specs()
    report = audit(referent, specs)
    assert report["verdict"] == "no leak" and report["episodes"] == N and report["goals"] == 2 * N
    leaky = [replace(s, task=replace(s.task, params={**s.task.params, THEN: [{**s.task.params[THEN][0], "target": _slot0(s)}]}))
             for s in specs]  # fmt: skip
    assert "slot" in audit(referent, leaky)["leaks"], "a second named always in slot 0 is a leak"


def _slot0(spec) -> str:  # noqa: ANN001
    """The grocery in slot 0, or the spec's second where none stands there."""
    return next((o.id for o in spec.objects if o.slot == 0 and o.id != spec.target), _second(spec))


def test_liberos_living_room_tasks_are_laid_out_and_the_shortcut_does_them() -> None:
    referent = registry.load("libero_10")
    laid = {}
    for task in libero.tasks("libero_10"):
        design = referent.code.canonical(referent.config, libero.problem("libero_10", task))
        if design is not None:
            laid[task[:18]] = laid.get(task[:18], []) + [
                (design.target, design.task.params[THEN][0]["target"], design.counterfactuals)
            ]
    assert {k: len(v) for k, v in laid.items()} == {"LIVING_ROOM_SCENE1": 1, "LIVING_ROOM_SCENE2": 2, "LIVING_ROOM_SCENE5": 1,
                                                    "LIVING_ROOM_SCENE6": 1}  # fmt: skip
    assert not laid["LIVING_ROOM_SCENE5"][0][2] and not laid["LIVING_ROOM_SCENE6"][0][2], "the mugs' tasks: no swap"
    ((first, second, swaps),) = laid["LIVING_ROOM_SCENE1"]
    assert (first, second) == ("alphabet_soup_1", "cream_cheese_1")
    assert [(c.target, c.goal, c.instruction) for c in swaps] == [
        ("tomato_sauce_1", 0, "put both the tomato sauce and the cream cheese box in the basket"),
        ("ketchup_1", 1, "put both the alphabet soup and the ketchup in the basket"),
    ]
    specs = _specs(28)[1]
    moved = [referent.shortcut(s) for s in specs]
    assert all(m.objects == s.objects for m, s in zip(moved, specs))
    assert sum(m.target == s.target and _second(m) == _second(s) for m, s in zip(moved, specs)) < len(specs) / 4
