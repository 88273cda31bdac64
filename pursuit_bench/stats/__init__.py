"""Seed-level statistics: every interval, test and count the reports print comes from here
(the ground floor beside ``io``: it imports nothing else of pursuit-bench).

Seeds are the unit of replication. A trained predator and the baselines put in its place play
the same evaluation episodes against the same prey of the same seed, so they are compared
*paired by seed*: the seed-level difference of mean returns, its mean over seeds and a
Student-t interval, a one-sided paired t-test per direction, and Holm's step-down correction
over the family of comparisons a report counts. Intervals are t-intervals, not percentile
bootstraps: at 3–10 seeds the percentile bootstrap under-covers (docs/statistics.md measures
both). A bootstrap is kept where it is the right tool, for aggregates over panels: the
probability of improvement (Agarwal et al. 2021, as rliable defines it: the Mann–Whitney
statistic per panel, averaged over panels) with a stratified bootstrap over seeds (seeds
resampled within each panel). rliable itself is not a dependency: it brings ``arch``, ``pandas``
and ``seaborn`` for a statistic of a few lines (checked against ``scipy.stats.mannwhitneyu``
in the tests).

The room's modules: ``intervals`` (t, median bootstrap, Wilson, coverage), ``comparisons``
(paired and Welch differences, TOST, verdicts, power, slopes, shares), ``families`` (Holm),
``aggregates`` (probability of improvement), ``text`` (an interval and a p-value as the tables
print them). Their names are all here too:
``from pursuit_bench import stats; stats.holm(...)``.
"""

from __future__ import annotations

from pursuit_bench.stats.aggregates import (
    RESAMPLES,
    improvement_interval,
    pairs_above,
    probability_of_improvement,
)
from pursuit_bench.stats.comparisons import (
    ALPHA,
    EQUIVALENCE_MARGIN,
    VERDICTS,
    classify,
    detectable,
    difference_verdict,
    equivalence,
    paired_difference,
    paired_equivalence,
    seeds_for_power,
    share_difference,
    slope_test,
    welch_difference,
)
from pursuit_bench.stats.families import (
    holm,
)
from pursuit_bench.stats.intervals import (
    CONFIDENCE,
    MEDIAN_MIN,
    TIE,
    coverage,
    median_interval,
    t_interval,
    wilson_bounds,
    wilson_interval,
)
from pursuit_bench.stats.text import p_text, span_text

__all__ = [
    "ALPHA",
    "CONFIDENCE",
    "EQUIVALENCE_MARGIN",
    "MEDIAN_MIN",
    "RESAMPLES",
    "TIE",
    "VERDICTS",
    "classify",
    "coverage",
    "detectable",
    "difference_verdict",
    "equivalence",
    "holm",
    "improvement_interval",
    "median_interval",
    "p_text",
    "paired_difference",
    "paired_equivalence",
    "pairs_above",
    "probability_of_improvement",
    "seeds_for_power",
    "share_difference",
    "slope_test",
    "span_text",
    "t_interval",
    "welch_difference",
    "wilson_bounds",
    "wilson_interval",
]
