"""REPRODUCTION.md against the sweep's committed results (results/reproduction/): the report
regenerated from them, without the run folders, gives the tables REPRODUCTION.md prints."""

import gzip
import json
from pathlib import Path

import pytest
from cli_helpers import load_script

from pursuit_bench.reports import reproduction as report

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "reproduction"


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("report")
    return report.write(RESULTS, out), out


def test_the_committed_results_are_compact_and_complete(regenerated: tuple[dict, Path]) -> None:
    size = sum(p.stat().st_size for p in RESULTS.rglob("*") if p.is_file())
    assert size < 5 * 2**20
    results = report.collect(RESULTS)
    hierarchical = [r for r in results if r.kind == "hierarchical"]
    flat = [r for r in results if r.kind == "flat"]
    assert len(hierarchical) == 100 and len(flat) == 50
    assert all(set(r.milestones) == {1500, 5000, 10500, 12750} for r in hierarchical)
    assert all(r.config["episodes"] == 15000 for r in results)
    assert all(len(p["episode_returns"]["trained"]) == 1000 for r in results for p in r.evaluation["panels"])
    totals, out = regenerated
    for name in totals["written"]:
        assert (out / name).stat().st_size > 1000
    assert {"forest.png", "counts.png", "budget.png", "fig2.png", "curves.png"} <= set(totals["written"])


def test_reproduction_md_prints_what_the_results_give(regenerated: tuple[dict, Path]) -> None:
    totals, _ = regenerated
    text = (ROOT / "REPRODUCTION.md").read_text()
    results = report.collect(RESULTS)
    table = report.panel_table(results)
    report.judge(table)
    for block in (
        report.classification_markdown(table),
        report.by_condition_markdown(report.verdicts_by_condition(table)),
        report.sensitivity_markdown(report.margin_sensitivity(table)),
        report.counts_markdown(report.strict_counts(table)),
        report.improvement_markdown(report.improvement(results, table)),
        report.power_markdown(report.power_table(table)),
        report.budget_markdown(totals["budgets"]),
        report.convergence_markdown(report.convergence(results)),
        report.variants_markdown(table),
        report.prey_markdown(report.prey_table(results)),
        report.flat_markdown(report.flat_table(results)),
    ):
        assert block in text, block[:200]
    headline = (
        f"**{totals['better']} better, {totals['equivalent']} equivalent, {totals['not resolved']} not\n"
        f"resolved and {totals['worse']} worse**"
    )
    assert headline in text


def test_the_json_keeps_full_precision_and_every_comparison(regenerated: tuple[dict, Path]) -> None:
    _, out = regenerated
    payload = json.loads((out / "report.json").read_text())
    comparisons = [c for p in payload["panels"] for c in p["paired"].values()]
    assert len(comparisons) == 44
    for c in comparisons:
        assert {"mean", "ci", "p_greater", "p_greater_holm", "p_less_holm", "p_equivalent_holm"} <= set(c)
        assert len(c["differences"]) == 10
    # one comparison recomputed from the per-run files themselves, not through the report: the
    # JSON holds its mean at full precision (the Markdown shows +0.597)
    chase = []
    for seed in range(10):
        with gzip.open(RESULTS / "runs" / f"1p-high-hierarchical-seed{seed}.json.gz", "rt") as file:
            panel = json.load(file)["evaluation"]["panels"][0]
        chase.append(panel["trained"] - panel["always_chase"])
    high = next(p for p in payload["panels"] if p["condition"] == "1p-high")["paired"]["always_chase"]
    assert high["differences"] == chase
    assert high["mean"] == sum(chase) / 10 and round(high["mean"], 3) == 0.597 and high["mean"] != 0.597
    # the counts as published (REPRODUCTION.md), literally
    summary = payload["summary"]
    assert summary["per_seed"]["counts"] == [12, 11, 13, 13, 8, 16, 10, 14, 11, 8]
    assert [summary[v] for v in report.VERDICTS] == [6, 5, 10, 1]
    assert summary["equivalence_margin"] == 0.05
    verdicts = {(p["condition"], p["predator"]): p["verdict"] for p in payload["panels"]}
    assert verdicts["3p-low-individual", "predator_0"] == "worse"
    assert [verdicts["3p-high-shared", f"predator_{k}"] for k in range(3)] == [
        "not resolved",
        "equivalent",
        "equivalent",
    ]


def test_the_authors_agents_figures_are_the_committed_data() -> None:
    authors_agents = load_script("docs/gen/authors_agents.py")
    rows = authors_agents.load()
    assert len(rows) == 10 and {r["prey"] for r in rows} == {"greedy", "ε = 0.1"}
    assert authors_agents.markdown(rows) in (ROOT / "docs" / "authors-agents.md").read_text()
    sentence = authors_agents.summary(rows)
    assert sentence.startswith("their greedy prey leaves the arena in 9–26 % of episodes")
    assert sentence in " ".join((ROOT / "REPRODUCTION.md").read_text().split())


