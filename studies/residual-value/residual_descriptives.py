"""Two descriptive tables of the residual study, for docs/residual.md's reading of it: how much and
where its runs correct the rule, and the robustness ladders' levels beside their changes.

**Corrections**, one row per setting, a summary of the report's descriptive table (`analyze`'s
corrections of every residual run at its last budget, against its own prey): the median and the
largest share of states a predator corrected (one value per run and predator), how many of them
corrected more than a fifth of their states, the median share of states in chase (one value per
run, the mean over its predators), where the
corrected states lie (stalking within 0.5 of the prey, stalking further, chasing: pooled over runs
and predators), and Spearman's rank correlation over seeds between a run's share of states corrected
(mean over its predators) and how far its pool margin lies from the hierarchical run of its seed
(residual − hierarchical, mean over predators), and the same against the pool return (the primary
measure). The correlations are descriptive, not a test of the protocol: their p-values are given as
they are and with Holm over the table's correlations.

**Ladder levels**: the report tests the *change* of a run's margin from its unperturbed level; a
smaller drop can start from a lower level. This table gives each kind's mean margin (against its
own prey, mean over predators and runs) at every level of the ladders the runs hold, residual and
hierarchical (— where a run of the group lacks the level). No test. Settings in the report's order.

    python studies/residual-value/residual_descriptives.py results/residual-study \
        --out results/residual-study/descriptives.md
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats as scipy_stats

from pursuit_bench import stats
from pursuit_bench.figures import plots
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.reports import rule_report, rule_study

NEAR = 0.5
"""Distance to the prey below which a stalking state counts as near (a distance bin whose lower
edge is below it)."""
FEWEST_SEEDS = 3
"""Seeds with both a residual and a hierarchical run a setting needs for its correlations."""


def _where(by_distance: dict[str, Any]) -> np.ndarray:
    """A run's corrected states, its predators together: stalking near, stalking further, chasing."""
    lower = np.array(next(iter(by_distance.values()))["bins"][:-1])
    stalk, _ = plots.correction_shares(by_distance, "stalk")
    chase, _ = plots.correction_shares(by_distance, "chase")
    return np.array([stalk[lower < NEAR].sum(), stalk[lower >= NEAR].sum(), chase.sum()])


def corrections_table(runs: list[dict[str, Any]]) -> list[str]:
    """The corrections' summary, one row per setting (the report's order), as markdown lines."""
    rows = rule_report.corrections(runs, rule_report.budgets(runs)[-1], differs=stats.EQUIVALENCE_MARGIN)
    cells: list[list[str | None]] = []  # None: a Holm-adjusted p, filled in once all are known
    pvalues: list[float] = []
    for setting in dict.fromkeys(r["setting"] for r in rows):
        mine = [r for r in rows if r["setting"] == setting]
        shares = [share for r in mine for share in r["corrected"].values()]
        chase = [float(np.mean(list(r["in_chase"].values()))) for r in mine]
        where = sum((_where(r["by_distance"]) for r in mine), np.zeros(3))
        where = where / max(where.sum(), 1e-12)
        paired = [r for r in mine if r["hierarchical_margin"] is not None]
        corrected = [float(np.mean(list(r["corrected"].values()))) for r in paired]
        row: list[str | None] = [
            setting,
            str(len(mine)),
            f"{np.median(shares):.1%}",
            f"{max(shares):.1%}",
            f"{sum(s > 0.2 for s in shares)}/{len(shares)}",
            f"{np.median(chase):.1%}",
            *(f"{w:.0%}" for w in where),
        ]
        for measure in ("margin", "return"):
            gaps = [r[measure] - r[f"hierarchical_{measure}"] for r in paired]
            if len(paired) < FEWEST_SEEDS or np.ptp(gaps) == 0 or np.ptp(corrected) == 0:
                row += ["—", "—", "—"]  # too few seeds, or a constant: no rank correlation
                continue
            rho = scipy_stats.spearmanr(corrected, gaps)
            row += [f"{rho.statistic:+.2f}", f"{rho.pvalue:.3f}", None]
            pvalues.append(float(rho.pvalue))
        cells.append(row)
    adjusted = iter(stats.holm(pvalues) if pvalues else [])
    body = ["| " + " | ".join(f"{next(adjusted):.3f}" if c is None else c for c in row) + " |" for row in cells]
    return [
        "Where the residual predator corrects the rule: every residual run at its last budget",
        "(`analyze`, its own prey); states corrected: one share per run and predator; states in chase:",
        "one share per run (mean over its predators); where: corrected states pooled over runs and",
        f"predators (near: within {NEAR:g} of the prey); Spearman over seeds: share of states corrected",
        "(mean over the run's predators) against residual − hierarchical pool margin, and against",
        "residual − hierarchical pool return (the primary measure); descriptive: p, and p with Holm",
        f"over the table's {len(pvalues)} correlations.",
        "",
        "| setting | residual runs | states corrected: median | largest | above 20 % | states in chase: median "
        "| corrected while stalking near | stalking further | chasing "
        "| ρ (margin) | p | p (Holm) | ρ (return) | p | p (Holm) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        *body,
    ]


