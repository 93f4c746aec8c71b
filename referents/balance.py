"""The role balancer every referent type draws its choices through."""

from __future__ import annotations

from collections import Counter
from collections.abc import Hashable, Sequence
from typing import Any, TypeVar

import numpy as np

from referents.schema import Candidate

T = TypeVar("T")


class Balance:
    """Greedy least-used choices with seeded tie-breaks.

    Each choice takes an option whose count under `key` is lowest, so every prefix of a plan is
    as balanced as the choices allow: with n episodes every value is chosen n/len(options) (+-1)
    times, and (value, slot) pairs are all covered once n reaches their number.
    """

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.counts: Counter[tuple[Hashable, Hashable]] = Counter()

    def pick(self, key: Hashable, options: Sequence[T], also: Hashable | None = None) -> T:
        """Least-used option under `key`, ties broken by `also` (a second key), then at random."""
        if not options:
            raise ValueError(f"no options to choose {key!r} from")
        scores = [(self.counts[(key, self._id(o))], self.counts[(also, self._id(o))] if also is not None else 0) for o in options]
        best = min(scores)
        ties = [o for o, s in zip(options, scores) if s == best]
        choice = ties[int(self.rng.integers(len(ties)))]
        self.counts[(key, self._id(choice))] += 1
        if also is not None:
            self.counts[(also, self._id(choice))] += 1
        return choice

    @staticmethod
    def _id(option: Any) -> Hashable:
        return option.key if isinstance(option, Candidate) else option
