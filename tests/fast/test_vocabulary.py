"""`targets=`, `distractor_only=` and `holdout=` do what they say for every built-in referent type,
or are refused in one line: an option recorded in a dataset's or exam's metadata but not applied
to its plan would be a lie. Planning only (no simulator)."""

from __future__ import annotations

import pytest

from gen.planning.plan import default_setup, plan
from referents.registry import Referent, available, load
from referents.schema import ReferentSpecError

N = 24


def _planned(referent: Referent, seed: int = 3) -> list[tuple[str, set[str]]]:
    """Each planned episode's target value and the values of everything it could have asked for."""
    out = []
    for spec in plan(referent, N, seed, default_setup(referent)):
        values = {a.id: a.value for a in referent.alternatives(spec)}
        out.append((values[referent.answer(spec)], set(values.values())))
    return out


def _a_value(name: str) -> str:
    """A value the type names targets by, the one its first planned episode asks for."""
    return _planned(load(name))[0][0]


@pytest.mark.parametrize("name", available())
def test_targets_and_distractor_only_are_applied_or_refused(name: str) -> None:
    value = _a_value(name)
    try:
        only = _planned(load(name, overrides={"targets": [value]}))
    except ReferentSpecError as exc:  # refused in one line, naming the option
        assert "targets" in str(exc) and "\n" not in str(exc)
    else:
        assert {target for target, _ in only} == {value}, f"targets=[{value}] not applied"
    try:
        never = _planned(load(name, overrides={"distractor_only": [value]}))
    except ReferentSpecError as exc:
        assert "distractor_only" in str(exc) and "\n" not in str(exc)
    else:
        assert all(target != value for target, _ in never), f"distractor_only=[{value}] not applied"
        assert any(value in seen for _, seen in never), f"distractor_only=[{value}] never shows {value!r} at all"


@pytest.mark.parametrize("name", available())
def test_holdout_keeps_a_value_out_or_is_refused(name: str) -> None:
    value = _a_value(name)
    try:
        held = _planned(load(name, overrides={"holdout": [value]}))
    except ReferentSpecError as exc:
        assert "holdout" in str(exc) and "\n" not in str(exc)
    else:
        assert all(value not in seen for _, seen in held), f"holdout=[{value}] still appears"


def test_libero_spatial_takes_its_places_as_the_card_lists_them() -> None:
    """Its card lists places as the values that name a bowl: an exam of held-out places can be made."""
    only = _planned(load("libero_spatial", overrides={"targets": ["on the stove"]}))
    assert {target for target, _ in only} == {"on the stove"}
    held = _planned(load("libero_spatial", overrides={"holdout": ["next to the plate"]}))
    assert all("next to the plate" not in seen for _, seen in held)
    never = _planned(load("libero_spatial", overrides={"distractor_only": ["at the table center"]}))
    assert all(t != "at the table center" for t, _ in never) and any("at the table center" in s for _, s in never)


def test_libero_goal_holds_out_a_place_and_names_what_it_accepts() -> None:
    held = load("libero_goal", overrides={"holdout": ["stove"]})
    specs = plan(held, N, 0, default_setup(held))
    assert all(o.name != "stove" for spec in specs for o in spec.objects)
    with pytest.raises(ReferentSpecError) as refused:
        load("libero_goal", overrides={"targets": ["sink"]})
    accepts = (
        "bowl, cabinet, cream cheese, front of the stove, middle drawer, plate, rack, stove, stove knob, top drawer, wine bottle"
    )
    assert f"'sink' names no object of this referent; it accepts: {accepts}" in str(refused.value)
