"""The budget study's report (pursuit_bench/reports/budget_report.py) on synthetic compact results
with a known answer: where the hierarchical runs are better by a wide margin, worse, or the same,
the verdicts say so once all six panels are in, and none is written before; the intervals are
Welch's on the pool returns computed here by hand; the command reads the study's folder."""

from __future__ import annotations

import gzip
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from cli_helpers import run_cli
from scipy import stats as scipy_stats

from pursuit_bench.reports import budget_report

BUDGETS = budget_report.BUDGETS

PREDATORS = {"3p-low-shared": 3, "2p-high-shared": 2, "1p-high": 1}
#: hierarchical − flat in each condition's pool return: the rule helps, the flat is better, no difference
EFFECT = {"3p-low-shared": 0.2, "2p-high-shared": -0.2, "1p-high": 0.0}
NAMES = (
    "FleeingPrey",
    *(f"hierarchical-seed{s}" for s in range(1000, 1004)),
    *(f"flat-seed{s}" for s in range(1004, 1008)),
)


def trained_value(condition: str, kind: str, seed: int, budget: int, member: int) -> float:
    rng = np.random.default_rng([list(PREDATORS).index(condition), int(kind == "flat"), seed, budget, member])
    return 0.5 + (EFFECT[condition] if kind == "hierarchical" else 0.0) + float(rng.normal(0, 0.004))


def members(condition: str, kind: str, seed: int, budget: int, shift: float = 0.0) -> dict[str, Any]:
    """One budget's evaluations; ``shift`` moves every return (the 15,000-episode population's
    differ from the same-budget one's, so that a report reading the wrong one is caught)."""
    out = {}
    for m, name in enumerate(NAMES):
        value = trained_value(condition, kind, seed, budget, m) + shift
        out[name] = {
            "panels": {f"predator_{p}": [value, 0.1, 0.2] for p in range(PREDATORS[condition])},
            "stderr": {f"predator_{p}": 0.01 for p in range(PREDATORS[condition])},
            "capture_rate": 0.9,
            "prey": {"return": -0.9, "left_area": 0.0 if m == 0 else 0.1, "captured": 0.9, "survived": 0.1},
        }
    return out


def write_runs(folder: Path, skip: tuple[str, str, int] | None = None) -> None:
    (folder / "runs").mkdir(parents=True)
    for condition in PREDATORS:
        for kind in ("hierarchical", "flat"):
            for seed in range(10):
                if (condition, kind, seed) == skip:
                    continue
                run = {
                    "format": budget_report.FORMAT, "condition": condition, "kind": kind, "seed": seed,
                    "build": "b", "evaluated_by": "e", "protocol": "crn-1", "episodes": 60, "eval_seed": 12345,
                    "budgets": list(budget_report.BUDGETS),
                    "same_budget": {str(b): members(condition, kind, seed, b) for b in budget_report.BUDGETS},
                    "first_population": {str(b): members(condition, kind, seed, b, -0.3) for b in BUDGETS[1:]},
                    "paper": {
                        "panels": {
                            f"predator_{p}": {"trained": 0.6 + 0.01 * seed, "always_chase": 0.5, "always_stalk": 0.55}
                            for p in range(PREDATORS[condition])
                        },
                        "prey": {"left_area": 0.05},
                        "episodes": 1000,
                    },
                }  # fmt: skip
                with gzip.open(folder / "runs" / f"{condition}-{kind}-seed{seed}.json.gz", "wt") as file:
                    json.dump(run, file)


def pool_return(condition: str, kind: str, budget: int) -> list[float]:
    return [
        float(np.mean([trained_value(condition, kind, s, budget, m) for m in range(len(NAMES))])) for s in range(10)
    ]


def test_the_verdicts_are_the_known_answers_once_all_six_panels_are_in(tmp_path: Path) -> None:
    write_runs(tmp_path)
    summary = budget_report.summarise(budget_report.read_runs(tmp_path))
    assert summary["whole_family"] and summary["complete"] == list(PREDATORS)
    verdicts = {(r["condition"], r["predator"]): r["verdict"] for r in summary["primary"]["panels"]}
    assert len(verdicts) == budget_report.PANELS
    for (condition, _), verdict in verdicts.items():
        assert (
            verdict
            == {"3p-low-shared": "rule helps", "2p-high-shared": "flat better", "1p-high": "equivalent"}[condition]
        )
    for row in summary["primary"]["panels"]:
        h = pool_return(row["condition"], "hierarchical", 1_000_000)
        f = pool_return(row["condition"], "flat", 1_000_000)
        reference = scipy_stats.ttest_ind(h, f, equal_var=False)
        assert row["difference"]["mean"] == pytest.approx(np.mean(h) - np.mean(f))
        assert row["difference"]["p"] == pytest.approx(reference.pvalue)
        assert "p_holm" in row["difference"]
    # the paper's comparison: every run beats both fixed modes in every panel
    for kind in ("hierarchical", "flat"):
        paper = summary["secondary"]["paper"][kind]
        assert set(paper["strict_count"].values()) == {budget_report.PANELS} and paper["of"] == budget_report.PANELS
        assert {r["verdict"] for r in paper["panels"]} == {"better"}
    for condition in PREDATORS:  # the figure's curves: each budget's mean over runs and its t-interval
        for kind in ("hierarchical", "flat"):
            curve = summary["curves"][condition][kind]
            assert curve["episodes"] == list(budget_report.BUDGETS)
            for i, budget in enumerate(budget_report.BUDGETS):
                values = pool_return(condition, kind, budget)
                half = scipy_stats.t.ppf(0.975, len(values) - 1) * scipy_stats.sem(values)
                assert curve["mean"][i] == pytest.approx(np.mean(values))
                assert curve["ci"][i] == pytest.approx([np.mean(values) - half, np.mean(values) + half])
    walls = summary["secondary"]["wall_rates"]["1p-high"]["flat"]["population"]["15000"]
    assert walls["mean"] == pytest.approx(0.1)  # FleeingPrey (0) is not a learned member: the others' 0.1
    text = budget_report.markdown(summary)
    assert "Interim" not in text and "| verdict |" in text


