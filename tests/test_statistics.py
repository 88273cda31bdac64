"""The statistics module against hand computations, worked examples, scipy, and simulation."""

import math

import numpy as np
import pytest
from scipy import stats

from pursuit_bench.study import report, statistics


def test_the_paired_difference_and_its_t_interval_by_hand() -> None:
    ours = [0.50, 0.42, 0.61, 0.47]
    theirs = [0.40, 0.40, 0.45, 0.45]
    d = [0.10, 0.02, 0.16, 0.02]  # seed by seed
    mean = sum(d) / 4  # 0.075
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / 3)
    half = 3.182446305284263 * sd / 2  # t(0.975, 3) * sd / sqrt(4)
    result = statistics.paired_difference(ours, theirs)
    assert result["differences"] == pytest.approx(d)
    assert result["mean"] == pytest.approx(mean) and result["sd"] == pytest.approx(sd)
    assert result["ci"] == pytest.approx([mean - half, mean + half])
    t = mean / (sd / 2)
    assert result["t"] == pytest.approx(t)
    reference = stats.ttest_rel(ours, theirs, alternative="greater")
    assert result["p_greater"] == pytest.approx(reference.pvalue)
    assert result["p_less"] == pytest.approx(stats.ttest_rel(ours, theirs, alternative="less").pvalue)
    with pytest.raises(ValueError, match="same seeds"):
        statistics.paired_difference([1.0, 2.0], [1.0])


def test_welch_against_scipy_and_by_hand() -> None:
    a, b = [0.50, 0.42, 0.61, 0.47, 0.55], [0.30, 0.45, 0.20]
    result = statistics.welch_difference(a, b)
    va, vb = np.var(a, ddof=1) / 5, np.var(b, ddof=1) / 3
    df = (va + vb) ** 2 / (va**2 / 4 + vb**2 / 2)
    half = stats.t.ppf(0.975, df) * math.sqrt(va + vb)
    assert result["mean"] == pytest.approx(np.mean(a) - np.mean(b))
    assert result["ci"] == pytest.approx([result["mean"] - half, result["mean"] + half])
    assert result["p"] == pytest.approx(stats.ttest_ind(a, b, equal_var=False).pvalue)


def test_holm_against_a_worked_example() -> None:
    # sorted: 0.005*4 = 0.02, 0.01*3 = 0.03, 0.03*2 = 0.06, 0.04*1 = 0.04 -> kept at 0.06
    adjusted = statistics.holm([0.01, 0.04, 0.03, 0.005])
    assert adjusted.tolist() == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert statistics.holm([0.5, 0.9]).tolist() == [1.0, 1.0]  # capped at one
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        statistics.holm([0.1, 1.5])


def test_a_tie_is_never_a_win() -> None:
    tied = statistics.paired_difference([0.3, 0.3, 0.3], [0.3, 0.3, 0.3])
    assert tied["p_greater"] == tied["p_less"] == 0.5 and tied["ci"] == [0.0, 0.0]
    zero_mean = statistics.paired_difference([0.3, 0.5, 0.4], [0.4, 0.4, 0.4])
    assert zero_mean["mean"] == pytest.approx(0.0) and zero_mean["p_greater"] == pytest.approx(0.5)
    comparisons = {b: {**tied, "p_greater_holm": 0.5, "p_less_holm": 0.5} for b in report.BASELINES}
    assert statistics.classify(comparisons) == "not resolved"
    # a seed-by-seed tie in the strict count, and equal means, are no wins either
    variant = {"mean": 0.3, "ci": None, "seeds": [0, 1], "values": [0.3, 0.3], "runs": []}
    table = [
        {
            "condition": "1p-high",
            "predator": "predator_0",
            "variants": {
                "hierarchical": variant,
                "always_chase": variant,
                "always_stalk": {**variant, "values": [0.1, 0.1], "mean": 0.1},
            },
            "paired": comparisons,
        }
    ]
    assert report.strict_counts(table)["counts"] == [0, 0]
    assert report.above_both_on_means(table) == 0


