"""Figures: one evaluation's bars (eval.png), and a sweep's Fig. 2 and learning curves (report)."""

from __future__ import annotations

import io
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt
import numpy as np

BASELINES = (("always_chase", "always chase", "#dd8452"), ("always_stalk", "always stalk", "#55a868"))
TRAINED_COLOR = "#4c72b0"


def reward_bars_png(result: dict[str, Any]) -> bytes:
    """PNG bytes of one panel per predator: three bars (the trained predator, labelled by its
    kind; always chase; always stalk)."""
    panels = result["panels"]
    bars = (("trained", result.get("predator_kind", "trained"), TRAINED_COLOR), *BASELINES)
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels) + 0.8, 3.4), squeeze=False, sharey=True)
    for ax, panel in zip(axes[0], panels, strict=True):
        values = [panel[key] for key, _, _ in bars]
        ax.bar([label for _, label, _ in bars], values, color=[color for _, _, color in bars])
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_title(panel["predator"])
        ax.tick_params(axis="x", labelrotation=20)
        for x, v in enumerate(values):
            ax.annotate(f"{v:.2f}", (x, v), ha="center", va="bottom" if v >= 0 else "top", fontsize=8)
    axes[0][0].set_ylabel("mean cumulative reward")
    fig.suptitle(f"{result['condition']}: {result['episodes']} episodes, seed {result['seed']}")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


#: Bar colours of the report's variants.
VARIANT_COLORS = {
    "hierarchical": TRAINED_COLOR,
    "flat": "#8172b3",
    "always_chase": BASELINES[0][2],
    "always_stalk": BASELINES[1][2],
}
LABELS = {
    "hierarchical": "hierarchical",
    "flat": "flat",
    "always_chase": "always chase",
    "always_stalk": "always stalk",
}


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    plt.close(fig)
    return buffer.getvalue()


