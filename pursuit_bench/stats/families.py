"""A family of tests: Holm's step-down correction, applied before a report leans on any cell of a
table of tests."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def holm(pvalues: Sequence[float] | np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values (in the given order): the smallest of m p-values times
    m, the next times m - 1, …, each at least the one before it, at most 1. A hypothesis is
    rejected at family-wise level α when its adjusted p-value is at most α."""
    p = np.asarray(pvalues, dtype=float)
    if np.any(np.isnan(p)) or np.any((p < 0) | (p > 1)):
        raise ValueError(f"Holm needs p-values in [0, 1], got {p.tolist()}")
    m = len(p)
    order = np.argsort(p, kind="stable")
    stepped = np.maximum.accumulate(np.minimum(1.0, (m - np.arange(m)) * p[order]))
    adjusted = np.empty(m)
    adjusted[order] = stepped
    return adjusted
