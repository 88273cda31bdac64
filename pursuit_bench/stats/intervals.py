"""Intervals of a seed-level measure: Student-t of a mean, the percentile bootstrap of a median,
Wilson's score interval of a share, and the coverage check that says whether an interval means what
it says (at the seed counts used)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import stats

CONFIDENCE = 0.95


#: Two measures closer than this are equal. A run's measures are means of episode returns summed
#: in different orders, so values equal in exact arithmetic can differ in their last bits (a pool
#: margin of exactly 0 came out as -2.8e-17): a comparison with a line or another run must not
#: read that as a difference.
TIE = 1e-12


def t_interval(values: Sequence[float] | np.ndarray, confidence: float = CONFIDENCE) -> list[float] | None:
    """The Student-t interval of the mean of ``values`` (seeds); None below two values."""
    x = np.asarray(values, dtype=float)
    if x.ndim != 1:
        raise ValueError(f"t_interval needs one value per seed (a 1-d array), got shape {x.shape}")
    if len(x) < 2:
        return None
    half = float(stats.t.ppf(0.5 + confidence / 2, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x)))
    return [float(x.mean()) - half, float(x.mean()) + half]


#: Fewest values a median's interval is given for: below it the percentile bootstrap covers far
#: less than it claims (lognormal data: 74 % at 3 values, 93–94 % at 5–20; ``studies/coverage/interval_coverage.py``).
MEDIAN_MIN = 5


def median_interval(
    values: Sequence[float] | np.ndarray, seed: int, confidence: float = CONFIDENCE, minimum: int = MEDIAN_MIN
) -> list[float] | None:
    """The percentile-bootstrap interval of the median of ``values`` (scipy's ``bootstrap``,
    2000 resamples drawn from ``seed``); None below ``minimum`` values or when all are equal."""
    x = np.asarray(values, dtype=float)
    if len(x) < minimum or np.ptp(x) == 0:
        return None
    interval = stats.bootstrap(
        (x,), np.median, n_resamples=2000, method="percentile", confidence_level=confidence,
        random_state=np.random.default_rng(seed),
    ).confidence_interval  # fmt: skip
    return [float(interval.low), float(interval.high)]


def coverage(draw: Any, truth: float, n: int, draws: int, seed: int = 0, confidence: float = CONFIDENCE) -> float:
    """The fraction of ``draws`` samples of size ``n`` (``draw(rng, shape)``) whose t-interval
    holds ``truth``: how often the interval :func:`t_interval` reports means what it says."""
    rng = np.random.default_rng(seed)
    samples = np.asarray(draw(rng, (draws, n)), dtype=float)
    held = 0
    for sample in samples:
        low, high = t_interval(sample, confidence) or (np.nan, np.nan)
        held += low <= truth <= high
    return held / draws


def wilson_interval(count: int, n: int, confidence: float = CONFIDENCE) -> list[float]:
    """Wilson's score interval of a share ``count / n`` (the failure shares of the rule study):
    it stays inside [0, 1] and keeps near its level at 10–30 runs where the normal (Wald)
    interval does not (``studies/coverage/interval_coverage.py`` measures it)."""
    if not 0 <= count <= n or n < 1:
        raise ValueError(f"a share needs 0 <= count <= n and n >= 1, got {count} of {n}")
    low, high = wilson_bounds(np.array(count / n), np.array(float(n)), confidence)
    return [float(low), float(high)]


def wilson_bounds(share: np.ndarray, n: np.ndarray, confidence: float = CONFIDENCE) -> tuple[np.ndarray, np.ndarray]:
    """Wilson's score interval, elementwise, of shares ``share`` out of ``n`` trials (arrays of
    one shape; NaN where n = 0 or the share is NaN), clipped to [0, 1] against rounding."""
    z = float(stats.norm.ppf(0.5 + confidence / 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        centre = (share + z * z / (2 * n)) / (1 + z * z / n)
        half = z / (1 + z * z / n) * np.sqrt(share * (1 - share) / n + z * z / (4 * n * n))
        return np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)
