"""REPRODUCTION.md against the sweep's committed results (results/reproduction/): the report
regenerated from them, without the run folders, gives the tables REPRODUCTION.md prints."""

import json
from pathlib import Path

import pytest

from pursuit_bench.study import report

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
    headline = f"**{totals['better']} better, {totals['not resolved']} not\nresolved and {totals['worse']} worse**"
    assert headline in text


def test_the_json_keeps_full_precision_and_every_comparison(regenerated: tuple[dict, Path]) -> None:
    _, out = regenerated
    payload = json.loads((out / "report.json").read_text())
    comparisons = [c for p in payload["panels"] for c in p["paired"].values()]
    assert len(comparisons) == 44
    for c in comparisons:
        assert {"mean", "ci", "p_greater", "p_greater_holm", "p_less_holm", "differences"} <= set(c)
        assert len(c["differences"]) == 10
    # full precision: means are not rounded to the few digits the Markdown shows
    assert any(len(repr(c["mean"])) > 8 for c in comparisons)
    assert (
        payload["summary"]["per_seed"]["counts"]
        == report.strict_counts(report.panel_table(report.collect(RESULTS)))["counts"]
    )