def test_the_counts_the_prose_quotes_are_the_table_s() -> None:
    """REPRODUCTION.md's sentences that count panels and conditions, recomputed."""
    table = report.panel_table(report.collect(RESULTS))
    report.judge(table)
    words = " ".join((ROOT / "REPRODUCTION.md").read_text().split())
    number = {1: "one", 2: "two", 3: "three", 4: "four", 5: "five", 6: "six", 7: "seven", 8: "eight", 10: "ten"}
    judged = [t for t in table if "verdict" in t]
    by_condition = report.verdicts_by_condition(table)
    for verdict, label in (("better", "better"), ("equivalent", "equivalent")):
        panels = sum(t["verdict"] == verdict for t in judged)
        conditions = sum(r[verdict] > 0 for r in by_condition)
        assert f"The {panels} {label} panels come from {conditions} conditions" in words or (
            f"the {panels} {label} from {conditions}" in words
        ), verdict
    unresolved = [t for t in judged if t["verdict"] == "not resolved"]
    baseline_ahead = sum(
        max(t["variants"][b]["mean"] for b in report.BASELINES) > t["variants"]["hierarchical"]["mean"]
        for t in unresolved
    )
    assert f"{number[len(unresolved)]} are not resolved, and in {number[baseline_ahead]} of those" in words
    multi = [r for r in by_condition if r["panels"] > 1]
    split = sum(sum(r[v] > 0 for v in report.VERDICTS) > 1 for r in multi)
    assert (
        f"In {number[split]} of the {number[len(multi)]} multi-predator conditions the predators' verdicts differ"
        in words
    )


def test_fig3_s_figures_are_the_committed_analyses() -> None:
    """REPRODUCTION.md's Fig. 3 paragraph: the k-NN R² of the shipped agents' value-stream
    embeddings, from results/analysis/ (scripts/export_analysis.py)."""
    words = " ".join((ROOT / "REPRODUCTION.md").read_text().split())

    def scores(condition: str) -> dict[str, list[str]]:
        analysis = json.loads((ROOT / "results" / "analysis" / f"fig3-{condition}.json").read_text())
        predators = analysis["predators"].values()
        return {q: [f"{p['organisation'][q]:.2f}" for p in predators] for q in ("value", "distance")}

    low, high = scores("2p-low-individual"), scores("2p-high-individual")
    assert f"organised by V(s) (k-NN R² {low['value'][0]} and {low['value'][1]})" in words
    assert f"distance to the prey ({low['distance'][0]} and {low['distance'][1]})" in words
    assert (
        f"(V {high['value'][0]} / {high['value'][1]}, distance {high['distance'][0]} / {high['distance'][1]})" in words
    )


def test_the_chase_analysis_figures_are_the_committed_ones() -> None:
    """REPRODUCTION.md's P(chase | distance) and chase-onset sentences, from
    results/analysis/repro-analysis.json."""
    analysis = json.loads((ROOT / "results" / "analysis" / "repro-analysis.json").read_text())
    words = " ".join((ROOT / "REPRODUCTION.md").read_text().split())
    low = [v for k, v in analysis.items() if k.endswith("low cost")]
    high = [v for k, v in analysis.items() if k.endswith("high cost")]
    assert sum(v["runs"] for v in low + high) == 100
    near = [p for v in low for p in v["p_chase"][1:3]]  # bins 0.1-0.2 and 0.2-0.3
    assert f"P(chase) {min(near):.2f}–{max(near):.2f} within 0.1–0.3" in words
    mid = [v["p_chase"][6] for v in low]  # 0.6-0.7
    assert f"still {min(mid):.2f}–{max(mid):.2f} of the time at 0.6–0.7" in words
    beyond = max(p for v in high for p in v["p_chase"][2:] if p is not None)
    assert f"P(chase) at most {beyond:.2f} beyond 0.2" in words
    close = [v["p_chase"][1] for v in high]
    assert f"({min(close):.2f}–{max(close):.2f} within 0.1–0.2)" in words
    onsets = {k: f"{v['chase_onset_median']:.2f}" for k, v in analysis.items()}
    order = ("1 predator", "2 predators", "3 predators")
    assert f"**{' / '.join(onsets[f'{n}, high cost'] for n in order)}**" in words
    assert f"**{' / '.join(onsets[f'{n}, low cost'] for n in order)}** under low cost" in words
    for n in order:  # the intervals apart
        h, lo = analysis[f"{n}, high cost"]["chase_onset_ci"], analysis[f"{n}, low cost"]["chase_onset_ci"]
        assert h[1] < lo[0]