def test_with_a_run_missing_the_report_is_interim_without_verdicts(tmp_path: Path) -> None:
    write_runs(tmp_path, skip=("1p-high", "flat", 9))
    summary = budget_report.summarise(budget_report.read_runs(tmp_path))
    assert not summary["whole_family"] and summary["in_progress"] == {"1p-high": {"hierarchical": 10, "flat": 9}}
    rows = summary["primary"]["panels"]
    assert len(rows) == 5 and all("verdict" not in r and "p_holm" not in r["difference"] for r in rows)
    assert all("verdict" not in r for r in summary["secondary"]["paper"]["flat"]["panels"])
    assert "**Interim**: 5 of the protocol's 6 panels" in budget_report.markdown(summary)


def test_the_command_reads_the_study_s_folder_and_refuses_an_empty_one(tmp_path: Path) -> None:
    write_runs(tmp_path / "study")
    (tmp_path / "study" / budget_report.MARKER).write_text("{}\n")
    code, output = run_cli("report", str(tmp_path / "study"), "--out", str(tmp_path / "out"))
    assert code == 0 and "verdicts written" in output, output
    assert (tmp_path / "out" / "budget-study.md").read_text().startswith("# The budget study")
    assert (tmp_path / "out" / "budget-study.png").read_bytes().startswith(b"\x89PNG")
    (tmp_path / "empty" / "runs").mkdir(parents=True)
    (tmp_path / "empty" / budget_report.MARKER).write_text("{}\n")
    code, output = run_cli("report", str(tmp_path / "empty"))
    assert code == 2 and "no judged runs" in output and len(output.strip().splitlines()) == 1, output


def test_a_result_made_with_other_settings_or_twice_is_refused_naming_the_file(tmp_path: Path) -> None:
    write_runs(tmp_path)
    path = tmp_path / "runs" / "1p-high-flat-seed3.json.gz"
    with gzip.open(path, "rt") as file:
        run = json.load(file)
    with gzip.open(path, "wt") as file:
        json.dump({**run, "episodes": 2}, file)  # the evaluation script's trial option
    with pytest.raises(ValueError, match=r"1p-high-flat-seed3\.json\.gz: not the protocol's evaluation \(episodes"):
        budget_report.read_runs(tmp_path)
    with gzip.open(path, "wt") as file:
        json.dump({**run, "seed": 4}, file)  # a second file of seed 4
    with pytest.raises(ValueError, match="named otherwise than its run"):
        budget_report.read_runs(tmp_path)


def early_value(seed: int, predator: int) -> float:
    return 0.3 + 0.02 * seed + 0.001 * predator


def write_first_parts(
    folder: Path, conditions: tuple[str, ...], build: str = "b", budget: int = BUDGETS[0], seeds: range = range(10)
) -> None:
    """The first parts' results (``run.py --paper-first``): the learned predator's return
    :func:`early_value`, the fixed modes' 0.4 and 0.45."""
    (folder / budget_report.FIRST_PARTS).mkdir(parents=True, exist_ok=True)
    for condition in conditions:
        for kind in ("hierarchical", "flat"):
            for seed in seeds:
                run = {
                    "format": budget_report.FIRST_PART_FORMAT, "condition": condition, "kind": kind, "seed": seed,
                    "build": build, "protocol": "crn-1", "eval_seed": 12345, "budget": budget,
                    "same_as_judged": condition != "3p-low-shared",
                    "paper": {
                        "episodes": 1000,
                        "panels": {
                            f"predator_{p}": {
                                "trained": early_value(seed, p), "always_chase": 0.4, "always_stalk": 0.45
                            }
                            for p in range(PREDATORS[condition])
                        },
                    },
                }  # fmt: skip
                path = folder / budget_report.FIRST_PARTS / f"{condition}-{kind}-seed{seed}.json.gz"
                with gzip.open(path, "wt") as file:
                    json.dump(run, file)