def fig2_png(table: list[dict[str, Any]]) -> bytes:
    """The paper's Fig. 2 over seeds: one row per condition, one panel per predator; a bar per
    variant at its mean over seeds, its 95 % interval, and each seed's value as a dot."""
    conditions = list(dict.fromkeys(t["condition"] for t in table))
    columns = max(sum(t["condition"] == c for t in table) for c in conditions)
    fig, axes = plt.subplots(
        len(conditions), columns, figsize=(3.6 * columns, 2.3 * len(conditions) + 0.6), squeeze=False, sharey=True
    )
    for row, condition in enumerate(conditions):
        entries = [t for t in table if t["condition"] == condition]
        for col in range(columns):
            ax = axes[row][col]
            if col >= len(entries):
                ax.set_visible(False)
                continue
            variants = entries[col]["variants"]
            for x, (name, v) in enumerate(variants.items()):
                ax.bar(x, v["mean"], color=VARIANT_COLORS.get(name, "grey"), width=0.7)
                if v["ci"] is not None:
                    lo, hi = v["ci"]
                    ax.errorbar(x, v["mean"], yerr=[[v["mean"] - lo], [hi - v["mean"]]], color="black", capsize=3, lw=1)
                ax.scatter([x] * len(v["values"]), v["values"], color="black", s=6, zorder=3)
            ax.set_xticks(range(len(variants)), [LABELS.get(n, n) for n in variants], fontsize=7, rotation=20)
            ax.axhline(0.0, color="black", linewidth=0.6)
            ax.set_title(f"{condition} · {entries[col]['predator']}", fontsize=9)
            ax.tick_params(axis="y", labelsize=7)
        axes[row][0].set_ylabel("mean return", fontsize=8)
    seeds = max(len(v["values"]) for t in table for v in t["variants"].values())
    fig.suptitle(f"Mean return per predator over {seeds} seeds\n95 % bootstrap interval; dots: seeds", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def curves_png(curves: dict[str, dict[str, Any]]) -> bytes:
    """Learning curves: per condition, every agent's return (top) and the capture rate
    (bottom) against episodes, mean over seeds with a 95 % band; one line style per kind."""
    conditions = list(curves)
    columns = min(5, len(conditions))
    rows = -(-len(conditions) // columns)
    fig, axes = plt.subplots(2 * rows, columns, figsize=(3.4 * columns, 4.6 * rows + 0.6), squeeze=False)
    styles = {"hierarchical": "-", "flat": "--"}
    agent_colors = plt.get_cmap("tab10")
    for i, condition in enumerate(conditions):
        top, bottom = axes[2 * (i // columns)][i % columns], axes[2 * (i // columns) + 1][i % columns]
        for kind, curve in curves[condition].items():
            x = curve["episodes"]
            for j, (label, series) in enumerate(curve["series"].items()):
                ax = bottom if label == "capture_rate" else top
                color = "black" if label == "capture_rate" else agent_colors(j)
                name = label.removeprefix("return/")
                ax.plot(x, series["mean"], styles.get(kind, ":"), color=color, lw=1.2, label=f"{name} ({kind})")
                if series["ci"] is not None:
                    ax.fill_between(x, series["ci"][0], series["ci"][1], color=color, alpha=0.15, lw=0)
        top.set_title(condition, fontsize=9)
        top.set_ylabel("return", fontsize=8)
        bottom.set_ylabel("capture rate", fontsize=8)
        bottom.set_xlabel("episode", fontsize=8)
        bottom.set_ylim(0, 1)
        for ax in (top, bottom):
            ax.tick_params(labelsize=7)
        top.legend(fontsize=6, loc="lower right")
    for j in range(len(conditions), rows * columns):
        axes[2 * (j // columns)][j % columns].set_visible(False)
        axes[2 * (j // columns) + 1][j % columns].set_visible(False)
    fig.suptitle(
        "Learning curves: mean over seeds, 95 % bootstrap band\nsolid: hierarchical, dashed: flat", fontsize=10
    )
    fig.tight_layout()
    return _png(fig)


def fig3_png(analysis: dict[str, Any], embeddings: dict[str, Any], closest: dict[str, Any]) -> bytes:
    """The paper's Fig. 3: for each predator, its value stream's t-SNE embedding coloured by
    V(s), by its distance to the prey and, with other predators, by whether it is the closest."""
    names = list(embeddings)
    several = len(names) > 1
    columns = 3 if several else 2
    fig, axes = plt.subplots(len(names), columns, figsize=(4.2 * columns, 3.8 * len(names)), squeeze=False)
    for row, name in enumerate(names):
        xy = embeddings[name]["xy"]
        score = analysis[name]["organisation"]
        panels = [
            (embeddings[name]["value"], "viridis", f"{name}: V(s) (organisation R² {score['value']:.2f})"),
            (embeddings[name]["distance"], "magma", f"{name}: distance to prey (R² {score['distance']:.2f})"),
        ]
        if several:
            panels.append((closest[name].astype(float), "coolwarm", f"{name}: closest to the prey (red)"))
        for ax, (colour, cmap, title) in zip(axes[row], panels, strict=True):
            points = ax.scatter(xy[:, 0], xy[:, 1], c=colour, cmap=cmap, s=4, linewidths=0)
            ax.set_title(title, fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            fig.colorbar(points, ax=ax, fraction=0.046, pad=0.02)
    fig.suptitle("t-SNE of the value stream's last hidden layer", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def modes_png(curves: dict[str, dict[str, Any]], title: str) -> bytes:
    """P(chase) against distance to the prey, one line per curve (with its 95 % band when
    given), and the number of states behind each point as bars below."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    colors = plt.get_cmap("tab10")
    for k, (label, curve) in enumerate(curves.items()):
        bins = np.asarray(curve["bins"])
        centres = (bins[:-1] + bins[1:]) / 2
        p = np.array([np.nan if v is None else v for v in curve["p_chase"]], dtype=float)
        top.plot(centres, p, "o-", color=colors(k), ms=3, label=label)
        if curve.get("ci") is not None:
            low, high = (np.array([np.nan if v is None else v for v in c], dtype=float) for c in curve["ci"])
            top.fill_between(centres, low, high, color=colors(k), alpha=0.15, lw=0)
        width = (bins[1] - bins[0]) / (len(curves) + 1)
        bottom.bar(centres + (k - len(curves) / 2) * width, curve["states"], width=width, color=colors(k))
    top.set_ylabel("P(chase)")
    top.set_ylim(-0.02, 1.02)
    top.legend(fontsize=8)
    top.set_title(title, fontsize=10)
    bottom.set_ylabel("states")
    bottom.set_xlabel("distance to the prey")
    fig.tight_layout()
    return _png(fig)
