"""Rates with their evidence: k of n, a Wilson 95% interval (used by the audit and battery), and a
cluster bootstrap interval for rollouts that share a scene.

Wilson treats every rollout as independent; an exam's swaps of one trial share its scene, so
their outcomes are correlated and Wilson is too narrow. `cluster_ci` resamples whole trials
(clusters) with replacement and takes the percentile interval of the pooled rate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

Z95 = 1.959963984540054
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 0  # fixed: the same outcomes always give the same interval


def wilson(k: float, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval for k successes in n trials (k may be fractional: expected hits)."""
    if n <= 0:
        return (0.0, 1.0)
    p = k / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass(frozen=True)
class Rate:
    k: float
    n: int

    @property
    def rate(self) -> float:
        return self.k / self.n if self.n else float("nan")

    @property
    def ci(self) -> tuple[float, float]:
        return wilson(self.k, self.n)

    def to_dict(self) -> dict:
        k = int(self.k) if float(self.k).is_integer() else round(self.k, 4)
        return {"k": k, "n": self.n, "rate": round(self.rate, 4) if self.n else None, "ci": [round(v, 4) for v in self.ci]}

    def __str__(self) -> str:
        lo, hi = self.ci
        k = f"{self.k:g}" if not float(self.k).is_integer() else str(int(self.k))
        return f"{self.rate:.1%} ({k}/{self.n}, 95% CI {lo:.1%}–{hi:.1%})" if self.n else "— (n=0)"


def cluster_ci(outcomes: Sequence[float], clusters: Sequence[int], resamples: int = BOOTSTRAP_RESAMPLES) -> tuple[float, float]:
    """95% percentile interval of the pooled rate when whole clusters (trials) are resampled."""
    if not len(outcomes):
        return (0.0, 1.0)
    ids, index = np.unique(np.asarray(clusters), return_inverse=True)
    hits = np.bincount(index, weights=np.asarray(outcomes, float), minlength=len(ids))
    sizes = np.bincount(index, minlength=len(ids)).astype(float)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    draws = rng.integers(0, len(ids), size=(resamples, len(ids)))
    rates = hits[draws].sum(axis=1) / sizes[draws].sum(axis=1)
    lo, hi = np.percentile(rates, [2.5, 97.5])
    return (round(float(lo), 4), round(float(hi), 4))


def paired_difference(
    first: Sequence[float], second: Sequence[float], clusters: Sequence[int], resamples: int = BOOTSTRAP_RESAMPLES
) -> dict:
    """second's pooled rate minus first's, over the same rows, with the 95% percentile interval of
    resampling whole clusters (trials) for both at once: two takes of one exam from the same
    initial states are paired, so their difference is tighter than two separate intervals say."""
    if not len(first):
        return {"difference": None, "ci_trials": [-1.0, 1.0], "n": 0}
    ids, index = np.unique(np.asarray(clusters), return_inverse=True)
    delta = np.bincount(index, weights=np.asarray(second, float) - np.asarray(first, float), minlength=len(ids))
    sizes = np.bincount(index, minlength=len(ids)).astype(float)
    draws = np.random.default_rng(BOOTSTRAP_SEED).integers(0, len(ids), size=(resamples, len(ids)))
    lo, hi = np.percentile(delta[draws].sum(axis=1) / sizes[draws].sum(axis=1), [2.5, 97.5])
    return {
        "difference": round(float(delta.sum() / sizes.sum()), 4),
        "ci_trials": [round(float(lo), 4), round(float(hi), 4)],
        "n": len(first),
    }


def widest_interval(rate: dict) -> tuple[float, float]:
    """The wider of a rate's two 95% intervals (`ci`, Wilson's, and `ci_trials`, which resamples
    trials): with one trial the resampled one shrinks to a point and would overstate the evidence."""
    trials = rate.get("ci_trials") or rate["ci"]
    return min(rate["ci"][0], trials[0]), max(rate["ci"][1], trials[1])


def against_chance(rate: dict, chance: float) -> str:
    """A rate against its chance: `above` (`below`) where its widest interval lies above (below)
    it, else `overlaps`. The battery's verdicts (eval/scoring/score.py, eval/scoring/report.py) judge by this rule."""
    lo, hi = widest_interval(rate)
    return "above" if lo > chance else "below" if hi < chance else "overlaps"
