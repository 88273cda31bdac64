"""Two descriptive tables of the residual study, for docs/residual.md's reading of it: how much and
where its runs correct the rule, and the robustness ladders' levels beside their changes.

**Corrections**, one row per setting, a summary of the report's descriptive table (`analyze`'s
corrections of every residual run at its last budget, against its own prey): the median and the
largest share of states a predator corrected (one value per run and predator), how many of them
corrected more than a fifth of their states, the median share of states in chase, where the
corrected states lie (stalking within 0.5 of the prey, stalking further, chasing: pooled over runs
and predators), and Spearman's rank correlation over seeds between a run's share of states corrected
(mean over its predators) and how far its pool margin lies from the hierarchical run of its seed
(residual − hierarchical, mean over predators), and the same against the pool return (the primary
measure). The correlations are descriptive, not a test of the protocol: their p-values are given as
they are and with Holm over the table's correlations.

**Ladder levels**: the report tests the *change* of a run's margin from its unperturbed level; a
smaller drop can start from a lower level. This table gives each kind's mean margin (against its
own prey, mean over predators and runs) at every level of the ladders, residual and hierarchical.
No test.

    python scripts/residual_descriptives.py results/residual-study --out results/residual-study/descriptives.md
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.study import rule_report, rule_study, statistics

LEVELS = (
    "none",
    "obs-noise=0.02",
    "obs-noise=0.05",
    "obs-noise=0.1",
    "delay=1",
    "delay=3",
    "delay=6",
    "obstacles=2",
    "obstacles=4",
    "obstacles=6",
)
"""The ladders' levels, as a run's compact result names them (the protocol's rungs)."""
NEAR = 0.5
"""Distance to the prey below which a stalking state counts as near (a distance bin whose lower
edge is below it)."""


def _where(run: dict[str, Any]) -> np.ndarray:
    """Corrected states of a run, all predators: stalking near, stalking further, chasing."""
    counts = np.zeros(3)
    for corrections in run["corrections"].values():
        by_distance = corrections["correction_by_distance"]
        for mode in ("stalk", "chase"):
            table = by_distance[mode]
            for low, states, share in zip(by_distance["bins"], table["states"], table["corrected"], strict=False):
                if states:
                    slot = 2 if mode == "chase" else (0 if low < NEAR else 1)
                    counts[slot] += states * share
    return counts


def _pooled(run: dict[str, Any], measure: str, predators: list[str] | None = None) -> float:
    """A run's pool ``measure`` ("margin" or "return") at its last budget, the mean over
    ``predators`` (a residual run's own, by default)."""
    evaluations = run["pool"][rule_study.last_budget(run)]
    return float(np.mean([rule_study.pooled(evaluations, p)[measure] for p in predators or run["corrections"]]))


def corrections_table(runs: list[dict[str, Any]]) -> list[str]:
    """The corrections' summary, one row per setting, as markdown lines."""
    lines = [
        "Where the residual predator corrects the rule: every residual run at its last budget",
        "(`analyze`, its own prey); shares per run and predator;",
        f"where: corrected states pooled over runs and predators (near: within {NEAR:g} of the prey);",
        "Spearman over seeds: share of states corrected against residual − hierarchical pool margin,",
        "and against residual − hierarchical pool return (the primary measure); descriptive: p and p",
        "with Holm over the table's 12 correlations.",
        "",
        "| setting | residual runs | states corrected: median | largest | above 20 % | states in chase: median "
        "| corrected while stalking near | stalking further | chasing "
        "| ρ (margin) | p | p (Holm) | ρ (return) | p | p (Holm) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    rows, pvalues = [], []
    for setting in sorted({rule_report.setting_of(r) for r in runs}):
        mine = {r["seed"]: r for r in runs if rule_report.setting_of(r) == setting and r["kind"] == "residual"}
        other = {r["seed"]: r for r in runs if rule_report.setting_of(r) == setting and r["kind"] == "hierarchical"}
        if not mine:
            continue
        shares = [c["corrected"] for r in mine.values() for c in r["corrections"].values()]
        chase = [float(np.mean([c["p_chase"] for c in r["corrections"].values()])) for r in mine.values()]
        where_ = sum((_where(r) for r in mine.values()), np.zeros(3))
        where_ = where_ / max(where_.sum(), 1e-12)
        seeds = sorted(set(mine) & set(other))
        share_of = [np.mean([c["corrected"] for c in mine[s]["corrections"].values()]) for s in seeds]
        gaps = {
            measure: [
                _pooled(mine[s], measure) - _pooled(other[s], measure, list(mine[s]["corrections"])) for s in seeds
            ]
            for measure in ("margin", "return")
        }
        margin_rho = stats.spearmanr(share_of, gaps["margin"])
        return_rho = stats.spearmanr(share_of, gaps["return"])
        pvalues += [margin_rho.pvalue, return_rho.pvalue]
        rows.append(
            f"| {setting} | {len(mine)} | {np.median(shares):.1%} | {max(shares):.1%} "
            f"| {sum(s > 0.2 for s in shares)}/{len(shares)} | {np.median(chase):.1%} "
            f"| {where_[0]:.0%} | {where_[1]:.0%} | {where_[2]:.0%} "
            f"| {margin_rho.statistic:+.2f} | {margin_rho.pvalue:.3f} | {{}} "
            f"| {return_rho.statistic:+.2f} | {return_rho.pvalue:.3f} | {{}} |"
        )
    adjusted = statistics.holm(pvalues) if pvalues else np.array([])
    lines += [row.format(f"{adjusted[2 * i]:.3f}", f"{adjusted[2 * i + 1]:.3f}") for i, row in enumerate(rows)]
    return lines


def ladder_levels_table(runs: list[dict[str, Any]]) -> list[str]:
    """Each kind's mean margin at every ladder level, per setting, as markdown lines."""
    lines = [
        "Robustness ladders: mean margin against the run's own prey (mean over its predators, then",
        "over runs), at every level; the report tests the change from `none`, paired by seed.",
        "",
        "| setting | kind | runs | " + " | ".join(LEVELS) + " |",
        "|---|---|---:|" + "---:|" * len(LEVELS),
    ]
    for setting in sorted({rule_report.setting_of(r) for r in runs}):
        for kind in ("residual", "hierarchical"):
            mine = [r for r in runs if rule_report.setting_of(r) == setting and r["kind"] == kind and "ladders" in r]
            if not mine:
                continue
            cells = [
                f"{np.mean([r['ladders'][level]['margin'] for r in mine]):+.3f}" if level in mine[0]["ladders"] else "—"
                for level in LEVELS
            ]
            lines.append(f"| {setting} | {kind} | {len(mine)} | " + " | ".join(cells) + " |")
    return lines


def tables(where: Path) -> str:
    """Both tables of the study in ``where``, as markdown."""
    runs = rule_study.read_runs(where / "runs")
    lines = [f"`python scripts/residual_descriptives.py {where}`", ""]
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
    except (OSError, ValueError, KeyError, TypeError) as error:  # a file that is not a study's compact run
        sys.exit(f"error: {args.study / 'runs'}: not a residual study's runs ({type(error).__name__}: {error})")
    if args.out:
        atomic_write_text(args.out, text)
    else:
        print(text, end="")


if __name__ == "__main__":
    main()
