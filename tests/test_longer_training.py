"""docs/longer-training.md against its committed results (results/budget150k/): the report
regenerated from them gives the tables the page prints, and the numbers its text quotes."""

from pathlib import Path

import pytest

from pursuit_bench.reports import reproduction as report

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "budget150k"
DOC = ROOT / "docs" / "longer-training.md"


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory: pytest.TempPathFactory) -> dict:
    return report.write(RESULTS, tmp_path_factory.mktemp("report"))


def test_the_page_prints_what_the_results_give(regenerated: dict) -> None:
    results = report.collect(RESULTS)
    text = DOC.read_text()
    table = report.panel_table(results)
    report.judge(table)
    for block in (
        report.budget_markdown(regenerated["budgets"]),
        report.margin_budget_markdown(report.margin_by_budget(results)),
        report.classification_markdown(table),
        report.convergence_markdown(report.convergence(results)),
        report.prey_budget_markdown(report.prey_by_budget(results)),
        report.prey_markdown(report.prey_table(results)),
    ):
        assert block in text, block[:200]


def test_the_runs_went_on_from_15000_episodes_and_are_complete() -> None:
    """Every run has all four budgets evaluated on 1000 episodes a variant, five seeds a
    condition, 150,000 episodes; and the numbers the text quotes are the results'."""
    runs = report.collect(RESULTS)
    assert sorted((r.condition, r.seed) for r in runs) == [(c, s) for c in ("1p-high", "1p-low") for s in range(5)]
    for run in runs:
        assert set(run.milestones) == {15000, 50000, 100000}
        assert run.config["episodes"] == 150000
        assert all(len(p["episode_returns"]["trained"]) == 1000 for p in run.evaluation["panels"])
    words = " ".join(DOC.read_text().split())
    margins = {r["condition"]: r["budgets"] for r in report.margin_by_budget(runs)}
    low = ", ".join(
        f"{margins['1p-low'][b]['mean']:+.3f}".replace("-", "−") for b in ("15000", "50000", "100000", "150000")
    )
    assert f"({low})" in words
    high = margins["1p-high"]
    assert (
        f"{high['15000']['mean']:+.3f} [{high['15000']['ci'][0]:+.3f}, {high['15000']['ci'][1]:+.3f}] at 15,000"
        in words
    )
    assert (
        f"{high['150000']['mean']:+.3f} [{high['150000']['ci'][0]:+.3f}, {high['150000']['ci'][1]:+.3f}] at 150,000"
        in words
    )
    slope = next(r for r in report.convergence(runs) if r["condition"] == "1p-high")
    assert slope["verdict"] == "falling"
