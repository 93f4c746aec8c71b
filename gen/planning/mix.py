"""One dataset, many referent types: how a list of types (`referent=[a,b,c]`) shares a dataset.

`lerobot-train` reads one dataset, so an adapter that should learn several axes at once needs
them in one. Each type keeps its own plan (the roles `referent=<type> n=N/k` would draw with the
same seed), its own confound audit and its own world; the types take turns in the list's order
(episode i is of type i mod k), so every prefix of the dataset holds each type's share to within
one episode. One dataset records one set of features, so the types must record the same ones.
A type in the list may name its own world, `<type>@<world>` (`color@libero_spatial`): a mix of
LIBERO's axes draws each from the LIBERO scene that carries it; a type without one is in `world=`,
or its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar

from jobs.cli import UserError

T = TypeVar("T")


WORLD_SEPARATOR = "@"


def split(item: str) -> tuple[str, str | None]:
    """A list item as (type, its world or None): `color@libero_spatial`, or `color`; `color@`, a
    separator naming no world, is refused (it would read as the type's own world)."""
    name, at, world = item.partition(WORLD_SEPARATOR)
    if at and not world:
        raise UserError(f"referent={item} names no world after {WORLD_SEPARATOR!r}: write {item}<world>, or {name} for its own")
    return name, world or None


def types(referent: Any) -> list[str]:
    """The types a `referent=` value names: one, or each of a list (refused: an empty list, a
    name that is not a string, a type named twice)."""
    if isinstance(referent, str):
        return [referent]
    if not isinstance(referent, list):
        raise UserError(f"referent must name a referent type or a list of them, got {referent!r}")
    shown = listed(referent)
    if not referent:
        raise UserError("referent=[] names no referent type: give one (referent=object) or a list of several")
    for name in referent:
        if not isinstance(name, str):
            raise UserError(f"{shown}: {name!r} is not a referent type's name")
    for name in referent:
        if referent.count(name) > 1:
            raise UserError(f"{shown} names {name} {referent.count(name)} times: name each type once")
    return list(referent)


def name(names: Sequence[str]) -> str:
    """A mix's name (its default folder, its progress bar): the types joined by '+'."""
    return "+".join(names)


def check_share(n: int, names: Sequence[str]) -> None:
    """Every type gets the same number of episodes, so `n` must be a multiple of their number;
    the refusal names the nearest one (both, when two are as near)."""
    k = len(names)
    if n % k == 0:
        return
    below, above = n // k * k, n // k * k + k
    if below == 0 or above - n < n - below:
        nearest = f"n={above}"
    elif n - below < above - n:
        nearest = f"n={below}"
    else:
        nearest = f"n={below} or n={above}"
    raise UserError(f"n={n} cannot be shared equally by the {k} types of {listed(names)}: give {nearest}")


def check_features(recorded: Sequence[tuple[str, str]], hint: str) -> None:
    """(type, what it records) for each type: one dataset records one set of features, so the
    first two types that differ are refused, naming both; `hint` says what would make them agree."""
    first, features = recorded[0]
    for other, theirs in recorded[1:]:
        if theirs != features:
            raise UserError(
                f"{listed([t for t, _ in recorded])} mixes types that record different features: {first} records {features}, "
                f"{other} records {theirs}; one dataset records one set ({hint})"
            )


def turn(index: int, k: int) -> int:
    """The place in the list of the type of episode `index` among `k` types taking turns."""
    return index % k


def interleave(shares: Sequence[Sequence[T]]) -> list[T]:
    """Each type's items (of equal number), in episode order."""
    return [item for round_ in zip(*shares, strict=True) for item in round_]


def share(items: Sequence[T], place: int, k: int) -> list[T]:
    """The items of the type at `place` among `k` (the inverse of `interleave`)."""
    return list(items[place::k])


def listed(names: Sequence[Any], option: str = "referent") -> str:
    """The list as `referent=` (or another list option, e.g. `confound=`) spells it, for one-line messages."""
    return f"{option}=[{','.join(map(str, names))}]"
