"""The common-opponent-pool study: its statistics against hand computations and simulation, its
plan (no judged run meets its own prey), and the command on a tiny sweep of both kinds."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run_cli
from scipy import stats as scipy_stats

from pursuit_bench import stats
from pursuit_bench.reports import pool


def test_the_equivalence_test_against_a_worked_example() -> None:
    a, b = [0.50, 0.52, 0.47, 0.51], [0.49, 0.50, 0.46, 0.53, 0.50]
    va, vb = np.var(a, ddof=1) / 4, np.var(b, ddof=1) / 5
    se = math.sqrt(va + vb)
    df = (va + vb) ** 2 / (va**2 / 3 + vb**2 / 4)
    mean = np.mean(a) - np.mean(b)  # +0.0045
    # H0 "difference <= -0.05" rejected by t = (mean + 0.05) / se, H0 "difference >= +0.05" by (mean - 0.05) / se
    p = max(scipy_stats.t.sf((mean + 0.05) / se, df), scipy_stats.t.cdf((mean - 0.05) / se, df))
    result = stats.equivalence(a, b, 0.05)
    assert result["p"] == pytest.approx(p) and result["p"] < 0.025
    half = scipy_stats.t.ppf(0.975, df) * se  # the 1 - 2 alpha = 95 % Welch interval
    assert result["bound"] == pytest.approx(max(abs(mean - half), abs(mean + half)))
    assert stats.equivalence(a, b, result["bound"] * 0.99)["p"] > 0.025  # just inside the bound: not shown
    assert stats.equivalence(a, b, result["bound"] * 1.01)["p"] < 0.025
    with pytest.raises(ValueError, match="margin=0"):
        stats.equivalence(a, b, 0)


def test_welch_intervals_cover_at_the_study_s_eight_runs_a_kind() -> None:
    rng = np.random.default_rng(7)
    draws = 3000
    for spread_b, skew in ((1.0, False), (3.0, False), (1.0, True)):
        a = rng.lognormal(0, 0.5, (draws, 8)) if skew else rng.normal(0, 1.0, (draws, 8))
        b = rng.normal(0, spread_b, (draws, 8))
        truth = math.exp(0.125) if skew else 0.0
        held = np.mean(
            [lo <= truth <= hi for lo, hi in (stats.welch_difference(x, y)["ci"] for x, y in zip(a, b, strict=True))]
        )
        assert 0.935 <= held <= 0.965, (spread_b, skew, held)


def _row(h: list[float], f: list[float]) -> dict:
    return {"condition": "1p-high", "predator": "predator_0", "hierarchical": h, "flat": f}


def test_the_four_verdicts_on_made_up_runs() -> None:
    rng = np.random.default_rng(0)
    flat_ahead = _row(list(0.2 + 0.02 * rng.standard_normal(8)), list(0.5 + 0.02 * rng.standard_normal(8)))
    rule_ahead = _row(list(0.5 + 0.02 * rng.standard_normal(8)), list(0.2 + 0.02 * rng.standard_normal(8)))
    alike = _row(list(0.3 + 0.005 * rng.standard_normal(8)), list(0.3 + 0.005 * rng.standard_normal(8)))
    noisy = _row(list(0.3 + 0.3 * rng.standard_normal(8)), list(0.32 + 0.3 * rng.standard_normal(8)))
    rows = [flat_ahead, rule_ahead, alike, noisy]
    counts = pool.compare(rows)
    assert [r["verdict"] for r in rows] == ["flat better", "rule helps", "equivalent", "not resolved"]
    assert counts == {"rule helps": 1, "flat better": 1, "equivalent": 1, "not resolved": 1}
    assert flat_ahead["difference"]["ci"][1] < 0 and flat_ahead["difference"]["p_holm"] <= 0.05
    # Holm over the family: the adjusted p-values are the raw ones stepped up
    raw = [r["difference"]["p"] for r in rows]
    assert [r["difference"]["p_holm"] for r in rows] == pytest.approx(stats.holm(raw).tolist())


def test_a_pool_margin_is_the_mean_over_opponents_minus_the_better_fixed_mode() -> None:
    evaluations = {
        "FleeingPrey": {"panels": {"predator_0": [0.6, 0.5, 0.1]}},
        "a": {"panels": {"predator_0": [0.2, -0.3, 0.3]}},
    }
    # means over the pool: trained 0.4, chase 0.1, stalk 0.2 -> margin 0.2
    assert pool.pooled(evaluations, "predator_0") == pytest.approx({"return": 0.4, "margin": 0.2})


def _sources(seeds: int) -> list[dict]:
    return [
        {"name": f"1p-low-{k}-seed{s}", "condition": "1p-low", "kind": k, "seed": s, "folder": f"f/{k}{s}"}
        for k in pool.KINDS
        for s in range(seeds)
    ]


def test_the_pool_never_holds_a_prey_that_trained_with_a_judged_predator() -> None:
    layout = pool.plan(_sources(5), pool_seeds=(3, 4))
    judged = {r["folder"] for r in layout["judged"]}
    members = {m["folder"] for m in layout["pools"]["1p-low"]}
    assert judged == {f"f/{k}{s}" for k in pool.KINDS for s in range(3)} and not judged & members
    assert {m["kind"] for m in layout["pools"]["1p-low"]} == set(pool.KINDS)
    jobs = pool._jobs(layout, [10, 20], 5, 7, 0)
    for key, (folder, _, opponents, _, _) in jobs:
        if not key.endswith("|cross"):
            assert folder not in {prey for _, prey in opponents} and opponents[0] == (pool.FLEEING, None)
    with pytest.raises(ValueError, match="fewer than two judged flat"):
        pool.plan([s for s in _sources(5) if not (s["kind"] == "flat" and s["seed"] in (1, 2))], (3, 4))
    with pytest.raises(ValueError, match="flat seed 2 of 1p-low given twice"):
        pool.plan([*_sources(5), _sources(5)[7]], (3, 4))
    with pytest.raises(ValueError, match="no hierarchical run of the pool seeds"):
        pool.plan([s for s in _sources(5) if not (s["kind"] == "hierarchical" and s["seed"] >= 3)], (3, 4))


@pytest.mark.slow
@pytest.mark.long
def test_pool_on_a_tiny_sweep_judges_both_kinds_against_the_same_opponents(tmp_path: Path) -> None:
    sweep, out = tmp_path / "sweep", tmp_path / "pool"
    code, output = run_cli(
        "sweep", "--conditions", "1p-low", "--seeds", "3", "--predators", "hierarchical,flat", "--episodes", "8",
        "--keep-checkpoints", "4", "--eval-episodes", "2", "--num-envs", "2", "--no-record", "--workers", "1",
        "--out", str(sweep),
    )  # fmt: skip
    assert code == 0, output
    args = ["pool", str(sweep), "--out", str(out), "--pool-seeds", "2", "--episodes", "3", "--cross-episodes", "2"]
    code, output = run_cli(*args, "--workers", "1")
    assert code == 0, output
    result = json.loads((out / "pool.json").read_text())
    assert result["budgets"] == [4, 8] and result["pools"]["1p-low"] == [
        "FleeingPrey", "1p-low-flat-seed2", "1p-low-hierarchical-seed2",
    ]  # fmt: skip
    assert sorted(r["name"] for r in result["runs"]) == [
        f"1p-low-{k}-seed{s}" for k in ("flat", "hierarchical") for s in (0, 1)
    ]
    # one evaluation as a direct call: seed 0's hierarchical predators at 4 episodes against seed 2's flat prey
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import evaluate_agents

    config, mine, _ = runs.described(sweep / "runs" / "1p-low-hierarchical-seed0", "checkpoint-ep4.pt")
    _, theirs, _ = runs.described(sweep / "runs" / "1p-low-flat-seed2")
    direct = evaluate_agents(
        "1p-low", {"predator_0": mine["predator_0"], "prey_0": theirs["prey_0"]}, episodes=3, seed=12345,
        prey_check=False, **config.protocol,
    )  # fmt: skip
    judged = next(r for r in result["runs"] if r["name"] == "1p-low-hierarchical-seed0")
    p = direct["panels"][0]
    assert judged["pool"]["4"]["1p-low-flat-seed2"]["panels"]["predator_0"] == [
        p["trained"], p["always_chase"], p["always_stalk"],
    ]  # fmt: skip
    assert set(judged["cross"]) == {"own", "other kind"}
    # a rerun evaluates nothing again and writes the same result; report rewrites the same report
    before = {name: (out / name).read_bytes() for name in ("pool.json", "pool.md", "pool-report.json", "pool.png")}
    code, output = run_cli(*args, "--workers", "1")
    assert code == 0 and "pool: 12 of 12 evaluations" in output.splitlines()[0], output
    code, output = run_cli("report", str(out), "--out", str(tmp_path / "again"))
    assert code == 0, output
    for name, data in before.items():
        assert (out / name).read_bytes() == data, name
        assert name == "pool.json" or (tmp_path / "again" / name).read_bytes() == data, name
    code, output = run_cli("pool", str(sweep), "--out", str(out), "--pool-seeds", "7")
    assert code == 2 and "--pool-seeds: [7] not among" in output
    code, output = run_cli("pool", str(sweep), str(sweep), "--out", str(tmp_path / "twice"), "--pool-seeds", "2")
    assert code == 2 and "given twice" in output and not (tmp_path / "twice" / "pool-parts").exists()


@pytest.mark.slow
@pytest.mark.long
def test_pool_on_a_tiny_sweep_of_three_kinds_compares_them_pairwise(tmp_path: Path) -> None:
    sweep, out = tmp_path / "sweep", tmp_path / "pool"
    code, output = run_cli(
        "sweep", "--conditions", "1p-low", "--seeds", "3", "--predators", "hierarchical,flat,residual",
        "--episodes", "8", "--keep-checkpoints", "4", "--eval-episodes", "2", "--num-envs", "2", "--no-record",
        "--workers", "1", "--out", str(sweep),
    )  # fmt: skip
    assert code == 0, output
    code, output = run_cli("pool", str(sweep), "--out", str(out), "--pool-seeds", "2", "--episodes", "2",
                           "--cross-episodes", "2", "--workers", "1")  # fmt: skip
    assert code == 0, output
    result = json.loads((out / "pool.json").read_text())
    assert result["pools"]["1p-low"] == [
        "FleeingPrey",
        *(f"1p-low-{k}-seed2" for k in ("flat", "hierarchical", "residual")),
    ]
    judged = next(r for r in result["runs"] if r["name"] == "1p-low-residual-seed0")
    assert set(judged["cross"]) == {"own", "other kind: flat", "other kind: hierarchical"}
    summary = json.loads((out / "pool-report.json").read_text())
    assert [r["pair"] for r in summary["budgets"][-1]["return"]["panels"]] == [
        ["residual", "hierarchical"], ["residual", "flat"], ["hierarchical", "flat"],
    ]  # fmt: skip
    assert "residual − flat" in (out / "pool.md").read_text() and "| pool return |" in output


def test_reproduction_md_prints_what_the_committed_pool_results_give(tmp_path: Path) -> None:
    root = Path(__file__).resolve().parents[1]
    result = pool.load(root / "results" / "pool" / "pool.json")
    summary = pool.summarise(result)
    text = (root / "REPRODUCTION.md").read_text()
    for table in pool.markdown(summary).split("\n## ")[1:]:  # every table under its heading
        body = table.split("\n", 2)[2].strip()
        assert body in text, table.splitlines()[0]
    judged = {(r["condition"], r["kind"], r["seed"]) for r in result["runs"]}  # no pool prey is a judged run's
    for condition, members in result["pools"].items():
        assert members[0] == pool.FLEEING
        for member in members[1:]:
            kind, seed = member.removeprefix(condition + "-").rsplit("-seed", 1)
            assert (condition, kind, int(seed)) not in judged
    code, output = run_cli("report", str(root / "results" / "pool"), "--out", str(tmp_path))
    assert code == 0, output
    assert (tmp_path / "pool.md").read_text() == (root / "docs" / "figures" / "pool" / "pool.md").read_text()
    assert (tmp_path / "pool.png").read_bytes() == (root / "docs" / "figures" / "pool" / "pool.png").read_bytes()


def test_three_kinds_are_planned_and_compared_pairwise_against_an_independent_computation() -> None:
    """A pool study of the residual, hierarchical and flat kinds: every kind's pool seeds in the pool,
    each judged run in cross-kind play against both other kinds' prey; at every budget every
    (panel, comparison) one Holm family, checked against scipy's Welch test and Holm written out."""
    sources = [
        {"name": f"1p-low-{k}-seed{s}", "condition": "1p-low", "kind": k, "seed": s, "folder": f"f/{k}{s}"}
        for k in ("flat", "residual", "hierarchical")
        for s in range(5)
    ]
    layout = pool.plan(sources, pool_seeds=(3, 4))
    assert (
        sorted(m["kind"] for m in layout["pools"]["1p-low"]) == ["flat"] * 2 + ["hierarchical"] * 2 + ["residual"] * 2
    )
    crossed = dict(pool._jobs(layout, [10, 20], 5, 7, 0))["1p-low-residual-seed0|cross"][2]
    assert crossed == [
        ("own", "f/residual0"),
        ("other kind: flat", "f/flat0"),
        ("other kind: hierarchical", "f/hierarchical0"),
    ]
    with pytest.raises(ValueError, match="compares two kinds or more"):
        pool.plan([s for s in sources if s["kind"] == "residual"], (3, 4))
    truth = {"hierarchical": 0.3, "residual": 0.5, "flat": 0.31}  # residual ahead of both; the others alike
    rng = np.random.default_rng(4)
    runs = []
    for kind, mean in truth.items():
        for seed in range(8):
            at = {}
            for budget in ("10", "20"):
                value = mean + rng.normal(0, 0.02)
                evaluation = {"panels": {"predator_0": [value, 0.0, 0.1]}, "stderr": {"predator_0": 0.01}}
                at[budget] = {"FleeingPrey": evaluation, "m": evaluation}
            own = {"panels": {"predator_0": [mean, 0.0, 0.1]}}
            cross = {"own": own, **{f"other kind: {o}": own for o in truth if o != kind}}
            runs.append(
                {"name": f"{kind}{seed}", "condition": "1p-low", "kind": kind, "seed": seed, "pool": at, "cross": cross}
            )
    summary = pool.summarise(
        {"budgets": [10, 20], "episodes": 5, "cross_episodes": 7, "seed": 0, "pools": {}, "runs": runs}
    )
    pairs = [("residual", "hierarchical"), ("residual", "flat"), ("hierarchical", "flat")]
    for entry in summary["budgets"]:
        rows = entry["return"]["panels"]
        assert [tuple(r["pair"]) for r in rows] == pairs
        raw = []
        for a, b in pairs:
            values = {
                k: [r["pool"][str(entry["episodes"])]["m"]["panels"]["predator_0"][0] for r in runs if r["kind"] == k]
                for k in (a, b)
            }
            raw.append(scipy_stats.ttest_ind(values[a], values[b], equal_var=False).pvalue)
        m, order = len(raw), np.argsort(raw)
        holm, running = [0.0] * m, 0.0
        for rank, i in enumerate(order):
            running = max(running, min(1.0, (m - rank) * raw[i]))
            holm[i] = running
        assert [r["difference"]["p_holm"] for r in rows] == pytest.approx(holm)
        assert [r["verdict"] for r in rows][:2] == ["residual better than hierarchical", "residual better than flat"]
        assert rows[2]["verdict"] in ("equivalent", "not resolved", "rule helps", "flat better")
        assert sum(entry["return"]["counts"].values()) == 3
    assert [p["pair"] for p in summary["improvement"]["return"]] == [list(p) for p in pairs]
    assert summary["improvement"]["return"][0]["value"] == 1.0
    assert len(summary["cross_kind"]) == 6 and {r["other_kind"] for r in summary["cross_kind"]} == set(truth)
    assert set(summary["curves"]["1p-low"]) == set(truth)
    text = pool.markdown(summary)
    assert "| 1p-low | predator_0 | residual − flat |" in text and "residual (prey of flat)" in text
