"""Comparisons of two kinds over seeds: the paired and Welch differences with their tests, TOST
equivalence, the four verdicts, power (seeds needed, the smallest detectable effect), a trend's
slope test and the exact test of two shares."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import stats

from pursuit_bench.stats.intervals import CONFIDENCE, TIE, t_interval

#: Family-wise error per direction: a one-sided test at 0.025 matches a two-sided 95 %
#: interval, so a comparison is called better (or worse) exactly when its interval, widened
#: for the family by Holm's procedure, excludes zero on that side.
ALPHA = 0.025


#: The equivalence margin of every four-verdict table, in return per episode (a capture is worth
#: 1): five captures in a hundred episodes, the larger of the reproduction's power margins
#: (REPRODUCTION.md). A choice, fixed (for the pool study) before it was applied to the
#: reproduction's panels and the robustness study; the report re-judges at ±0.02 and ±0.1 beside it.
EQUIVALENCE_MARGIN = 0.05


def paired_difference(
    ours: Sequence[float] | np.ndarray, theirs: Sequence[float] | np.ndarray, confidence: float = CONFIDENCE
) -> dict[str, Any]:
    """``ours - theirs`` seed by seed (same seed, same episodes): the differences, their mean,
    standard deviation, t-interval, t statistic and the one-sided p-values of the paired
    t-test for ``ours > theirs`` (``p_greater``) and ``ours < theirs`` (``p_less``).

    Seeds whose differences are all equal have no spread: the interval is that value and the
    p-values are 0 or 1 (0.5 for a difference of exactly zero: a tie is never a win)."""
    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"paired values need the same seeds: shapes {a.shape} and {b.shape}")
    d = a - b
    n = len(d)
    mean = float(d.mean()) if n else float("nan")
    sd = float(d.std(ddof=1)) if n > 1 else float("nan")
    if n < 2:
        t, p_greater = float("nan"), float("nan")
    elif sd <= TIE:  # no spread (but for the last bits of sums taken in different orders)
        mean = 0.0 if abs(mean) <= TIE else mean
        t = float(np.sign(mean) * np.inf) if mean != 0 else 0.0
        p_greater = 0.0 if mean > 0 else 1.0 if mean < 0 else 0.5
    else:
        t = mean / (sd / np.sqrt(n))
        p_greater = float(stats.t.sf(t, n - 1))
    p_less = 1.0 - p_greater  # the t distribution is continuous: the two tails add to one
    return {
        "n": n,
        "differences": d.tolist(),
        "mean": mean,
        "sd": sd,
        "ci": t_interval(d, confidence),
        "t": float(t),
        "p_greater": float(p_greater),
        "p_less": float(p_less),
    }


def welch_difference(
    ours: Sequence[float] | np.ndarray, theirs: Sequence[float] | np.ndarray, confidence: float = CONFIDENCE
) -> dict[str, Any]:
    """``mean(ours) - mean(theirs)`` for two independent groups of seeds (other runs, other
    prey: nothing to pair), with Welch's t-interval (Welch–Satterthwaite degrees of freedom) and
    the two-sided p-value of Welch's test (as ``scipy.stats.ttest_ind(equal_var=False)``)."""
    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if len(a) < 2 or len(b) < 2:
        raise ValueError(f"Welch's interval needs two or more seeds in each group, got {len(a)} and {len(b)}")
    mean = float(a.mean() - b.mean())
    va, vb = a.var(ddof=1) / len(a), b.var(ddof=1) / len(b)
    se = float(np.sqrt(va + vb))
    if se <= TIE:  # no spread (but for the last bits)
        return {"mean": mean, "ci": [mean, mean], "p": 1.0 if abs(mean) <= TIE else 0.0, "df": float("nan")}
    df = float((va + vb) ** 2 / (va**2 / (len(a) - 1) + vb**2 / (len(b) - 1)))
    half = float(stats.t.ppf(0.5 + confidence / 2, df) * se)
    p = float(2 * stats.t.sf(abs(mean) / se, df))
    return {"mean": mean, "ci": [mean - half, mean + half], "p": p, "df": df}


