"""The statistics module against hand computations, worked examples, scipy, and simulation."""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import load_script
from scipy import stats as scipy_stats

from pursuit_bench import stats
from pursuit_bench.reports import reproduction as report

ROOT = Path(__file__).resolve().parents[1]


def test_the_paired_difference_and_its_t_interval_by_hand() -> None:
    ours = [0.50, 0.42, 0.61, 0.47]
    theirs = [0.40, 0.40, 0.45, 0.45]
    d = [0.10, 0.02, 0.16, 0.02]  # seed by seed
    mean = sum(d) / 4  # 0.075
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / 3)
    half = 3.182446305284263 * sd / 2  # t(0.975, 3) * sd / sqrt(4)
    result = stats.paired_difference(ours, theirs)
    assert result["differences"] == pytest.approx(d)
    assert result["mean"] == pytest.approx(mean) and result["sd"] == pytest.approx(sd)
    assert result["ci"] == pytest.approx([mean - half, mean + half])
    t = mean / (sd / 2)
    assert result["t"] == pytest.approx(t)
    reference = scipy_stats.ttest_rel(ours, theirs, alternative="greater")
    assert result["p_greater"] == pytest.approx(reference.pvalue)
    assert result["p_less"] == pytest.approx(scipy_stats.ttest_rel(ours, theirs, alternative="less").pvalue)
    with pytest.raises(ValueError, match="same seeds"):
        stats.paired_difference([1.0, 2.0], [1.0])


def test_welch_against_scipy_and_by_hand() -> None:
    a, b = [0.50, 0.42, 0.61, 0.47, 0.55], [0.30, 0.45, 0.20]
    result = stats.welch_difference(a, b)
    va, vb = np.var(a, ddof=1) / 5, np.var(b, ddof=1) / 3
    df = (va + vb) ** 2 / (va**2 / 4 + vb**2 / 2)
    half = scipy_stats.t.ppf(0.975, df) * math.sqrt(va + vb)
    assert result["mean"] == pytest.approx(np.mean(a) - np.mean(b))
    assert result["ci"] == pytest.approx([result["mean"] - half, result["mean"] + half])
    assert result["p"] == pytest.approx(scipy_stats.ttest_ind(a, b, equal_var=False).pvalue)


def test_holm_against_a_worked_example() -> None:
    # sorted: 0.005*4 = 0.02, 0.01*3 = 0.03, 0.03*2 = 0.06, 0.04*1 = 0.04 -> kept at 0.06
    adjusted = stats.holm([0.01, 0.04, 0.03, 0.005])
    assert adjusted.tolist() == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert stats.holm([0.5, 0.9]).tolist() == [1.0, 1.0]  # capped at one
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        stats.holm([0.1, 1.5])


def test_a_tie_is_never_a_win() -> None:
    tied = stats.paired_difference([0.3, 0.3, 0.3], [0.3, 0.3, 0.3])
    assert tied["p_greater"] == tied["p_less"] == 0.5 and tied["ci"] == [0.0, 0.0]
    zero_mean = stats.paired_difference([0.3, 0.5, 0.4], [0.4, 0.4, 0.4])
    assert zero_mean["mean"] == pytest.approx(0.0) and zero_mean["p_greater"] == pytest.approx(0.5)
    comparisons = {b: {**tied, "p_greater_holm": 0.5, "p_less_holm": 0.5} for b in report.BASELINES}
    assert stats.classify(comparisons) == "not resolved"
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
    def comparison(mean: float, greater: float, less: float, equivalent: float = 1.0) -> dict:
        return {"mean": mean, "p_greater_holm": greater, "p_less_holm": less, "p_equivalent_holm": equivalent}

    better = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(0.1, 0.02, 1.0)}
    assert stats.classify(better) == "better"
    one_side = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(0.01, 0.2, 1.0)}
    assert stats.classify(one_side) == "not resolved"
    worse = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(-0.05, 1.0, 0.01)}
    assert stats.classify(worse) == "worse"
    # the weaker baseline (the smaller deficit) significantly ahead, the stronger one too noisy to
    # say: a fixed mode beats the learned switch, so the panel is worse
    weaker_ahead = {"always_chase": comparison(-0.02, 1.0, 0.01), "always_stalk": comparison(-0.2, 1.0, 0.3)}
    assert stats.classify(weaker_ahead) == "worse"
    # ahead of one, within the margin of the other: equivalent; within the margin of neither: not
    level = {"always_chase": comparison(0.3, 0.001, 1.0), "always_stalk": comparison(0.01, 0.2, 0.5, 0.004)}
    assert stats.classify(level) == "equivalent"
    both_level = {"always_chase": comparison(0.0, 0.5, 0.5, 0.01), "always_stalk": comparison(0.0, 0.5, 0.5, 0.02)}
    assert stats.classify(both_level) == "equivalent"
    one_level = {"always_chase": comparison(0.0, 0.5, 0.5, 0.01), "always_stalk": comparison(0.0, 0.5, 0.5, 0.03)}
    assert stats.classify(one_level) == "not resolved"
    # significance wins over equivalence: ahead of both is better even where within the margin
    close_ahead = {b: comparison(0.02, 0.001, 1.0, 0.001) for b in ("always_chase", "always_stalk")}
    assert stats.classify(close_ahead) == "better"


