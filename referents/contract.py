"""The referent type contract: what a type's module (`<type>.py`, beside its `<type>.yaml`) may
define, and the default of every name but `design`.

The module's public names must all be contract names (helpers are private: `_name`); any other
one, such as a misspelt `alternative`, is refused at load with one line naming it, so nothing
silently falls back to a default.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import importlib.util
import sys
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields, replace
from pathlib import Path
from types import ModuleType

import numpy as np

from core import programs, worlds
from core.demo import DemoScript
from core.libero import Problem
from core.spec import EpisodeSpec, TaskSpec
from referents import destination
from referents.balance import Balance
from referents.design import Design
from referents.schema import CONFOUNDS, ReferentConfig, ReferentSpecError
from referents.variables import Alternative, object_alternatives


def _the_target(spec: EpisodeSpec) -> str:
    return spec.target


def _accept(cfg: ReferentConfig) -> None:
    """No checks beyond the schema's."""


def _no_words(cfg: ReferentConfig) -> tuple[str, ...]:
    """Targets are named by the objects' names and attributes only."""
    return ()


def nearest_canonical(cfg: ReferentConfig, spec: EpisodeSpec) -> EpisodeSpec:
    """The instruction-blind shortcut: pick up whatever stands nearest the canonical slot."""
    x, y = cfg.layout.slots[cfg.layout.canonical_slot]
    nearest = min(spec.objects, key=lambda o: np.hypot(o.pos[0] - x, o.pos[1] - y))
    return replace(spec, target=nearest.id, task=TaskSpec(program="pick"))


@dataclass(frozen=True)
class TypeModule:
    """A referent type's code: the contract's names as its module defines them, defaults filled in.
    This class is the contract, written once (scripts/contract_doc.py renders it into
    docs/REFERENTS.md). A type's module must define `design`; a world's module beside its spec of
    the type (referents/in_worlds/<world>/<type>.py) may define any hook, replacing the type's."""

    # `design(config, balance) -> Design`: the balanced discrete choices of one episode (objects, slots,
    # target, template, counterfactuals), each through `balance.pick` (least used, seeded ties)
    design: Callable[[ReferentConfig, Balance], Design]
    # `demo(skills, spec)`: the oracle's plan, a few lines over the skills of core/demo.py
    demo: DemoScript = programs.perform
    # `alternatives(config, spec) -> [Alternative]`: what the instruction chooses among, for the confound
    # audit, each with the variables that declare their family (referents/variables.py)
    alternatives: Callable[[ReferentConfig, EpisodeSpec], list[Alternative]] = object_alternatives
    # `answer(spec) -> str`: the id of the right alternative
    answer: Callable[[EpisodeSpec], str] = _the_target
    # `assets(config) -> [(kind, count)]`: the bodies every scene compiles
    assets: Callable[[ReferentConfig], Iterable[tuple[str, int]]] = ReferentConfig.assets
    # `validate(config)`: type-specific checks of the spec: `raise config.fail(field, problem)`
    validate: Callable[[ReferentConfig], None] = _accept
    # `shortcut(config, spec) -> EpisodeSpec`: what an instruction-blind policy does in the scene (the
    # `position` reference policy demonstrates it)
    shortcut: Callable[[ReferentConfig, EpisodeSpec], EpisodeSpec] = nearest_canonical
    # `named_place(config, spec, named) -> EpisodeSpec`: what a policy does that reads the name only as
    # where its object always stood in the confounded data (`named_place`); None: one place for every name
    named_place: Callable[[ReferentConfig, EpisodeSpec, str], EpisodeSpec] | None = None
    # `canonical(config, problem) -> Design | None`: a LIBERO task's own scene (gen.canonical), None for a
    # task the type cannot do
    canonical: Callable[[ReferentConfig, Problem], Design | None] | None = None
    # `words(config) -> (str, ...)`: what else `targets=`, `distractor_only=` and `holdout=` may name
    # besides the objects' names and attributes (a place), which `design` then honours
    words: Callable[[ReferentConfig], tuple[str, ...]] = _no_words
    # `CONFOUNDS`: the shortcuts `confound=` may re-introduce (`position`, `layout`)
    CONFOUNDS: tuple[str, ...] = ()

    def inventory(self, cfg: ReferentConfig) -> tuple[tuple[str, int], ...]:
        """The bodies every scene compiles, checked now rather than when a scene is first built:
        catalog kinds, positive counts, and a body for every kind the spec's objects use."""
        where = f"(assets() of referent type {cfg.type})"
        try:
            pairs = [tuple(entry) for entry in self.assets(cfg)]
        except TypeError:
            raise cfg.fail("assets", f"must be (kind, count) pairs {where}") from None
        held = destination.container(cfg)
        if held is not None and held.kind not in {kind for kind, *_ in pairs}:
            pairs.append((held.kind, 1))
        for pair in pairs:
            if len(pair) != 2 or not isinstance(pair[1], int) or pair[1] < 1:
                raise cfg.fail("assets", f"{pair!r} is not a (kind, count >= 1) pair {where}")
            kinds = worlds.world(cfg.world).kinds
            if not isinstance(pair[0], str) or pair[0] not in kinds:
                raise cfg.fail("assets", f"unknown kind {pair[0]!r} {where}; known: {', '.join(sorted(kinds))}")
        inventory = tuple(sorted(pairs))
        twice = [kind for kind, n in Counter(kind for kind, _ in inventory).items() if n > 1]
        if twice:
            raise cfg.fail("assets", f"kind {twice[0]!r} is listed twice {where}")
        missing = sorted({c.kind for c in cfg.objects} - {kind for kind, _ in inventory})
        if missing:
            raise cfg.fail("objects", f"kind {missing[0]!r} has no body in the scene's inventory {where}")
        return inventory


