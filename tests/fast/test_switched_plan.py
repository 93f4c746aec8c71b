"""Switched episodes in a plan (`switched=`, gen/planning/switches.py): the share asked for, every
alternative as often the second target, the second targets audited, and the specs of episodes
that never switch unchanged."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

from core.spec import EpisodeSpec
from gen.config import parse
from gen.planning.plan import plan_and_audit
from gen.products import scenes
from gen.products.run import generate


def test_the_share_switches_and_every_alternative_is_as_often_the_second_target(tmp_path: Path) -> None:
    planned = plan_and_audit(parse([f"out={tmp_path / 'plan'}", "n=120", "switched=0.25", "plan_only=true"]))
    switched = [spec for spec in planned.specs if spec.switch is not None]
    assert len(switched) == 30
    seconds = [spec.after_switch() for spec in switched]
    assert all(s.target != first.target and s.instruction != first.instruction for s, first in zip(seconds, switched))
    by_object = Counter(s.target for s in seconds)
    by_slot = Counter(s.object(s.target).slot for s in seconds)
    layout = planned.shares[0].referent.config.layout
    assert len(by_object) == 6 and max(by_object.values()) - min(by_object.values()) <= 2, by_object
    assert len(by_slot) == len(layout.slots) and max(by_slot.values()) - min(by_slot.values()) <= 2, by_slot
    report = planned.shares[0].audit["switched"]
    assert report["episodes"] == 30 and report["unexpected_leaks"] == []
    unswitched = plan_and_audit(parse([f"out={tmp_path / 'plain'}", "n=120", "plan_only=true"]))
    kept = [a.to_json() == b.to_json() for a, b in zip(planned.specs, unswitched.specs) if a.switch is None]
    assert all(kept) and "switch" not in unswitched.specs[0].to_json()


def test_a_training_switch_comes_mostly_on_the_descent(tmp_path: Path) -> None:
    """oracle/episode.py `along`: a step in [1, the hand 2 cm from what it takes hold of], most of
    them from where an exam switches (the hand 10 cm off) on, drawn from the episode's seed and
    index alone: the same plan switches at the same steps, spread over the way."""
    from oracle.episode import along

    planned = plan_and_audit(parse([f"out={tmp_path / 'plan'}", "n=200", "switched=0.25", "plan_only=true"]))
    switched = [spec for spec in planned.specs if spec.switch is not None]
    steps = [along(spec, 24, 14) for spec in switched]
    assert all(1 <= step <= 24 for step in steps) and len(set(steps)) >= 12, steps
    descent = sum(step >= 14 for step in steps) / len(steps)
    assert 0.65 <= descent <= 0.95 and min(steps) < 14, (descent, steps)
    assert steps == [along(spec, 24, 14) for spec in switched] and along(switched[0], 1, 1) == 1


def test_a_plan_records_where_it_will_switch(tmp_path: Path) -> None:
    out = tmp_path / "plan"
    generate(parse([f"out={out}", "n=10", "switched=0.3", "plan_only=true"]), progress=False)
    records = scenes.read(out)
    marked = [json.loads(s) for s in records["switch"] if isinstance(s, str)]
    assert len(marked) == 3 and all(m["step"] is None and m["target"] and m["instruction"] for m in marked)
    specs = [EpisodeSpec.from_json(s) for s in records["spec"]]
    assert [s.switch is not None for s in specs] == [isinstance(s, str) for s in records["switch"]]
    audit = json.loads((out / "meta" / "audit.json").read_text())
    assert "switched" in json.dumps(audit)