def test_paired_equivalence_against_a_worked_example() -> None:
    # differences 0.01, 0.03, -0.01, 0.02, 0.00: mean 0.01, sd 0.015811, se 0.0070711, 4 df
    d = [0.01, 0.03, -0.01, 0.02, 0.00]
    result = stats.paired_equivalence(d, 0.05)
    # H0 difference >= +0.05: t = (0.01 - 0.05) / 0.0070711 = -5.6569, P(T4 <= t) = 0.0024063;
    # H0 difference <= -0.05: t = 8.4853, smaller; the larger p is the first
    assert result["p"] == pytest.approx(0.0024063, abs=2e-7)
    # the 95 % t-interval 0.01 ± 2.7764 * 0.0070711 = [-0.009632, 0.029632]
    assert result["bound"] == pytest.approx(0.029632, abs=1e-6)
    assert stats.paired_equivalence(d, result["bound"] * 0.99)["p"] > 0.025
    assert stats.paired_equivalence(d, result["bound"] * 1.01)["p"] < 0.025
    assert stats.paired_equivalence([0.02] * 4, 0.05)["p"] == 0.0  # no spread, inside
    with pytest.raises(ValueError, match="margin"):
        stats.paired_equivalence(d, -0.1)


def test_the_t_interval_covers_what_it_claims() -> None:
    """4000 simulated sets of seeds each, normal and skewed (lognormal, σ = 0.25: skewness 0.78,
    more than the seed-level differences of results/reproduction show), at 3, 5 and 10 seeds:
    the 95 % t-interval holds the true mean 95 % of the time, within two points."""
    sigma = 0.25
    for n in (3, 5, 10):
        normal = stats.coverage(lambda rng, shape: rng.normal(0.1, 0.05, shape), 0.1, n, 4000, seed=n)
        skewed = stats.coverage(
            lambda rng, shape: rng.lognormal(0.0, sigma, shape), math.exp(sigma**2 / 2), n, 4000, seed=n
        )
        assert abs(normal - 0.95) <= 0.02, (n, normal)
        assert abs(skewed - 0.95) <= 0.02, (n, skewed)


def test_wilson_s_interval_is_where_the_score_test_does_not_reject() -> None:
    # Wilson's interval is every p whose score test of the observed share does not reject:
    # (share - p)^2 <= z^2 p (1 - p) / n, a quadratic in p solved here by numpy's roots
    z = scipy_stats.norm.ppf(0.975)
    for count, n in ((0, 10), (3, 10), (10, 10), (7, 30), (1, 1)):
        share = count / n
        roots = np.sort(np.roots([1 + z * z / n, -(2 * share + z * z / n), share * share]).real)
        low, high = stats.wilson_interval(count, n)
        assert low == pytest.approx(max(roots[0], 0.0), abs=1e-12)
        assert high == pytest.approx(min(roots[1], 1.0), abs=1e-12)
    shares, trials = np.array([0.3, np.nan, 0.5]), np.array([10.0, 5.0, 0.0])
    low, high = stats.wilson_bounds(shares, trials)
    assert [low[0], high[0]] == stats.wilson_interval(3, 10)
    assert np.isnan(low[1:]).all() and np.isnan(high[1:]).all()
    with pytest.raises(ValueError, match="0 <= count <= n"):
        stats.wilson_interval(11, 10)


