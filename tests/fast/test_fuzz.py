"""Property-based tests: no option line and no spec file makes a traceback escape, and a
rejected input writes nothing."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from core.spec import Setup
from gen.config import GenConfig, parse
from gen.planning.audit import audit
from gen.planning.plan import designs, realize
from jobs.cli import UserError
from referents import registry
from referents.schema import ReferentSpecError

FUZZ = settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture])
KEYS = list(GenConfig.__dataclass_fields__) + ["nonsense", "lora.rank", "n.x", ""]
VALUES = st.one_of(
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from(["true", "false", "null", "[]", "[a,b]", "[red]", "{}", "object", "exam", "ray", "position", "h264", "1.5"]),
    st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=12),
)
OVERRIDE = st.one_of(st.tuples(st.sampled_from(KEYS), VALUES).map(lambda kv: f"{kv[0]}={kv[1]}"), st.text(max_size=15))


@FUZZ
@given(argv=st.lists(OVERRIDE, max_size=4))
def test_any_option_line_parses_or_fails_in_one_line(tmp_path: Path, argv: list[str]) -> None:
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        before = sorted(p.name for p in tmp_path.iterdir())
        try:
            parse(argv)
        except UserError as exc:
            assert str(exc) and "\n" not in str(exc).strip()
        assert sorted(p.name for p in tmp_path.iterdir()) == before, "parsing must not write"
    finally:
        os.chdir(cwd)


BASES = {name: yaml.safe_load(registry.spec_file(name).read_text()) for name in registry.available()}
JUNK = st.one_of(
    st.none(),
    st.integers(-5, 50),
    st.floats(allow_nan=True),
    st.text(max_size=8),
    st.lists(st.integers(-3, 9), max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


@st.composite
def mutated_specs(draw: st.DrawFn) -> dict:
    spec = yaml.safe_load(yaml.safe_dump(BASES[draw(st.sampled_from(sorted(BASES)))]))
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(sorted(spec) + ["extra", "holdout", "targets"]))
        action = draw(st.sampled_from(["drop", "junk", "nested"]))
        if action == "drop":
            spec.pop(key, None)
        elif action == "junk":
            spec[key] = draw(JUNK)
        elif (
            key == "objects"
            and isinstance(spec.get("objects"), list)
            and spec["objects"]
            and isinstance(spec["objects"][0], dict)
        ):
            spec["objects"][0][draw(st.sampled_from(["kind", "name", "attributes", "role"]))] = draw(JUNK)
        elif key == "layout" and isinstance(spec.get("layout"), dict):
            spec["layout"][draw(st.sampled_from(["slots", "jitter", "yaw", "canonical_slot"]))] = draw(JUNK)
    return spec


@FUZZ
@given(spec=mutated_specs())
def test_any_spec_file_plans_or_fails_naming_the_file(tmp_path: Path, spec: dict) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(spec))
    try:
        ref = registry.load("unused", str(path))
        plan = designs(ref, 6, seed=0)
        audit(ref, [realize(ref, d, i, 0, Setup(world=ref.config.world)) for i, d in enumerate(plan)])
    except (ReferentSpecError, registry.UnknownReferent) as exc:
        assert str(exc).startswith(str(path)) or "referent" in str(exc)
        assert "\n" not in str(exc).strip()


@pytest.mark.parametrize("text", ["", "- a\n- b", ":::", "type: [", "objects: 7"])
def test_unreadable_spec_text(tmp_path: Path, text: str) -> None:
    path = tmp_path / "spec.yaml"
    path.write_text(text)
    with pytest.raises(ReferentSpecError):
        registry.load("color", str(path))
