"""Aggregates over panels: the probability of improvement (Agarwal et al. 2021, as rliable defines
it) and its stratified-bootstrap interval."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pursuit_bench.stats.intervals import CONFIDENCE, TIE

RESAMPLES = 2000


def pairs_above(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The share of pairs (x_i, y_j) with x_i > y_j, ties (within :data:`TIE`) half, over the last
    axis of each (leading axes: resamples)."""
    gap = x[..., :, None] - y[..., None, :]
    above = gap > TIE
    tied = np.abs(gap) <= TIE
    return (above + 0.5 * tied).mean(axis=(-2, -1))


def probability_of_improvement(xs: Sequence[np.ndarray], ys: Sequence[np.ndarray]) -> float:
    """P(X > Y) averaged over panels (Agarwal et al. 2021): per panel the Mann–Whitney U of its
    runs' scores over the number of pairs (ties count half), then the mean over panels."""
    return float(
        np.mean([pairs_above(np.asarray(x, float), np.asarray(y, float)) for x, y in zip(xs, ys, strict=True)])
    )


def improvement_interval(
    xs: Sequence[np.ndarray],
    ys: Sequence[np.ndarray],
    seed: int = 0,
    resamples: int = RESAMPLES,
    confidence: float = CONFIDENCE,
) -> dict[str, Any]:
    """:func:`probability_of_improvement` with a percentile interval from the stratified
    bootstrap of Agarwal et al. (2021): each panel's runs of each variant resampled with
    replacement within the panel, the statistic recomputed over all panels."""
    rng = np.random.default_rng(seed)
    draws = np.zeros(resamples)
    for x, y in zip(xs, ys, strict=True):
        x, y = np.asarray(x, float), np.asarray(y, float)
        rx = x[rng.integers(0, len(x), (resamples, len(x)))]
        ry = y[rng.integers(0, len(y), (resamples, len(y)))]
        draws += pairs_above(rx, ry) / len(xs)
    low, high = np.quantile(draws, [(1 - confidence) / 2, (1 + confidence) / 2])
    return {
        "value": probability_of_improvement(xs, ys),
        "ci": [float(low), float(high)],
        "panels": len(xs),
        "resamples": resamples,
    }