def test_seeds_for_power_against_the_textbook_value() -> None:
    # a paired t-test, effect size 0.5, two-sided 5 % (one-sided 2.5 %), 80 % power: 34 pairs
    assert stats.seeds_for_power(sd=1.0, delta=0.5) == 34
    assert stats.seeds_for_power(sd=0.1, delta=0.05) == 34
    assert stats.seeds_for_power(sd=0.1, delta=0.05, alpha=0.05 / 44) > 34
    # what n seeds could have detected: the inverse of seeds_for_power
    delta = stats.detectable(sd=1.0, n=34)
    assert 0.48 < delta <= 0.5
    with pytest.raises(ValueError, match="delta > 0"):
        stats.seeds_for_power(sd=1.0, delta=0.0)


def test_the_probability_of_improvement_is_mann_whitney_averaged_over_panels() -> None:
    rng = np.random.default_rng(3)
    xs = [rng.normal(0.1 * k, 1.0, 10).round(1) for k in range(4)]  # rounded: ties happen
    ys = [rng.normal(0.0, 1.0, 7).round(1) for _ in range(4)]
    naive = np.mean(
        [
            scipy_stats.mannwhitneyu(x, y, alternative="greater").statistic / (len(x) * len(y))
            for x, y in zip(xs, ys, strict=True)
        ]
    )
    assert stats.probability_of_improvement(xs, ys) == pytest.approx(naive)
    result = stats.improvement_interval(xs, ys, resamples=500)
    assert result["ci"][0] < result["value"] < result["ci"][1]
    # the resamples come from the seed: another seed draws others, the same seed the same ones
    other = stats.improvement_interval(xs, ys, seed=1, resamples=500)
    assert other["value"] == result["value"] and other["ci"] != result["ci"]
    assert stats.improvement_interval(xs, ys, seed=1, resamples=500) == other


def test_the_slope_test_tells_a_trend_from_a_plateau() -> None:
    rng = np.random.default_rng(0)
    x = np.array([10.5, 12.75, 15.0])
    rising = [0.02 * x + rng.normal(0, 0.005, 3) for _ in range(10)]
    flat = [0.3 + rng.normal(0, 0.002, 3) for _ in range(10)]
    noisy = [0.3 + (-1) ** k * 0.05 * (x - 12.75) for k in range(10)]  # seeds disagree: slopes ±0.05
    assert stats.slope_test(rising, x, tolerance=0.004)["verdict"] == "rising"
    assert stats.slope_test(flat, x, tolerance=0.004)["verdict"] == "flat"
    unresolved = stats.slope_test(noisy, x, tolerance=0.004)
    assert unresolved["verdict"] == "not resolved" and unresolved["detectable"] > 0.004


def test_the_median_interval_against_the_exact_bootstrap_distribution() -> None:
    assert stats.median_interval([1.0, 2.0, 3.0, 4.0], seed=0) is None
    assert stats.median_interval([2.0] * 8, seed=0) is None
    # 0, 1, …, 10: a resample's median is at most k when 6 or more of its 11 draws are, so
    # P(median <= k) = P(Binomial(11, (k + 1) / 11) >= 6): 0.007 at k = 1, 0.051 at 2, 0.949 at
    # 7, 0.993 at 8. The 2.5 % and 97.5 % points of the bootstrap distribution are 2 and 8, more
    # than five binomial standard errors of 2000 resamples from the steps: found whatever the seed.
    values = np.arange(11.0)
    for seed in (0, 1, 2, 3):
        assert stats.median_interval(values, seed=seed) == [2.0, 8.0]
    # the resamples come from the seed: on 200 values (at 20 or 51 the interval's ends sit on the
    # same order statistics whatever the seed) another seed gives another interval, the same seed
    # the same one
    skewed = np.random.default_rng(0).lognormal(0.0, 0.5, 200)
    first, second = stats.median_interval(skewed, seed=0), stats.median_interval(skewed, seed=1)
    assert first is not None and second is not None and first != second
    assert stats.median_interval(skewed, seed=1) == second