def _tost_p(mean: float, se: float, df: float, margin: float) -> float:
    """The larger of the two one-sided t-test p-values that a difference of ``mean`` (standard
    error ``se``, ``df`` degrees of freedom) lies above ``-margin`` and below ``+margin``; with no
    spread, 0 inside the margin and 1 outside."""
    if se <= TIE:
        return 0.0 if abs(mean) < margin - TIE else 1.0
    above = float(stats.t.sf((mean + margin) / se, df))  # H0: difference <= -margin
    below = float(stats.t.cdf((mean - margin) / se, df))  # H0: difference >= +margin
    return max(above, below)


def equivalence(
    ours: Sequence[float] | np.ndarray, theirs: Sequence[float] | np.ndarray, margin: float, alpha: float = ALPHA
) -> dict[str, Any]:
    """Two one-sided Welch tests (TOST) that ``mean(ours) - mean(theirs)`` lies inside
    ``(-margin, +margin)``, for two independent groups of seeds: ``p`` is the larger of the two
    one-sided p-values (equivalence is shown at level ``alpha`` when ``p <= alpha``, that is when
    the ``1 - 2 alpha`` Welch interval lies inside the margin); ``bound`` is the smallest margin
    this data would show equivalence at, ``max(|low|, |high|)`` of that interval."""
    if not margin > 0:
        raise ValueError(f"margin={margin!r}: expected a positive equivalence margin")
    a, b = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    welch = welch_difference(a, b, confidence=1 - 2 * alpha)
    mean, (low, high) = welch["mean"], welch["ci"]
    se = float(np.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b)))
    p = _tost_p(mean, se, welch["df"], margin)
    return {"margin": margin, "p": p, "bound": max(abs(low), abs(high))}


def paired_equivalence(differences: Sequence[float] | np.ndarray, margin: float) -> dict[str, Any]:
    """Two one-sided paired t-tests (TOST) that the mean of seed-level ``differences`` lies inside
    ``(-margin, +margin)``: ``p`` is the larger of the two one-sided p-values (equivalence is shown
    at level alpha when ``p <= alpha``, that is when the ``1 - 2 alpha`` t-interval lies inside the
    margin); ``bound`` is the smallest margin this data would show equivalence at (alpha 0.025),
    ``max(|low|, |high|)`` of the 95 % t-interval."""
    if not margin > 0:
        raise ValueError(f"margin={margin!r}: expected a positive equivalence margin")
    d = np.asarray(differences, dtype=float)
    if d.ndim != 1 or len(d) < 2:
        raise ValueError(f"paired equivalence needs two or more seed-level differences, got shape {d.shape}")
    mean, n = float(d.mean()), len(d)
    p = _tost_p(mean, float(d.std(ddof=1)) / np.sqrt(n), n - 1, margin)
    low, high = t_interval(d, 1 - 2 * ALPHA) or [mean, mean]
    return {"margin": margin, "p": p, "bound": max(abs(low), abs(high))}


def difference_verdict(
    mean: float, p_holm: float, equivalent_p_holm: float | None, words: tuple[str, str], alpha: float = ALPHA
) -> str:
    """The verdict of one comparison of a family, from its Holm-adjusted two-sided ``p_holm`` and,
    where it has one, its equivalence test's: ``words[0]`` or ``words[1]`` (the difference below or
    above zero) when ``p_holm`` is at most ``2 alpha`` (``alpha`` a direction), else ``equivalent``
    when the equivalence p is at most ``alpha``, else ``not resolved``."""
    if p_holm <= 2 * alpha:
        return words[0] if mean < 0 else words[1]
    if equivalent_p_holm is not None and equivalent_p_holm <= alpha:
        return "equivalent"
    return "not resolved"


#: A panel's four verdicts (:func:`classify`), in the order the reports print them.
VERDICTS = ("better", "equivalent", "not resolved", "worse")


def classify(comparisons: dict[str, dict[str, Any]], alpha: float = ALPHA) -> str:
    """A panel's verdict from its comparisons with each baseline (:func:`paired_difference`
    results carrying Holm-adjusted ``p_greater_holm``, ``p_less_holm`` and, for equivalence,
    ``p_equivalent_holm``): ``worse`` when any baseline is significantly ahead of the trained
    predator; ``better`` when it is significantly ahead of every baseline; ``equivalent`` when,
    against every baseline, it is either significantly ahead or within the equivalence margin
    (two one-sided tests): no baseline is better by the margin or more, and it is not shown
    better than all; else ``not resolved``."""
    if any(c["p_less_holm"] <= alpha for c in comparisons.values()):
        return "worse"
    if all(c["p_greater_holm"] <= alpha for c in comparisons.values()):
        return "better"
    if all(c["p_greater_holm"] <= alpha or c.get("p_equivalent_holm", 1.0) <= alpha for c in comparisons.values()):
        return "equivalent"
    return "not resolved"


