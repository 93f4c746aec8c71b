"""Rates with their evidence: k of n, and a Wilson 95% interval (used by the audit and battery)."""

from __future__ import annotations

import math
from dataclasses import dataclass

Z95 = 1.959963984540054


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