@pytest.mark.slow
@pytest.mark.long
def test_statistics_md_prints_what_its_script_gives() -> None:
    """docs/statistics.md's coverage table and skewness figures are what
    studies/coverage/interval_coverage.py computes (seeded: the same every time)."""
    interval_coverage = load_script("studies/coverage/interval_coverage.py")
    text = (ROOT / "docs" / "statistics.md").read_text()
    assert interval_coverage.coverage_markdown() in text
    assert interval_coverage.marl_markdown() in text  # the MARL rows' 3 seeds a learner
    figures = interval_coverage.skewness_figures()
    ours, normal, mild, strong = (f"{v:+.2f}".replace("-", "−") for v in figures.values())
    normal = normal.lstrip("+−") if normal in ("+0.00", "−0.00") else normal
    words = " ".join(text.split())
    assert f"sample skewness of {ours};" in words
    assert (
        f"normal data give {normal}, the lognormal with σ = 0.25 of the test {mild} and the one with σ = 0.5 {strong}"
        in words
    )


def test_the_strict_count_uses_the_seeds_every_panel_has() -> None:
    """A sweep under way may have evaluated more seeds of one condition than of another: the
    count per seed is over the seeds all panels share, each panel's values read by seed."""

    def variant(values: list[float], seeds: list[int]) -> dict:
        return {"mean": float(np.mean(values)), "ci": None, "seeds": seeds, "values": values, "runs": []}

    table = [
        {
            "condition": "1p-low",
            "predator": "predator_0",
            "variants": {
                "hierarchical": variant([0.5, 0.1, 0.9], [0, 1, 2]),
                "always_chase": variant([0.4, 0.2, 0.0], [0, 1, 2]),
                "always_stalk": variant([0.0, 0.0, 0.0], [0, 1, 2]),
            },
            "paired": {},
        },
        {
            "condition": "1p-high",
            "predator": "predator_0",
            "variants": {
                "hierarchical": variant([0.3, 0.3], [1, 2]),
                "always_chase": variant([0.1, 0.4], [1, 2]),
                "always_stalk": variant([0.2, 0.2], [1, 2]),
            },
            "paired": {},
        },
    ]
    counts = report.strict_counts(table)
    assert counts["seeds"] == [1, 2] and counts["counts"] == [1, 1]  # seed 1: 1p-high wins; seed 2: 1p-low wins


def _boschloo_by_hand(a: int, n_a: int, b: int, n_b: int) -> float:
    """Boschloo's two-sided p of two binomial samples (a of n_a, b of n_b), from its definition:
    the one-sided Fisher p as the statistic, its tail's probability maximised over the common
    success probability on a fine grid, twice the smaller one-sided p."""
    ii, jj = np.meshgrid(np.arange(n_a + 1), np.arange(n_b + 1), indexing="ij")
    total = ii + jj
    # Fisher's one-sided p of every outcome: P(X >= i) and P(X <= i), X hypergeometric given i + j
    greater = scipy_stats.hypergeom.sf(ii - 1, n_a + n_b, total, n_a)
    less = scipy_stats.hypergeom.cdf(ii, n_a + n_b, total, n_a)
    grid = np.linspace(0.0005, 0.9995, 2000)
    p_a = scipy_stats.binom.pmf(np.arange(n_a + 1)[None], n_a, grid[:, None])
    p_b = scipy_stats.binom.pmf(np.arange(n_b + 1)[None], n_b, grid[:, None])
    weights = p_a[:, :, None] * p_b[:, None, :]  # grid × outcomes of a × outcomes of b
    one_sided = []
    for statistic in (greater, less):
        tail = statistic <= statistic[a, b] * (1 + 1e-13)  # relative, as the p can be tiny
        one_sided.append(float((weights * tail[None]).sum(axis=(1, 2)).max()))
    return min(1.0, 2 * min(one_sided))


