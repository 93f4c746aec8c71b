"""Feature statistics in lerobot's format, computed exactly.

Vectors: min, max, mean, std (population), count and the 1/10/50/90/99 % quantiles over all
frames. Images: the same per channel, scaled to [0, 1] and shaped (3, 1, 1), computed from exact
256-bin histograms of every pixel of every frame (lerobot samples frames, and its std
overflows uint8 to about 0).
"""

from __future__ import annotations

import numpy as np

QUANTILES = {"q01": 0.01, "q10": 0.10, "q50": 0.50, "q90": 0.90, "q99": 0.99}


def vector_stats(values: np.ndarray) -> dict[str, np.ndarray]:
    """Stats over the first axis of a (T, D) or (T,) array."""
    x = np.asarray(values, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    stats = {
        "min": x.min(axis=0),
        "max": x.max(axis=0),
        "mean": x.mean(axis=0),
        "std": x.std(axis=0),
        "count": np.array([len(x)]),
    }
    for name, q in QUANTILES.items():
        stats[name] = np.quantile(x, q, axis=0, method="inverted_cdf")
    return stats


def image_histogram(frames: np.ndarray) -> np.ndarray:
    """(T, H, W, 3) uint8 -> (3, 256) pixel counts per channel."""
    flat = frames.reshape(-1, frames.shape[-1])
    return np.stack([np.bincount(flat[:, c], minlength=256) for c in range(flat.shape[1])]).astype(np.int64)


def image_stats(histogram: np.ndarray, frames: int) -> dict[str, np.ndarray]:
    """Per-channel stats in [0, 1], each shaped (3, 1, 1), from a (3, 256) histogram."""
    levels = np.arange(256, dtype=np.float64) / 255.0
    counts = histogram.astype(np.float64)
    total = counts.sum(axis=1)
    mean = counts @ levels / total
    var = counts @ levels**2 / total - mean**2
    cdf = np.cumsum(counts, axis=1) / total[:, None]
    present = counts > 0
    stats = {
        "min": levels[present.argmax(axis=1)],
        "max": levels[255 - present[:, ::-1].argmax(axis=1)],
        "mean": mean,
        "std": np.sqrt(np.maximum(var, 0.0)),
    }
    for name, q in QUANTILES.items():
        stats[name] = levels[(cdf >= q - 1e-12).argmax(axis=1)]
    shaped = {k: v.reshape(-1, 1, 1) for k, v in stats.items()}
    shaped["count"] = np.array([frames])
    return shaped


def to_json(stats: dict[str, dict[str, np.ndarray]]) -> dict[str, dict[str, list]]:
    return {key: {name: np.asarray(v).tolist() for name, v in s.items()} for key, s in stats.items()}
