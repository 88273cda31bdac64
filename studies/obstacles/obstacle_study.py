"""The obstacle experiment (docs/obstacles.md): its table and figure from compact results.

    # once, after the sweeps:
    python studies/obstacles/obstacle_study.py --export sweeps/obstacles sweeps/obstacles-noavoid
    python studies/obstacles/obstacle_study.py                                                       # table and figure

``--export`` writes the two sweeps' results into ``results/obstacles/avoidance`` and
``results/obstacles/plain`` (``report.export``: gzip JSON per run). Without it, the table (printed,
markdown) and ``docs/figures/obstacles.png`` are made from those and, for the empty arena at the
same budget, from ``results/obstacles/empty`` (the first reproduction sweep's runs of these
conditions: the hierarchical runs' 5000-episode checkpoints, the flat runs' final 4500 episodes).
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.io.files import atomic_write_bytes
from pursuit_bench.reports import reproduction as report

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "results" / "obstacles"
FIGURE = ROOT / "docs" / "figures" / "obstacles.png"
CONDITIONS = ("1p-high", "2p-high-shared", "3p-high-individual")
#: (label, results folder, predator kind, budget: None for the final evaluation)
VARIANTS = (
    ("hierarchical, avoidance", RESULTS / "avoidance", "hierarchical", None),
    ("hierarchical, plain navigation", RESULTS / "plain", "hierarchical", None),
    ("flat", RESULTS / "avoidance", "flat", None),
    ("hierarchical, no obstacles", RESULTS / "empty", "hierarchical", 5000),
    ("flat, no obstacles", RESULTS / "empty", "flat", None),
)


def _evaluation(run: report.RunResult, budget: int | None) -> dict[str, Any]:
    return run.evaluation if budget is None else run.milestones[budget]


def rows() -> list[dict[str, Any]]:
    """One row per condition and variant: means over seeds (and over predators) with 95 %
    t-intervals over seeds; the margin over the better baseline paired by seed, with the
    one-sided p-values of its paired t-test each way, and those Holm-adjusted over the table's
    rows (one family a direction)."""
    loaded: dict[Path, list[report.RunResult]] = {}
    table = []
    for condition in CONDITIONS:
        for label, folder, kind, budget in VARIANTS:
            runs = loaded.setdefault(folder, report.collect(folder))
            chosen = [_evaluation(r, budget) for r in runs if r.condition == condition and r.kind == kind]
            panels = [e["panels"] for e in chosen]
            trained = np.array([np.mean([p["trained"] for p in ps]) for ps in panels])
            best = np.array([np.mean([max(p["always_chase"], p["always_stalk"]) for p in ps]) for ps in panels])
            paired = stats.paired_difference(trained, best)  # seed by seed: same prey, same episodes
            row: dict[str, Any] = {
                "condition": condition,
                "variant": label,
                "seeds": len(chosen),
                "trained": float(trained.mean()),
                "trained_interval": stats.t_interval(trained),
                "best_baseline": float(best.mean()),
                "margin": paired["mean"],
                "margin_interval": paired["ci"],
                "margin_p_greater": paired["p_greater"],
                "margin_p_less": paired["p_less"],
                "capture_rate": float(np.mean([e["capture_rate"] for e in chosen])),
                "episode_length": float(np.mean([e["episode_length"] for e in chosen])),
            }
            if "obstacle_collisions" in chosen[0]:
                predators = [p["predator"] for p in panels[0]]
                for key in ("obstacle_collisions", "obstacle_contact_steps"):
                    row[key] = float(np.mean([np.mean([e[key][p] for p in predators]) for e in chosen]))
                    row[f"prey_{key}"] = float(np.mean([e[key]["prey_0"] for e in chosen]))
            table.append(row)
    for side in ("margin_p_greater", "margin_p_less"):
        for row, adjusted in zip(table, stats.holm([r[side] for r in table]), strict=True):
            row[f"{side}_holm"] = float(adjusted)
    return table


def _span(interval: list[float] | None) -> str:
    return f" [{interval[0]:+.2f}, {interval[1]:+.2f}]" if interval else ""


def markdown(table: list[dict[str, Any]]) -> str:
    lines = [
        "| condition | predators | seeds | return as trained | best baseline | margin over it "
        "| p (margin > 0): raw / Holm | p (margin < 0): Holm "
        "| captures | collisions (contact steps) per predator-episode | the prey's |",
        "|---|---|---|---|---|---|---:|---:|---|---|---|",
    ]
    for r in table:
        if "obstacle_collisions" in r:
            hits = f"{r['obstacle_collisions']:.2f} ({r['obstacle_contact_steps']:.1f})"
            prey = f"{r['prey_obstacle_collisions']:.2f} ({r['prey_obstacle_contact_steps']:.1f})"
        else:
            hits = prey = "–"
        lines.append(
            f"| {r['condition']} | {r['variant']} | {r['seeds']} | {r['trained']:+.3f}{_span(r['trained_interval'])} "
            f"| {r['best_baseline']:+.3f} | {r['margin']:+.3f}{_span(r['margin_interval'])} "
            f"| {r['margin_p_greater']:.3f} / {r['margin_p_greater_holm']:.3f} | {r['margin_p_less_holm']:.3f} "
            f"| {r['capture_rate']:.0%} | {hits} | {prey} |"
        )
    return "\n".join(lines) + "\n"


def figure(table: list[dict[str, Any]]) -> bytes:
    """Two panels per condition: the predators' margin over the better baseline, and their
    contact steps with obstacles per episode, by variant (intervals over seeds)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [v[0] for v in VARIANTS]
    colours = ["#c0392b", "#e67e22", "#2c3e80", "#e8a59d", "#9aa5ce"]
    fig, axes = plt.subplots(2, len(CONDITIONS), figsize=(12, 6.5), sharey="row")
    for c, condition in enumerate(CONDITIONS):
        here = [r for r in table if r["condition"] == condition]
        x = np.arange(len(here))
        margins = [r["margin"] for r in here]
        errors = np.array(
            [
                [r["margin"] - r["margin_interval"][0], r["margin_interval"][1] - r["margin"]]
                if r["margin_interval"]
                else [0.0, 0.0]
                for r in here
            ]
        ).T
        ax = axes[0, c]
        ax.bar(x, margins, yerr=errors, color=colours, capsize=3)
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_title(condition)
        ax.set_xticks([])
        if c == 0:
            ax.set_ylabel("return margin over the better baseline\n(mean over seeds, 95 % interval)")
        ax = axes[1, c]
        contact = [r.get("obstacle_contact_steps", 0.0) for r in here]
        ax.bar(x, contact, color=colours)
        ax.set_xticks([])
        if c == 0:
            ax.set_ylabel("steps touching an obstacle\nper predator and episode")
    handles = [plt.Rectangle((0, 0), 1, 1, color=col) for col in colours]
    fig.legend(handles, labels, loc="lower center", ncol=3, frameon=False)
    fig.suptitle("5 obstacles of radius 0.15, 5000 training episodes (baselines use the same lower layer)")
    fig.tight_layout(rect=(0, 0.08, 1, 0.97))
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    return buffer.getvalue()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--export", nargs=2, metavar=("AVOIDANCE_SWEEP", "PLAIN_SWEEP"), type=Path)
    args = parser.parse_args()
    if args.export:
        for sweep, out in zip(args.export, (RESULTS / "avoidance", RESULTS / "plain"), strict=True):
            size = report.export(report.collect(sweep), out, {"sweep": str(sweep)})
            print(f"{out}: {size / 1e3:.0f} kB")
    table = rows()
    atomic_write_bytes(FIGURE, figure(table))
    print(markdown(table))


if __name__ == "__main__":
    main()
