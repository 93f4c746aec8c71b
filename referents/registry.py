"""The referent types by name: which there are, which world each lays its scenes out in, and
loading one (its spec validated, its code checked against the contract, referents/contract.py).

A built-in type is `referents/<type>.yaml` + `referents/<type>.py`, in its own world (ours unless
the spec says otherwise). A type in another world is data, `referents/in_worlds/<world>/<type>.yaml`
(that world's objects, places and wording for the type), with an optional module beside it,
`<world>/<type>.py`, whose hooks override the type's (LIBERO-Object's object axis knows LIBERO's own
tasks: its `canonical`, its shortcuts). `referent=<type> world=<world>` is the one grammar. A world's
spec that says `canonical_only: true` lays out that world's LIBERO tasks for gen.canonical and no
scenes of its own (LIBERO-10's kitchens: `tasks_only`); `referent=` does not take it there. A
world's spec may record its episodes under a name of its own (`type: libero_object`), kept from
when it was a type of its own; `referent=libero_object` is that name, an alias of
`referent=object world=libero_object`, and both record the same. A spec file given by path may
bring its type's module beside it (`<dir>/<type>.py`).
"""

from __future__ import annotations

import functools
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from core.demo import DemoScript, Skills
from core.spec import EpisodeSpec
from referents import destination
from referents.balance import Balance
from referents.contract import TypeModule, code_of
from referents.design import Design
from referents.schema import ReferentConfig, ReferentSpecError
from referents.variables import Alternative

__all__ = [
    "HERE", "IN_WORLDS", "Referent", "UnknownReferent", "available", "carried_by", "demo_of", "load", "of_world", "own_name",
    "spec_file", "tasks_only", "types", "world_of", "worlds_of",
]  # fmt: skip

HERE = Path(__file__).parent
IN_WORLDS = HERE / "in_worlds"  # a built-in type's specs for other worlds than its own: <world>/<type>.yaml


class UnknownReferent(ValueError):
    pass


def types() -> list[str]:
    """The built-in types: a spec and a module each in this folder."""
    return sorted(p.stem for p in HERE.glob("*.yaml"))


@functools.cache
def _in_worlds() -> dict[Path, tuple[str, str, str]]:
    """Every spec of a type in another world than its own that lays out scenes there: its file ->
    (type, world, the name its episodes record). Those that lay out that world's LIBERO tasks only
    are `tasks_only`'s."""
    found = sorted(p for p in IN_WORLDS.glob("*/*.yaml") if not _canonical_only(p))
    return {p: (p.stem, p.parent.name, _field(p, "type", p.stem)) for p in found}


def _canonical_only(path: Path) -> bool:
    """Whether a world's spec of a type says `canonical_only: true`: it lays out that world's LIBERO
    tasks on LIBERO's own states (gen.canonical), and no scenes of its own (a LIBERO-10 kitchen,
    whose one carriable thing leaves nothing to name)."""
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return False
    return isinstance(data, dict) and data.get("canonical_only") is True


def tasks_only(world: str) -> list[Path]:
    """The specs that lay out `world`'s LIBERO tasks and no scenes of their own (`_canonical_only`)."""
    return [p for p in sorted((IN_WORLDS / world).glob("*.yaml")) if _canonical_only(p)]


def _alias(name: str) -> Path | None:
    """The spec a world's own name for a type stands for (`libero_object`: the object axis there)."""
    return next((path for path, (kind, _, label) in _in_worlds().items() if label == name and label != kind), None)


def available() -> list[str]:
    """Every name `referent=` takes: the built-in types and the names some worlds' specs record."""
    return sorted([*types(), *(label for kind, _, label in _in_worlds().values() if label != kind)])


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
        names it in a mix of types (gen/planning/mix.py)."""
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


def _modules(referent_type: str, spec_path: Path) -> tuple[Path | None, Path | None]:
    """A type's code: its module, and a module whose hooks override it (a world's, beside that
    world's spec of the type) or None. A spec outside the package may bring its module beside it."""
    beside = spec_path.resolve().parent / f"{referent_type}.py"
    if spec_path.resolve().parent.parent == IN_WORLDS.resolve():  # in_worlds/<world>/<type>.yaml (+ .py)
        over = spec_path.with_suffix(".py")
        return HERE / f"{spec_path.stem}.py", over if over.is_file() else None
    if beside.parent != HERE.resolve() and beside.is_file():
        return beside, None
    alias = _alias(referent_type)  # a world's own name for a type: that world's code of it
    if alias is not None:
        return _modules(referent_type, alias)
    return (HERE / f"{referent_type}.py" if referent_type in types() else None), None


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
    path = Path(spec_path) if spec_path is not None else (_alias(name) or HERE / f"{name}.yaml")
    return _field(path, "world", "native")