@pytest.mark.parametrize("a, n_a, b, n_b", [(0, 30, 10, 30), (10, 30, 0, 30), (3, 10, 20, 30), (19, 30, 26, 30)])
def test_the_difference_of_two_failure_shares_is_boschloo_s_test_of_two_binomial_samples(
    a: int, n_a: int, b: int, n_b: int
) -> None:
    result = stats.share_difference(a, n_a, b, n_b)
    assert result["difference"] == pytest.approx(a / n_a - b / n_b)
    assert result["p"] == pytest.approx(_boschloo_by_hand(a, n_a, b, n_b), rel=1e-4)
    # the same counts read the other way round (the kinds as rows) give another p: the test tells them apart
    swapped = stats.share_difference(a, a + b, n_a - a, n_a - a + n_b - b)["p"]
    assert swapped != pytest.approx(result["p"], rel=0.05)


def test_measures_equal_but_for_their_last_bits_are_ties() -> None:
    summed = 0.1 + 0.2 + 0.3  # 0.6 in exact arithmetic, 0.6000000000000001 in floats
    assert summed != 0.6
    above = np.array([summed, 0.9])
    below = np.array([0.6, 0.2])
    # summed vs 0.6 is a tie (half); the other three pairs are clear wins
    assert stats.probability_of_improvement([above], [below]) == pytest.approx(3.5 / 4)


def _study_coverage():  # type: ignore[no-untyped-def]
    return load_script("studies/coverage/study_coverage.py")


def test_a_study_s_coverage_check_finds_the_known_answers() -> None:
    """studies/coverage/study_coverage.py's resampled worlds: normal runs give Welch's interval about its
    95 %; one run of 30 carrying the whole difference gives what counting says, since a draw
    without it (probability (29/30)^30) has an interval of width 0 that misses the truth."""
    study_coverage = _study_coverage()
    rng = np.random.default_rng(5)
    assert 0.93 <= study_coverage.welch_coverage(rng.normal(0, 1, 30), rng.normal(0.3, 2, 30), seed=0) <= 0.965
    lonely = np.r_[np.zeros(29), 1.0]
    expected = 1 - (29 / 30) ** 30
    assert study_coverage.welch_coverage(lonely, np.zeros(30), seed=0) == pytest.approx(expected, abs=0.03)
    assert 0.93 <= study_coverage.paired_coverage(rng.normal(0.1, 1, 30), seed=0) <= 0.965
    assert study_coverage.paired_coverage(lonely, seed=0) == pytest.approx(expected, abs=0.03)


@pytest.mark.long
def test_the_residual_study_s_committed_coverage_is_what_its_script_gives() -> None:
    """results/residual-study/interval-coverage.md (docs/residual.md cites it) is what
    studies/coverage/study_coverage.py computes from the committed runs (seeded)."""
    study_coverage = _study_coverage()
    committed = (ROOT / "results" / "residual-study" / "interval-coverage.md").read_text()
    assert committed.endswith(study_coverage.tables(ROOT / "results" / "residual-study"))


@pytest.mark.long
def test_a_study_s_coverage_rows_keep_their_values_as_settings_join(tmp_path: Path) -> None:
    """Each row is seeded by its own names, not its place: 3p-low-individual's rows computed from
    its runs alone are the rows the committed file (every judged setting) holds for it."""
    study_coverage = _study_coverage()
    source = ROOT / "results" / "residual-study"
    alone = tmp_path / "residual-study"
    (alone / "runs").mkdir(parents=True)
    shutil.copy(source / "residual-study.json", alone)
    for run in (source / "runs").glob("3p-low-individual-*.json.gz"):
        shutil.copy(run, alone / "runs")
    rows = [line for line in study_coverage.tables(alone).splitlines() if "| 3p-low-individual |" in line]
    committed = (source / "interval-coverage.md").read_text().splitlines()
    assert len(rows) == 6 + 9  # the primary's 3 panels x 2 comparisons, and 3 ladders x 3 rungs
    assert rows == [line for line in committed if "| 3p-low-individual |" in line]