def test_classification_follows_the_corrected_tests() -> None:
    def comparison(mean: float, greater: float, less: float) -> dict:
        return {"mean": mean, "p_greater_holm": greater, "p_less_holm": less}

    better = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(0.1, 0.02, 1.0)}
    assert statistics.classify(better) == "better"
    one_side = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(0.01, 0.2, 1.0)}
    assert statistics.classify(one_side) == "not resolved"
    worse = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(-0.05, 1.0, 0.01)}
    assert statistics.classify(worse) == "worse"


def test_the_t_interval_covers_what_it_claims() -> None:
    """4000 simulated sets of seeds each, normal and skewed (lognormal, σ = 0.25: skewness 0.78,
    more than the seed-level differences of results/reproduction show), at 3, 5 and 10 seeds:
    the 95 % t-interval holds the true mean 95 % of the time, within two points."""
    sigma = 0.25
    for n in (3, 5, 10):
        normal = statistics.coverage(lambda rng, shape: rng.normal(0.1, 0.05, shape), 0.1, n, 4000, seed=n)
        skewed = statistics.coverage(
            lambda rng, shape: rng.lognormal(0.0, sigma, shape), math.exp(sigma**2 / 2), n, 4000, seed=n
        )
        assert abs(normal - 0.95) <= 0.02, (n, normal)
        assert abs(skewed - 0.95) <= 0.02, (n, skewed)


def test_seeds_for_power_against_the_textbook_value() -> None:
    # a paired t-test, effect size 0.5, two-sided 5 % (one-sided 2.5 %), 80 % power: 34 pairs
    assert statistics.seeds_for_power(sd=1.0, delta=0.5) == 34
    assert statistics.seeds_for_power(sd=0.1, delta=0.05) == 34
    assert statistics.seeds_for_power(sd=0.1, delta=0.05, alpha=0.05 / 44) > 34
    # what n seeds could have detected: the inverse of seeds_for_power
    delta = statistics.detectable(sd=1.0, n=34)
    assert 0.48 < delta <= 0.5
    with pytest.raises(ValueError, match="delta > 0"):
        statistics.seeds_for_power(sd=1.0, delta=0.0)


def test_the_probability_of_improvement_is_mann_whitney_averaged_over_panels() -> None:
    rng = np.random.default_rng(3)
    xs = [rng.normal(0.1 * k, 1.0, 10).round(1) for k in range(4)]  # rounded: ties happen
    ys = [rng.normal(0.0, 1.0, 7).round(1) for _ in range(4)]
    naive = np.mean(
        [
            stats.mannwhitneyu(x, y, alternative="greater").statistic / (len(x) * len(y))
            for x, y in zip(xs, ys, strict=True)
        ]
    )
    assert statistics.probability_of_improvement(xs, ys) == pytest.approx(naive)
    result = statistics.improvement_interval(xs, ys, resamples=500)
    assert result["ci"][0] < result["value"] < result["ci"][1]
    assert statistics.improvement_interval(xs, ys, resamples=500) == result  # seeded


def test_the_slope_test_tells_a_trend_from_a_plateau() -> None:
    rng = np.random.default_rng(0)
    x = np.array([10.5, 12.75, 15.0])
    rising = [0.02 * x + rng.normal(0, 0.005, 3) for _ in range(10)]
    flat = [0.3 + rng.normal(0, 0.002, 3) for _ in range(10)]
    noisy = [0.3 + (-1) ** k * 0.05 * (x - 12.75) for k in range(10)]  # seeds disagree: slopes ±0.05
    assert statistics.slope_test(rising, x, tolerance=0.004)["verdict"] == "rising"
    assert statistics.slope_test(flat, x, tolerance=0.004)["verdict"] == "flat"
    unresolved = statistics.slope_test(noisy, x, tolerance=0.004)
    assert unresolved["verdict"] == "not resolved" and unresolved["detectable"] > 0.004


def test_the_median_interval_needs_five_values_and_holds_the_median() -> None:
    assert statistics.median_interval([1.0, 2.0, 3.0, 4.0], seed=0) is None
    assert statistics.median_interval([2.0] * 8, seed=0) is None
    values = np.random.default_rng(0).lognormal(0.0, 0.5, 20)
    low, high = statistics.median_interval(values, seed=0)  # type: ignore[misc]
    assert low < np.median(values) < high
    assert statistics.median_interval(values, seed=0) == [low, high]  # seeded: the same every time
