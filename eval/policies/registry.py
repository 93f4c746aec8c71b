"""Policy names -> policies, for `python -m eval policy=<name>` and the worker processes that
rebuild a policy from its name.

A name is `KEY` or `KEY:ARG`. eval registers its own policies here (the reference policies and
`remote:HOST:PORT`); packages above eval declare theirs as entry points in the
`deconfound.policies` group (train's `ckpt:PATH`, in pyproject.toml), which are imported only
when a name asks for them, so eval never imports them. A factory that takes the argument says
so with an `argument` attribute naming it (`PATH`, `HOST:PORT`) and is called with the rest of
the name; any other factory is called with nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.metadata import EntryPoint, entry_points

from eval.policies import NamedPlace, Nothing, Oracle, Policy, PolicyError, Position, Random
from eval.policies.lerobot import LeRobotPolicy
from eval.policies.remote import RemotePolicy

GROUP = "deconfound.policies"

Factory = Callable[..., Policy]
_FACTORIES: dict[str, Factory] = {}


def register(key: str, factory: Factory) -> None:
    """Make `factory` the policy `key` (or `key:ARG`, when the factory has an `argument`)."""
    if not key or ":" in key:
        raise ValueError(f"a policy key is a plain name, got {key!r}")
    _FACTORIES[key] = factory


def _load(entry: EntryPoint) -> Factory:
    try:
        return entry.load()
    except Exception as exc:  # a plugin that cannot import (e.g. its extra is not installed)
        raise PolicyError(f"policy {entry.name!r} ({entry.value}) cannot be loaded: {type(exc).__name__}: {exc}") from None


def _factory(key: str) -> Factory | None:
    if key in _FACTORIES:
        return _FACTORIES[key]
    found = entry_points(group=GROUP, name=key)
    return _load(next(iter(found))) if found else None


def _written(key: str, factory: Factory | None) -> str:
    argument = getattr(factory, "argument", None)
    return f"{key}:{argument}" if argument else key


def names() -> list[str]:
    """Every registered policy as it is written (`oracle`, `remote:HOST:PORT`, `ckpt:PATH`)."""
    listed = [_written(key, factory) for key, factory in _FACTORIES.items()]
    for entry in entry_points(group=GROUP):
        if entry.name not in _FACTORIES:
            try:
                listed.append(_written(entry.name, _load(entry)))
            except PolicyError:
                listed.append(entry.name)
    return listed


def make(name: str, **options: object) -> Policy:
    """The policy `name` names, or PolicyError saying why not (one line); `options` go to its
    factory (e.g. `keys=` for remote policies)."""
    key, sep, arg = name.partition(":")
    factory = _factory(key)
    if factory is None:
        raise PolicyError(f"unknown policy {name!r}; registered: {', '.join(names())}")
    argument = getattr(factory, "argument", None)
    if argument and not arg:
        raise PolicyError(f"policy {key} needs an argument: {key}:{argument}")
    if sep and not argument:
        raise PolicyError(f"policy {key} takes no argument: write {key}, not {name!r}")
    try:
        return factory(arg, **options) if argument else factory(**options)
    except TypeError as exc:
        if options:  # a factory that takes no such option
            raise PolicyError(f"policy {key} takes no option {', '.join(options)}: {exc}") from None
        raise


register("oracle", Oracle)
register("position", Position)
register("named_place", NamedPlace)
register("nothing", Nothing)
register("random", Random)
register("remote", RemotePolicy)
register("lerobot", LeRobotPolicy)
