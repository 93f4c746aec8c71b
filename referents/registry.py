"""Referent types: the ways an instruction can name its target.

Each type is one declarative spec (`<type>.yaml`, schema in `referents.schema`) and one small
module (`<type>.py`) that keeps to the contract in `referents.contract`:

* `design(config, balance) -> Design` — the balanced discrete choices of one episode (required);
* `demo(skills, spec)` — the oracle's plan (default: grasp the target and lift it);
* `alternatives(config, spec) -> list[Alternative]` — what the instruction chooses among, for
  the confound audit (default: every object in the scene);
* `answer(spec) -> str` — which alternative is right (default: the target object);
* `assets(config)` — the model inventory (default: one body per candidate of a kind, at most
  `objects_per_scene`);
* `validate(config)` — type-specific checks of the spec (default: none);
* `shortcut(config, spec) -> EpisodeSpec` — what an instruction-blind policy does in a scene,
  which the `position` reference policy demonstrates (default: pick up whatever stands nearest
  the canonical slot);
* `named_place(config, spec, named) -> EpisodeSpec` — what a policy does that reads the name only as
  the place its object always stood in the confounded data, which the `named_place` reference policy
  demonstrates (default: none; a type whose confounded data puts every target in one slot has
  nothing to add to `shortcut`);
* `words(config)` — what else `targets=`, `distractor_only=` and `holdout=` may name besides the
  objects' names and attributes (e.g. a place), which `design` then honours (default: nothing);
* `CONFOUNDS` — the shortcuts `confound=` may re-introduce (default: none).

The built-in types live here; a spec file given by path may bring its type's module beside it
(`<dir>/<type>.py`). Adding a type means adding those two files; nothing else changes.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from core.demo import Plan, Skills
from core.spec import EpisodeSpec
from referents import destination
from referents.balance import Balance
from referents.contract import TypeModule, code_of, pick_and_lift
from referents.design import Design
from referents.features import Alternative
from referents.schema import ReferentConfig, ReferentSpecError

__all__ = [
    "HERE", "IN_WORLDS", "Referent", "UnknownReferent", "available", "demo_of", "load", "of_world", "own_name", "pick_and_lift",
    "spec_file", "world_of", "worlds_of",
]  # fmt: skip

HERE = Path(__file__).parent
IN_WORLDS = HERE / "in_worlds"  # a built-in type's specs for other worlds than its own: <world>/<type>.yaml


class UnknownReferent(ValueError):
    pass


def available() -> list[str]:
    """The built-in types."""
    return sorted(p.stem for p in HERE.glob("*.yaml"))


@dataclass(frozen=True)
class Referent:
    """A loaded referent type: its validated spec, its checked code, the bodies its scenes compile."""

    config: ReferentConfig
    code: TypeModule
    inventory: tuple[tuple[str, int], ...]

    @property
    def name(self) -> str:
        return self.config.type

    @property
    def label(self) -> str:
        """The type, and its world where that is not the type's own (`color@libero_spatial`): what
        names it in a mix of types (gen/mix.py)."""
        own = world_of(self.name) if self.name in available() else self.config.world
        return self.name if self.config.world == own else f"{self.name}@{self.config.world}"

    def design(self, balance: Balance) -> Design:
        try:
            design = destination.add(self.config, self.code.design(destination.inner(self.config), balance))
        except ReferentSpecError as exc:
            raise _held_out(self.config, exc) from None
        bodies = dict(self.inventory)
        for kind, n in Counter(p.candidate.kind for p in design.placements).items():
            if n > bodies.get(kind, 0):
                problem = f"a scene holds {n} {kind!r} objects but assets() of type {self.name} compiles {bodies.get(kind, 0)}"
                raise self.config.fail("assets", problem)
        return design

    def demo(self, skills: Skills, spec: EpisodeSpec) -> None:
        self.code.demo(skills, spec)

    def alternatives(self, spec: EpisodeSpec) -> list[Alternative]:
        return self.code.alternatives(self.config, self._seen(spec))

    def assets(self) -> tuple[tuple[str, int], ...]:
        return self.inventory

    def answer(self, spec: EpisodeSpec) -> str:
        return self.code.answer(spec)

    def shortcut(self, spec: EpisodeSpec) -> EpisodeSpec:
        """The episode an instruction-blind policy would do in this scene (what `position` demonstrates)."""
        if destination.container(self.config) is None:
            return self.code.shortcut(self.config, spec)
        return destination.restored(spec, self.code.shortcut(self.config, destination.without(spec)))

    def named_place(self, spec: EpisodeSpec, named: str) -> EpisodeSpec | None:
        """The episode a policy would do that reads the name `named` (an object id) only as a
        place (what `named_place` demonstrates); None for a type whose names share one place."""
        if self.code.named_place is None:
            return None
        if destination.container(self.config) is None:
            return self.code.named_place(self.config, spec, named)
        return destination.restored(spec, self.code.named_place(self.config, destination.without(spec), named))

    def _seen(self, spec: EpisodeSpec) -> EpisodeSpec:
        """The scene as the type sees it: a world's container (referents/destination.py) left out."""
        return spec if destination.container(self.config) is None else destination.without(spec)


def _module_path(referent_type: str, spec_path: str | Path | None) -> Path | None:
    """Where a type's code lives: beside the spec file it came from, else among the built-in types."""
    if spec_path is not None:
        beside = Path(spec_path).resolve().parent / f"{referent_type}.py"
        if beside.parent != HERE.resolve() and beside.is_file():
            return beside
    return HERE / f"{referent_type}.py" if referent_type in available() else None