def of_world(world: str) -> list[str]:
    """The referents whose own scenes are in `world` (a world's own name for a type among them)."""
    return [name for name in available() if world_of(name) == world]


def carried_by(world: str) -> list[str]:
    """Every name `referent=<name> world=<world>` takes: the types with a spec there, and the
    referents of that world."""
    return [name for name in available() if world in worlds_of(name)]


def worlds_of(name: str) -> list[str]:
    """The worlds that carry referent `name`: its own, and those with a spec of it (IN_WORLDS/<world>/<name>.yaml)."""
    return list(dict.fromkeys([world_of(name), *(world for kind, world, _ in _in_worlds().values() if kind == name)]))


def spec_file(name: str, world: str | None = None) -> Path:
    """The built-in spec of referent `name` in `world` (default its own): referents/<name>.yaml, or
    the type's spec for that world (IN_WORLDS/<world>/<name>.yaml), or the spec a world's own name
    for a type stands for."""
    if name not in available():
        raise UnknownReferent(f"unknown referent {name!r}; available: {', '.join(available())}")
    alias = _alias(name)
    if alias is not None and world in (None, alias.parent.name):
        return alias
    if world is None or world == world_of(name):
        return HERE / f"{name}.yaml"
    there = IN_WORLDS / world / f"{name}.yaml"
    if there.is_file():
        return there
    carriers = ", ".join(worlds_of(name))
    raise UnknownReferent(f"referent {name} has no design in world {world}; worlds that carry {name}: {carriers}")


def own_name(name: str, world: str | None) -> tuple[str, str | None]:
    """A type in a world as the name its episodes there record, where the world's spec gives one of
    its own (`object` in libero_object: `libero_object`, its world its own), else as given."""
    there = IN_WORLDS / str(world) / f"{name}.yaml"
    label = _in_worlds()[there][2] if world is not None and there in _in_worlds() else name
    return (label, None) if label != name else (name, world)


def demo_of(referent_type: str, spec_path: str | Path | None = None) -> DemoScript:
    """The oracle's plan for a type's episodes, by the name they record (all a replay needs: no spec
    file). A type brought beside its spec file is found only given that file's path."""
    path = Path(spec_path) if spec_path is not None else (_alias(referent_type) or HERE / f"{referent_type}.yaml")
    module, over = _modules(referent_type, path)
    if module is None:
        raise UnknownReferent(
            f"unknown referent type {referent_type!r}; built-in: {', '.join(available())} "
            "(a type brought beside its spec file needs that file's path)"
        )
    return code_of(module, over).demo


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
    module, over = _modules(config.type, path)
    if module is None:
        raise config.fail(
            "type",
            f"no module for referent type {config.type!r}: none beside the spec ({path.resolve().parent / f'{config.type}.py'}) "
            f"and no built-in type of that name ({', '.join(available())})",
        )
    if module.parent != HERE and config.type in available():
        raise config.fail("type", f"{config.type!r} is a built-in type; the module beside the spec ({module}) needs another name")
    code = code_of(module, over)
    if config.confound and config.confound not in code.CONFOUNDS:
        raise config.fail("confound", f"{config.confound!r} is not defined for referent type {config.type!r}")
    try:
        code.validate(config)
    except ReferentSpecError as exc:
        raise _held_out(config, exc) from None
    except (KeyError, TypeError, ValueError, AttributeError) as exc:  # a field its validate did not foresee
        raise ReferentSpecError(f"{path}: a field of type {config.type} is malformed ({type(exc).__name__}: {exc})") from None
    stray = config.unknown_words(tuple(code.words(config)))
    if stray is not None:
        raise stray
    return Referent(config, code, code.inventory(config))
