"""How often a 95 % interval over seeds holds the true mean: the t-interval the reports use
(``pursuit_bench.stats.coverage``) beside the percentile bootstrap they used before, on
normal and lognormal data, at 3, 5 and 10 seeds; 4000 simulated sets each; Welch's interval and the
equivalence test at the pool study's 8 runs a kind and at the rule study's 10, 20 and 30 (with
Wilson's interval of a failure share and the seed rule's type I error); and the median's
interval the pursuit-law fits give over attacks, at 3–20 values. Prints the tables
docs/statistics.md and docs/pursuit-law.md quote (seeded: the same table every time), then how skewed the seed-level
differences of results/reproduction are beside the simulated data, by the same measure.

    python studies/coverage/interval_coverage.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy import stats as scipy_stats

from pursuit_bench import stats
from pursuit_bench.reports import reproduction as report

ROOT = Path(__file__).resolve().parents[2]

DRAWS = 4000
RESAMPLES = 2000
SEEDS = (3, 5, 10)
#: (label, draw(rng, shape), true mean)
DISTRIBUTIONS = (
    ("normal", lambda rng, shape: rng.normal(0.0, 1.0, shape), 0.0),
    ("lognormal σ = 0.25 (skewness 0.78)", lambda rng, shape: rng.lognormal(0.0, 0.25, shape), math.exp(0.25**2 / 2)),
    ("lognormal σ = 0.5 (skewness 1.75)", lambda rng, shape: rng.lognormal(0.0, 0.5, shape), math.exp(0.5**2 / 2)),
)


def percentile_bootstrap_coverage(draw, truth: float, n: int, seed: int) -> float:  # type: ignore[no-untyped-def]
    """The same draws as :func:`stats.coverage` (same seed), each given the percentile
    bootstrap interval of its mean from RESAMPLES resamples."""
    rng = np.random.default_rng(seed)
    samples = np.asarray(draw(rng, (DRAWS, n)), dtype=float)
    resampler = np.random.default_rng(seed + 1)
    held = 0
    for chunk in np.array_split(samples, 40):
        means = np.take_along_axis(
            chunk[:, None, :], resampler.integers(0, n, (len(chunk), RESAMPLES, n)), axis=2
        ).mean(axis=2)
        low, high = np.quantile(means, [0.025, 0.975], axis=1)
        held += int(np.sum((low <= truth) & (truth <= high)))
    return held / DRAWS


def median_coverage(sigma: float, n: int, draws: int = 1000) -> float:
    """How often :func:`stats.median_interval` holds the true median of lognormal data
    (skewed, as fitted gains are) from ``n`` values; ``draws`` simulated sets."""
    rng = np.random.default_rng(n)
    held = 0
    for k in range(draws):
        interval = stats.median_interval(rng.lognormal(0.0, sigma, n), seed=k, minimum=1)
        held += interval is not None and interval[0] <= 1.0 <= interval[1]
    return held / draws


#: Runs a kind in the pool study (REPRODUCTION.md, "The pool study"): hierarchical and flat.
POOL_RUNS = 8
#: (label, draw of the hierarchical runs, draw of the flat runs, true difference)
WELCH_CASES = (
    ("normal, equal spread", lambda rng, s: rng.normal(0, 1, s), lambda rng, s: rng.normal(0, 1, s), 0.0),
    ("normal, spreads 1 and 3", lambda rng, s: rng.normal(0, 1, s), lambda rng, s: rng.normal(0, 3, s), 0.0),
    (
        "lognormal σ = 0.5 against normal",
        lambda rng, s: rng.lognormal(0, 0.5, s),
        lambda rng, s: rng.normal(0, 1, s),
        math.exp(0.125),
    ),
)


def welch_checks(margin: float = 0.05, sd: float = 0.03) -> None:
    """Welch's interval's coverage at the pool study's runs a kind, and the equivalence test's
    error: how often it calls two kinds equivalent when they differ by exactly the margin (at most
    2.5 % if it means what it says), and how often it does when they do not differ at all."""
    print(f"\n| Welch, {POOL_RUNS} runs a kind | coverage of the 95 % interval |\n|---|---:|")
    for label, draw_h, draw_f, truth in WELCH_CASES:
        rng = np.random.default_rng(1)
        h, f = draw_h(rng, (DRAWS, POOL_RUNS)), draw_f(rng, (DRAWS, POOL_RUNS))
        ci = [stats.welch_difference(x, y)["ci"] for x, y in zip(h, f, strict=True)]
        print(f"| {label} | {np.mean([lo <= truth <= hi for lo, hi in ci]):.1%} |")
    print(f"\n| true difference (runs' sd {sd}) | called equivalent within ±{margin} |\n|---:|---:|")
    for truth in (margin, 0.0):
        rng = np.random.default_rng(2)
        h, f = rng.normal(truth, sd, (DRAWS, POOL_RUNS)), rng.normal(0.0, sd, (DRAWS, POOL_RUNS))
        called = np.mean([stats.equivalence(x, y, margin)["p"] <= stats.ALPHA for x, y in zip(h, f, strict=True)])
        print(f"| {truth:+.2f} | {called:.1%} |")


#: Runs a kind in the rule study (REPRODUCTION.md, "Protocol of the rule study"): 10 at first, 20
#: and 30 where the seed rule adds them.
STUDY_RUNS = (10, 20, 30)
#: A split kind: most runs succeed near +0.2, a fifth fail near -0.2 (1p-high's flat runs, issue 47).
SPLIT_FAILURE = 0.2


def split(rng: np.random.Generator, shape: tuple[int, ...], failure: float = SPLIT_FAILURE) -> np.ndarray:
    """Pool returns of a kind whose runs split: N(+0.2, 0.05) or, with probability ``failure``, N(-0.2, 0.1)."""
    failed = rng.random(shape) < failure
    return np.where(failed, rng.normal(-0.2, 0.1, shape), rng.normal(0.2, 0.05, shape))


def rule_study_checks(margin: float = 0.05) -> None:
    """The rule study's intervals at its seed counts: Welch's interval (normal, unequal spreads,
    skewed, split against unsplit); Wilson's interval of a failure share; the type I error of the
    primary test at a fixed 10 runs and under the seed rule (a failed run among a panel's first
    10 of either kind: 10 more of both; again at 20; at most 30), both kinds split alike (no
    difference); and how often equivalence within the margin is called at a true difference of
    exactly the margin."""
    split_truth = (1 - SPLIT_FAILURE) * 0.2 + SPLIT_FAILURE * -0.2
    cases = (
        *WELCH_CASES,
        ("split (a fifth fail) against normal sd 0.05", split, lambda rng, s: rng.normal(split_truth, 0.05, s), 0.0),
    )
    print("\n| Welch | " + " | ".join(f"{n} runs a kind" for n in STUDY_RUNS) + " |\n|---|" + "---:|" * len(STUDY_RUNS))
    for label, draw_h, draw_f, truth in cases:
        held = []
        for n in STUDY_RUNS:
            rng = np.random.default_rng(n)
            h, f = draw_h(rng, (DRAWS, n)), draw_f(rng, (DRAWS, n))
            ci = [stats.welch_difference(x, y)["ci"] for x, y in zip(h, f, strict=True)]
            held.append(np.mean([lo <= truth <= hi for lo, hi in ci]))
        print(f"| {label} | " + " | ".join(f"{c:.1%}" for c in held) + " |")
    print(
        "\n| failure share | " + " | ".join(f"{n} runs" for n in STUDY_RUNS) + " |\n|---:|" + "---:|" * len(STUDY_RUNS)
    )
    for share in (0.1, 0.3, 0.5):
        held = []
        for n in STUDY_RUNS:
            counts = np.random.default_rng(n).binomial(n, share, DRAWS)
            intervals = {c: stats.wilson_interval(int(c), n) for c in np.unique(counts)}
            held.append(np.mean([intervals[c][0] <= share <= intervals[c][1] for c in counts]))
        print(f"| {share} | " + " | ".join(f"{c:.1%}" for c in held) + " |")
    rng = np.random.default_rng(3)
    fixed = rule = 0
    sizes = []
    for _ in range(DRAWS):
        h, f = split(rng, (30,)), split(rng, (30,))
        n = 10
        while n < 30 and ((h[:n] < 0).any() or (f[:n] < 0).any()):
            n += 10
        sizes.append(n)
        fixed += stats.welch_difference(h[:10], f[:10])["p"] <= 2 * stats.ALPHA
        rule += stats.welch_difference(h[:n], f[:n])["p"] <= 2 * stats.ALPHA
    print(
        f"\nno true difference, both kinds split (a fifth fail): the primary test rejects {fixed / DRAWS:.1%} "
        f"at 10 runs, {rule / DRAWS:.1%} under the seed rule (runs a kind: mean {np.mean(sizes):.1f}; "
        f"30 in {np.mean(np.array(sizes) == 30):.0%})"
    )
    for n in STUDY_RUNS:
        rng = np.random.default_rng(4)
        h, f = rng.normal(margin, 0.05, (DRAWS, n)), rng.normal(0.0, 0.05, (DRAWS, n))
        called = np.mean([stats.equivalence(x, y, margin)["p"] <= stats.ALPHA for x, y in zip(h, f, strict=True)])
        print(f"true difference {margin:+.2f} (runs' sd 0.05), {n} runs a kind: called equivalent {called:.1%}")


def pooled_skewness(groups: np.ndarray | list[np.ndarray]) -> float:
    """The sample skewness of values standardised within their group (a comparison's seeds)."""
    z = [(g - g.mean()) / g.std(ddof=1) for g in map(np.asarray, groups)]
    return float(scipy_stats.skew(np.concatenate(z)))


def coverage_markdown() -> str:
    """docs/statistics.md's coverage table: the t-interval beside the percentile bootstrap."""
    lines = ["| data | seeds | t-interval | percentile bootstrap |", "|---|---:|---:|---:|"]
    for label, draw, truth in DISTRIBUTIONS:
        for n in SEEDS:
            t = stats.coverage(draw, truth, n, DRAWS, seed=n)
            bootstrap = percentile_bootstrap_coverage(draw, truth, n, seed=n)
            lines.append(f"| {label} | {n} | {t:.1%} | {bootstrap:.1%} |")
    return "\n".join(lines) + "\n"


def skewness_figures() -> dict[str, float]:
    """How skewed the reproduction's seed-level differences are (pooled over its comparisons,
    standardised within each), and the same measure on as many simulated groups of each
    distribution: docs/statistics.md quotes them."""
    table = report.panel_table(report.collect(ROOT / "results" / "reproduction"))
    ours = [np.array(c["differences"]) for t in table for c in t.get("paired", {}).values()]
    n, rng = len(ours[0]), np.random.default_rng(0)
    figures = {"results/reproduction": pooled_skewness(ours)}
    for label, draw, _ in DISTRIBUTIONS:
        figures[label] = pooled_skewness(list(draw(rng, (len(ours) * 50, n))))
    return figures


#: Runs a kind in the MARL rows' comparisons (studies/marl/PLAN.md): three seeds of each learner.
MARL_RUNS = 3


def marl_markdown() -> str:
    """Welch's interval at the MARL rows' 3 runs a kind: the unsplit cases; then a learner whose
    runs each fail with probability 1/3 (near -0.2, else near +0.2: :func:`split`) against one
    that does not, overall and by how many of its three runs failed (what a reader sees)."""
    lines = [f"| Welch, {MARL_RUNS} runs a kind | coverage of the 95 % interval |", "|---|---:|"]
    for label, draw_a, draw_b, truth in WELCH_CASES:
        rng = np.random.default_rng(MARL_RUNS)
        a, b = draw_a(rng, (DRAWS, MARL_RUNS)), draw_b(rng, (DRAWS, MARL_RUNS))
        ci = [stats.welch_difference(x, y)["ci"] for x, y in zip(a, b, strict=True)]
        lines.append(f"| {label} | {np.mean([lo <= truth <= hi for lo, hi in ci]):.1%} |")
    rng = np.random.default_rng(MARL_RUNS)
    shape = (DRAWS, MARL_RUNS)
    failed = rng.random(shape) < 1 / 3  # split()'s draws, in its order, keeping which runs failed
    a = np.where(failed, rng.normal(-0.2, 0.1, shape), rng.normal(0.2, 0.05, shape))
    b = rng.normal((2 * 0.2 - 0.2) / 3, 0.05, shape)
    held = np.array(
        [lo <= 0.0 <= hi for lo, hi in (stats.welch_difference(x, y)["ci"] for x, y in zip(a, b, strict=True))]
    )
    lines.append(f"| each run fails with probability 1/3, against normal sd 0.05 | {held.mean():.1%} |")
    lines += ["", "| of the split learner's 3 runs, failed | share of the draws | coverage |", "|---:|---:|---:|"]
    count = failed.sum(axis=1)
    for k in range(MARL_RUNS + 1):
        lines.append(f"| {k} | {np.mean(count == k):.1%} | {held[count == k].mean():.1%} |")
    return "\n".join(lines)


def main() -> None:
    print(coverage_markdown())
    welch_checks()
    rule_study_checks()
    print()
    print(marl_markdown())
    print("\n| median of attacks' gains, lognormal σ | values | percentile bootstrap (stats.median_interval) |")
    print("|---:|---:|---:|")
    for sigma in (0.3, 0.6):
        for n in (3, 5, 10, 20):
            print(f"| {sigma} | {n} | {median_coverage(sigma, n):.1%} |")
    print("\npooled skewness of the seed-level differences, and of as many simulated groups:")
    for label, value in skewness_figures().items():
        print(f"  {label}: {value:+.2f}")


if __name__ == "__main__":
    main()