def seeds_for_power(
    sd: float, delta: float, alpha: float = ALPHA, power: float = 0.8, most: int = 100_000
) -> int | None:
    """The fewest seeds at which a one-sided paired t-test at level ``alpha`` detects a true
    mean difference ``delta`` with probability ``power``, for seed-level differences of standard
    deviation ``sd`` (the noncentral t); None if more than ``most`` are needed."""
    if not (sd >= 0 and delta > 0 and 0 < alpha < 1 and 0 < power < 1):
        raise ValueError(
            f"seeds_for_power needs sd >= 0, delta > 0, alpha and power in (0, 1): got {sd}, {delta}, {alpha}, {power}"
        )
    if sd == 0:
        return 2

    def achieved(n: int) -> float:
        df = n - 1
        return float(stats.nct.sf(stats.t.ppf(1 - alpha, df), df, delta / (sd / np.sqrt(n))))

    if achieved(most) < power:
        return None
    lo, hi = 2, most  # power rises with n: bisect for the first n that reaches it
    while lo < hi:
        mid = (lo + hi) // 2
        if achieved(mid) >= power:
            hi = mid
        else:
            lo = mid + 1
    return lo


def detectable(sd: float, n: int, alpha: float = ALPHA, power: float = 0.8) -> float:
    """The smallest true mean that a one-sided t-test over ``n`` values of spread ``sd`` detects
    with probability ``power``: what a test that found nothing could have found."""
    if n < 2:
        return float("inf")
    df = n - 1
    critical = stats.t.ppf(1 - alpha, df)
    lo, hi = 0.0, 1.0
    while stats.nct.sf(critical, df, hi) < power:
        hi *= 2
    for _ in range(60):  # bisect the noncentrality
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if stats.nct.sf(critical, df, mid) < power else (lo, mid)
    return float(hi * sd / np.sqrt(n))


def slope_test(curves: Sequence[np.ndarray], x: np.ndarray, tolerance: float, alpha: float = ALPHA) -> dict[str, Any]:
    """Whether curves (one per seed, sampled at ``x``) still move: each seed's least-squares
    slope, the slopes' mean over seeds with its t-interval, and the verdict ``rising``,
    ``falling``, ``flat`` (the interval inside ±``tolerance``: an equivalence test) or ``not
    resolved``; ``detectable`` is the slope the test finds with 80 % power, so a ``not
    resolved`` says how large a trend could have gone unseen."""
    slopes = np.array([np.polyfit(x, np.asarray(c, dtype=float), 1)[0] for c in curves])
    ci = t_interval(slopes, 1 - 2 * alpha)
    verdict = "not resolved"
    if ci is not None:
        if ci[0] > 0:
            verdict = "rising"
        elif ci[1] < 0:
            verdict = "falling"
        elif -tolerance < ci[0] and ci[1] < tolerance:
            verdict = "flat"
    sd = float(slopes.std(ddof=1)) if len(slopes) > 1 else float("nan")
    return {
        "slopes": slopes.tolist(),
        "mean": float(slopes.mean()),
        "ci": ci,
        "tolerance": tolerance,
        "verdict": verdict,
        "detectable": detectable(sd, len(slopes), alpha) if len(slopes) > 1 else None,
    }


def share_difference(count_a: int, n_a: int, count_b: int, n_b: int) -> dict[str, Any]:
    """``count_a / n_a - count_b / n_b`` with Boschloo's exact unconditional test (two-sided; more
    powerful than Fisher's at these counts, and exact: no large-sample approximation).

    SciPy's ``boschloo_exact`` takes each *column* of the 2×2 table as one binomial sample, so the
    kinds are the columns. With the kinds as rows the null is the same but the sampling model is
    not the study's (the totals of failures and successes fixed, not the runs of each kind), and
    the p-values are not this design's exact test's."""
    table = [[count_a, count_b], [n_a - count_a, n_b - count_b]]
    p = 1.0 if count_a + count_b in (0, n_a + n_b) else float(stats.boschloo_exact(table).pvalue)
    return {"difference": count_a / n_a - count_b / n_b, "p": min(1.0, p)}