def test_fig2_holds_the_same_runs_at_both_budgets_and_says_which_are_not_yet_played(tmp_path: Path) -> None:
    write_runs(tmp_path)
    write_first_parts(tmp_path, ("3p-low-shared", "2p-high-shared"))
    summary = budget_report.summarise(budget_report.read_runs(tmp_path), budget_report.read_first_parts(tmp_path))
    rows = summary["fig2"]
    assert len(rows) == 2 * budget_report.PANELS
    first, final = str(BUDGETS[0]), str(BUDGETS[-1])
    for row in rows:
        at_end = row["budgets"][final]
        trained = [0.6 + 0.01 * s for s in range(10)]  # write_runs' paper panels
        half = scipy_stats.t.ppf(0.975, 9) * scipy_stats.sem(trained)
        assert at_end["trained"]["mean"] == pytest.approx(np.mean(trained))
        assert at_end["trained"]["ci"] == pytest.approx([np.mean(trained) - half, np.mean(trained) + half])
        assert at_end["always_stalk"]["values"] == [0.55] * 10
        if row["condition"] == "1p-high":
            assert first not in row["budgets"]
            continue
        early = [early_value(s, int(row["predator"][-1])) for s in range(10)]
        assert row["budgets"][first]["seeds"] == list(range(10))
        assert row["budgets"][first]["trained"]["mean"] == pytest.approx(np.mean(early))
        assert row["budgets"][first]["always_chase"]["ci"] == pytest.approx([0.4, 0.4])
    drawn = [(c, q) for c in ("3p-low-shared", "2p-high-shared") for q in range(PREDATORS[c])]
    for kind in ("hierarchical", "flat"):  # the paper's count per seed: above both fixed modes (0.4, 0.45)
        strict = summary["fig2_strict"][kind]
        assert strict[first] == {
            "panels": 5,
            "per_seed": {str(seed): sum(early_value(seed, q) > 0.45 for _, q in drawn) for seed in range(10)},
        }
        assert strict[final] == {"panels": 5, "per_seed": {str(seed): 5 for seed in range(10)}}  # 1p-high unplayed
    text = budget_report.markdown(summary)
    assert "40 of the 60 first parts in, 40 drawn" in text and "20 of them also checked" in text
    assert (
        "of the 5 panels played at both budgets, those where the learned predator is above both fixed modes, "
        "per seed: at 15,000 episodes seed 0: 0, seed 1: 0" in text
    )
    assert "| flat | 1p-high predator_0 | 15,000 | not yet played |" in text
    (tmp_path / budget_report.MARKER).write_text("{}\n")
    code, output = run_cli("report", str(tmp_path), "--out", str(tmp_path / "out"))
    assert code == 0 and "budget-fig2.png" in output, output
    assert (tmp_path / "out" / "budget-fig2.png").read_bytes().startswith(b"\x89PNG")
    written = json.loads((tmp_path / "out" / "budget-study-report.json").read_text())
    assert written["fig2"] == json.loads(json.dumps(rows))  # the command reads the first parts too


def test_first_parts_of_another_budget_or_build_are_refused(tmp_path: Path) -> None:
    write_runs(tmp_path)
    write_first_parts(tmp_path, ("1p-high",), budget=50_000)
    with pytest.raises(ValueError, match=r"1p-high-flat-seed0\.json\.gz: not a first part of 15,000 episodes"):
        budget_report.read_first_parts(tmp_path)
    other = tmp_path / "other"
    write_runs(other)
    write_first_parts(other, ("1p-high",), build="another")
    with pytest.raises(ValueError, match="first parts trained by another, not the judged runs' build"):
        budget_report.summarise(budget_report.read_runs(other), budget_report.read_first_parts(other))


def test_fig2_pairs_the_budgets_by_seed_and_draws_no_condition_still_running(tmp_path: Path) -> None:
    write_runs(tmp_path, skip=("1p-high", "flat", 9))  # 1p-high not complete: not drawn
    write_first_parts(tmp_path, ("2p-high-shared",), seeds=range(3, 8))
    write_first_parts(tmp_path, ("1p-high",))
    summary = budget_report.summarise(budget_report.read_runs(tmp_path), budget_report.read_first_parts(tmp_path))
    assert summary["first_parts"] == {"in": 30, "of": 60, "drawn": 10, "same_as_judged": 10}
    assert {r["condition"] for r in summary["fig2"]} == {"3p-low-shared", "2p-high-shared"}
    first, final = str(BUDGETS[0]), str(BUDGETS[-1])
    for row in summary["fig2"]:
        if row["condition"] == "3p-low-shared":  # no first part: 10^6 over all ten runs
            assert list(row["budgets"]) == [final] and row["budgets"][final]["seeds"] == list(range(10))
            continue
        assert row["budgets"][first]["seeds"] == row["budgets"][final]["seeds"] == [3, 4, 5, 6, 7]
        assert row["budgets"][final]["trained"]["values"] == pytest.approx([0.6 + 0.01 * s for s in range(3, 8)])