CONTRACT = tuple(f.name for f in fields(TypeModule))


@functools.cache
def code_of(path: Path, over: Path | None = None) -> TypeModule:
    """The checked code of the type module at `path` (a built-in type's, or one beside its spec),
    each hook a module `over` defines (a world's, beside that world's spec of the type) in place of
    the type's own."""
    found = _hooks(path)
    if "design" not in found:
        raise ReferentSpecError(f"{path}: design: missing; every referent type defines design(config, balance) -> Design")
    if over is not None:
        found |= _hooks(over)
    for name, value in found.items():
        if name != "CONFOUNDS" and not callable(value):
            raise ReferentSpecError(f"{path}: {name}: must be a function, got {value!r}")
    confounds = found.get("CONFOUNDS", ())
    if not isinstance(confounds, tuple) or not set(confounds) <= set(CONFOUNDS):
        raise ReferentSpecError(f"{path}: CONFOUNDS: must be a tuple of {', '.join(CONFOUNDS)}, got {confounds!r}")
    return TypeModule(**found)


def _hooks(path: Path) -> dict:
    """The contract's names a module defines; any other public name is refused in one line."""
    built_in = path.parent.resolve() == Path(__file__).resolve().parent
    module = importlib.import_module(f"referents.{path.stem}") if built_in else _import_file(path)
    for name in _defined(path):
        if not name.startswith("_") and name not in CONTRACT:
            raise ReferentSpecError(
                f"{path}: {name}: not part of the referent type contract ({', '.join(CONTRACT)}); a helper's name starts with _"
            )
    return {name: getattr(module, name) for name in CONTRACT if hasattr(module, name)}


def _defined(path: Path) -> list[str]:
    """The names a module's top-level statements define (what it imports is not its own)."""
    names = []
    for node in ast.parse(path.read_text(), str(path)).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.append(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names += [n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)]
    return names


def _import_file(path: Path) -> ModuleType:
    """A type module from outside the package, under a name unique to its file."""
    name = f"_referent_{path.stem}_{hashlib.sha256(str(path).encode()).hexdigest()[:8]}"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses defined in it look their module up here
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the type's own code: any failure is reported in one line
        del sys.modules[name]
        raise ReferentSpecError(f"{path}: cannot import: {type(exc).__name__}: {exc}") from None
    return module