def _field(path: Path, name: str, default: str) -> str:
    """A word of a spec file's, read without validating it (a spec that cannot be read gives
    `default` here and fails, naming its problem, when loaded)."""
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return default
    value = data.get(name, default) if isinstance(data, dict) else default
    return value if isinstance(value, str) else default


def world_of(name: str, spec_path: str | Path | None = None) -> str:
    """The world a referent's scenes happen in (its own spec's)."""
    return _field(Path(spec_path) if spec_path is not None else HERE / f"{name}.yaml", "world", "native")


def of_world(world: str) -> list[str]:
    """The built-in referent types whose own scenes are in `world`."""
    return [name for name in available() if world_of(name) == world]


def carried_by(world: str) -> list[str]:
    """Every built-in type `referent=<type> world=<world>` takes: its own, those with a spec for it,
    and those that are the same axis there (`object` in libero_object)."""
    return [name for name in available() if world in worlds_of(name)]


def _aliases(name: str) -> list[str]:
    """The built-in types that are the axis `name` in a world of their own (libero_object's `axis: object`)."""
    return [other for other in available() if _field(HERE / f"{other}.yaml", "axis", "") == name]


def worlds_of(name: str) -> list[str]:
    """The worlds that carry referent `name`: its own, those with a spec of it (IN_WORLDS/<world>/<name>.yaml),
    and those of a type that is the same axis there."""
    others = sorted(p.parent.name for p in IN_WORLDS.glob(f"*/{name}.yaml"))
    return list(dict.fromkeys([world_of(name), *others, *(world_of(a) for a in _aliases(name))]))


def spec_file(name: str, world: str | None = None) -> Path:
    """The built-in spec of referent `name` in `world` (default its own): referents/<name>.yaml, a spec
    of the type for that world (IN_WORLDS/<world>/<name>.yaml: data only, the type's module designs
    it), or the type that is that axis there (`referent=object world=libero_object` is libero_object)."""
    if name not in available():
        raise UnknownReferent(f"unknown referent {name!r}; available: {', '.join(available())}")
    if world is None or world == world_of(name):
        return HERE / f"{name}.yaml"
    there = IN_WORLDS / world / f"{name}.yaml"
    if there.is_file():
        return there
    alias = [a for a in _aliases(name) if world_of(a) == world]
    if alias:
        return HERE / f"{alias[0]}.yaml"
    carriers = ", ".join(worlds_of(name))
    raise UnknownReferent(f"referent {name} has no design in world {world}; worlds that carry {name}: {carriers}")


def own_name(name: str, world: str | None) -> tuple[str, str | None]:
    """A type in a world as the built-in type that is that axis there, in its own world
    (`object` in libero_object: `libero_object`, None), else as given."""
    alias = [a for a in _aliases(name) if world is not None and world_of(a) == world] if name in available() else []
    return (alias[0], None) if alias and not (IN_WORLDS / world / f"{name}.yaml").is_file() else (name, world)  # type: ignore[operator]


def demo_of(referent_type: str, spec_path: str | Path | None = None) -> Plan:
    """The oracle's plan for a type's episodes, by the type's name (all a replay needs: no spec
    file). A type brought beside its spec file is found only given that file's path."""
    module = _module_path(referent_type, spec_path)
    if module is None:
        raise UnknownReferent(
            f"unknown referent type {referent_type!r}; built-in: {', '.join(available())} "
            "(a type brought beside its spec file needs that file's path)"
        )
    return code_of(module).demo


def _held_out(config: ReferentConfig, exc: ReferentSpecError) -> ReferentSpecError:
    """A spec that no longer holds once `holdout=` removed objects: the line names the option."""
    if not config.holdout:
        return exc
    problem = str(exc).removeprefix(f"{config.path}: ")
    return config.fail("holdout", f"without {', '.join(config.holdout)} the spec no longer holds: {problem}")


def load(
    name: str, spec_path: str | Path | None = None, overrides: dict[str, Any] | None = None, world: str | None = None
) -> Referent:
    """The referent `name` in `world` (default its own; see `spec_path`), or the spec file at
    `spec_path` (whose type's module may stand beside it).

    `overrides` replace top-level spec fields (e.g. objects_per_scene, holdout, confound).
    """
    if spec_path is None:
        path = spec_file(name, world)
    else:
        path = Path(spec_path)
        if not path.is_file():
            raise ReferentSpecError(f"{path}: referent spec file not found")
    config = ReferentConfig.from_yaml(path, overrides)
    module = _module_path(config.type, path)
    if module is None:
        raise config.fail(
            "type",
            f"no module for referent type {config.type!r}: none beside the spec ({path.resolve().parent / f'{config.type}.py'}) "
            f"and no built-in type of that name ({', '.join(available())})",
        )
    if module.parent != HERE and config.type in available():
        raise config.fail("type", f"{config.type!r} is a built-in type; the module beside the spec ({module}) needs another name")
    code = code_of(module)
    if config.confound and config.confound not in code.CONFOUNDS:
        raise config.fail("confound", f"{config.confound!r} is not defined for referent type {config.type!r}")
    try:
        code.validate(config)
    except ReferentSpecError as exc:
        raise _held_out(config, exc) from None
    stray = config.unknown_words(tuple(code.words(config)))
    if stray is not None:
        raise stray
    return Referent(config, code, code.inventory(config))
