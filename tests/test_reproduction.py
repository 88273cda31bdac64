"""REPRODUCTION.md against the sweep's committed results (results/reproduction/): the report
regenerated from them, without the run folders, gives the tables REPRODUCTION.md prints."""

from pathlib import Path

import pytest

from pursuit_bench import report

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
    assert len(hierarchical) == 50 and all(set(r.milestones) == {1500, 5000} for r in hierarchical)
    assert all(len(p["episode_returns"]["trained"]) >= 300 for r in results for p in r.evaluation["panels"])
    totals, out = regenerated
    for name in totals["written"]:
        assert (out / name).stat().st_size > 1000


def test_reproduction_md_prints_what_the_results_give(regenerated: tuple[dict, Path]) -> None:
    totals, _ = regenerated
    text = (ROOT / "REPRODUCTION.md").read_text()
    results = report.collect(RESULTS)
    assert report.budget_markdown(totals["budgets"]) in text
    assert report.convergence_markdown(report.convergence(results)) in text
    assert report.prey_markdown(report.prey_table(results)) in text
    final = totals["budgets"][-1]
    assert f"best in **{final['hierarchical_best']} of {final['panels']}**" in text
    assert f"best or tied with the best in **{final['hierarchical_best_or_tied']}**" in text