def ladder_levels_table(runs: list[dict[str, Any]]) -> list[str]:
    """Each kind's mean margin at every ladder level the runs hold, per setting, as markdown lines
    (— where a run of the group lacks the level)."""
    laddered = [r for r in runs if "ladders" in r and r["kind"] in ("residual", "hierarchical")]
    levels = list(dict.fromkeys(level for r in laddered for level in r["ladders"]))
    lines = [
        "Robustness ladders: mean margin against the run's own prey (mean over its predators, then",
        "over runs), at every level; the report tests the change from `none`, paired by seed.",
        "",
        "| setting | kind | runs | " + " | ".join(levels) + " |",
        "|---|---|---:|" + "---:|" * len(levels),
    ]
    for setting in dict.fromkeys(c for c, _ in rule_report.panels(laddered)) if laddered else []:
        for kind in ("residual", "hierarchical"):
            mine = [r for r in laddered if rule_report.setting_of(r) == setting and r["kind"] == kind]
            if not mine:
                continue
            cells = [
                f"{np.mean([r['ladders'][level]['margin'] for r in mine]):+.3f}"
                if all(level in r["ladders"] for r in mine)
                else "—"
                for level in levels
            ]
            lines.append(f"| {setting} | {kind} | {len(mine)} | " + " | ".join(cells) + " |")
    return lines


def tables(where: Path) -> str:
    """Both tables of the study in ``where``, as markdown; ValueError naming what is missing."""
    runs = rule_study.read_runs(where / "runs")
    if not any(r["kind"] == "residual" and "corrections" in r for r in runs):
        raise ValueError("no residual run with its corrections")
    lines = [f"`python studies/residual-value/residual_descriptives.py {where}`", ""]
    return "\n".join(lines + corrections_table(runs) + [""] + ladder_levels_table(runs)) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", type=Path, help="A study's folder (runs/*.json.gz).")
    parser.add_argument("--out", type=Path, help="Write the table here (else print it).")
    args = parser.parse_args()
    if not (args.study / "runs").is_dir():
        sys.exit(f"error: {args.study / 'runs'} is not a folder of a study's runs")
    if not any((args.study / "runs").glob("*.json.gz")):
        sys.exit(f"error: {args.study / 'runs'} holds no run (*.json.gz)")
    try:
        text = tables(args.study)
    except (OSError, ValueError) as error:  # unreadable, of another format, or no residual run
        sys.exit(f"error: {args.study / 'runs'}: {error}")
    except KeyError as error:
        sys.exit(f"error: {args.study / 'runs'}: a run lacks {error}: not a residual study's compact run")
    if args.out:
        atomic_write_text(args.out, text)
    else:
        print(text, end="")


if __name__ == "__main__":
    main()
