"""Figures: one evaluation's bars (eval.png), and a sweep's Fig. 2 and learning curves (report)."""

from __future__ import annotations

import io
import textwrap
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.lines
import matplotlib.pyplot as plt
import matplotlib.ticker
import numpy as np

from pursuit_bench.stats.intervals import wilson_bounds

BASELINES = (("always_chase", "always chase", "#dd8452"), ("always_stalk", "always stalk", "#55a868"))
TRAINED_COLOR = "#4c72b0"


def reward_bars_png(result: dict[str, Any], run: str | None = None) -> bytes:
    """PNG bytes of one panel per predator: three bars (the trained predator, labelled by its
    kind; always chase; always stalk), each with its standard error; the title names the run
    (``run``, or the shipped agents' condition and seed) and the evaluation."""
    panels = result["panels"]
    bars = (("trained", _bar_label(result.get("predator_kind", "trained")), TRAINED_COLOR), *BASELINES)
    width = max(3.2 * len(panels) + 0.8, 5.2)  # room for the two-line title over one panel
    fig, axes = plt.subplots(1, len(panels), figsize=(width, 3.6), squeeze=False, sharey=True)
    low = min(min(p[k] - p["stderr"][k] for k, _, _ in bars) for p in panels)
    high = max(max(p[k] + p["stderr"][k] for k, _, _ in bars) for p in panels)
    margin = 0.25 * max(high - low, 0.1)
    for ax, panel in zip(axes[0], panels, strict=True):
        values = [panel[key] for key, _, _ in bars]
        errors = [panel["stderr"][key] for key, _, _ in bars]
        ax.bar([label for _, label, _ in bars], values, color=[color for _, _, color in bars])
        ax.errorbar(range(len(values)), values, yerr=errors, fmt="none", color="black", capsize=3, lw=1)
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_title(panel["predator"])
        ax.tick_params(axis="x", labelrotation=20)
        for x, (v, e) in enumerate(zip(values, errors, strict=True)):
            y = v + e if v >= 0 else v - e  # beyond the error bar's end, moved off it by a few points
            ax.annotate(
                f"{v:+.2f}",
                (x, y),
                xytext=(0, 3 if v >= 0 else -3),
                textcoords="offset points",
                ha="center",
                va="bottom" if v >= 0 else "top",
                fontsize=8,
            )
        ax.set_ylim(min(low, 0.0) - margin, max(high, 0.0) + margin)
    axes[0][0].set_ylabel("mean cumulative reward (± s.e.)")
    shipped = result.get("pretrained")
    if shipped:
        who = f"shipped agents of {result['condition']} (seed {shipped.get('seed', '?')})"
    else:
        who = f"{run or 'run'}: {result['condition']}"
    trained = result.get("trained_episodes")
    trained_text = f", trained {trained} episodes" if trained is not None else ""
    fig.suptitle(f"{who}{trained_text}\nevaluation: {result['episodes']} episodes, seed {result['seed']}", fontsize=10)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def interval_words(seeds: int) -> str:
    """What a plotted interval is, honestly: a t-interval over the seeds (with two, a wide
    one); none for one seed."""
    if seeds >= 2:
        return f"95 % t-interval over {seeds} seeds"
    return "1 seed: no interval"


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


def _seed_bar(ax: Any, x: float, cell: dict[str, Any], color: str) -> None:
    """A bar at ``cell``'s mean over seeds, its interval (where it has one) and each seed's value as a dot."""
    ax.bar(x, cell["mean"], color=color, width=0.7)
    if cell["ci"] is not None:
        lo, hi = cell["ci"]
        ax.errorbar(x, cell["mean"], yerr=[[cell["mean"] - lo], [hi - cell["mean"]]], color="black", capsize=3, lw=1)
    ax.scatter([x] * len(cell["values"]), cell["values"], color="black", s=6, zorder=3)


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
                _seed_bar(ax, x, v, VARIANT_COLORS.get(name, "grey"))
            ax.set_xticks(range(len(variants)), [LABELS.get(n, n) for n in variants], fontsize=7, rotation=20)
            ax.axhline(0.0, color="black", linewidth=0.6)
            ax.set_title(f"{condition} · {entries[col]['predator']}", fontsize=9)
            ax.tick_params(axis="y", labelsize=7)
        axes[row][0].set_ylabel("mean return", fontsize=8)
    present = [n for n in LABELS if any(n in t["variants"] for t in table)]
    per_variant = {n: max(len(t["variants"][n]["values"]) for t in table if n in t["variants"]) for n in present}
    seeds = max(per_variant.values())
    fewer = [f"{LABELS[n]} {k}" for n, k in per_variant.items() if k != seeds]
    over = f"{seeds} seeds" + (f" ({', '.join(fewer)})" if fewer else "")
    words = "95 % t-interval over seeds" if seeds >= 2 else interval_words(seeds)
    fig.suptitle(f"Mean return per predator over {over}\n{words}; dots: seeds", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def fig2_budgets_png(rows: list[dict[str, Any]], budgets: list[str], episodes: int) -> bytes:
    """The paper's Fig. 2 of the same runs at ``budgets``: one row per kind, one panel per
    predator; in each, a group of bars per budget (the learned predator, always-chase,
    always-stalk, each with its own co-trained prey, ``episodes`` a variant) at the mean over
    runs, its 95 % interval, and each run's value as a dot; a budget not yet played is marked so."""
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    columns = max(sum(r["kind"] == k for r in rows) for k in kinds)
    fig, axes = plt.subplots(
        len(kinds), columns, figsize=(2.9 * columns, 2.6 * len(kinds) + 0.9), squeeze=False, sharey=True
    )
    variants = ("trained", "always_chase", "always_stalk")
    for row, kind in enumerate(kinds):
        entries = [r for r in rows if r["kind"] == kind]
        for col in range(columns):
            ax = axes[row][col]
            if col >= len(entries):
                ax.set_visible(False)
                continue
            for g, budget in enumerate(budgets):
                entry = entries[col]["budgets"].get(budget)
                left = g * (len(variants) + 1)
                if entry is None:
                    ax.text(left + 1, 0.5, "not yet\nplayed", ha="center", va="center", fontsize=7, color="grey",
                            transform=ax.get_xaxis_transform())  # fmt: skip
                    continue
                for v, name in enumerate(variants):
                    _seed_bar(
                        ax, left + v, entry[name], VARIANT_COLORS.get(kind if name == "trained" else name, "grey")
                    )
            centres = [g * (len(variants) + 1) + 1 for g in range(len(budgets))]
            ax.set_xlim(-0.7, centres[-1] + 1.7)
            ax.set_xticks(centres, [f"{int(b):,}\nepisodes" for b in budgets], fontsize=7)
            ax.axhline(0.0, color="black", linewidth=0.6)
            ax.set_title(f"{entries[col]['condition']} · {entries[col]['predator']}", fontsize=8)
            ax.tick_params(axis="y", labelsize=7)
        axes[row][0].set_ylabel(f"{kind} runs\nmean return", fontsize=8)
    handles = [plt.Rectangle((0, 0), 1, 1, color=VARIANT_COLORS[k]) for k in (*kinds, "always_chase", "always_stalk")]
    labels = [f"learned ({k})" for k in kinds] + [LABELS["always_chase"], LABELS["always_stalk"]]
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=7, frameon=False)
    runs = sorted({len(e["seeds"]) for r in rows for e in r["budgets"].values()})
    counts = "–".join(str(n) for n in (runs[0], runs[-1])) if len(set(runs)) > 1 else str(runs[0] if runs else 0)
    fig.suptitle(
        f"The paper's Fig. 2 of the same runs at {' and '.join(f'{int(b):,}' for b in budgets)} episodes: "
        f"own co-trained prey, {episodes} episodes a variant\n"
        f"bars: mean over {counts} runs, 95 % t-interval; dots: runs",
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return _png(fig)


def curves_png(curves: dict[str, dict[str, Any]]) -> bytes:
    """Learning curves: per condition, every agent's return (top) and the capture rate
    (bottom) against episodes, mean over seeds with their interval; the predators' line style
    says their kind, the prey is named alone."""
    conditions = list(curves)
    columns = min(5, len(conditions))
    rows = -(-len(conditions) // columns)
    fig, axes = plt.subplots(2 * rows, columns, figsize=(max(3.4 * columns, 5.6), 4.6 * rows + 0.6), squeeze=False)
    styles = {"hierarchical": "-", "flat": "--"}
    kinds = sorted({kind for c in curves.values() for kind in c})
    seeds = max((curve.get("seeds", 0) for c in curves.values() for curve in c.values()), default=0)
    for i, condition in enumerate(conditions):
        top, bottom = axes[2 * (i // columns)][i % columns], axes[2 * (i // columns) + 1][i % columns]
        for kind, curve in curves[condition].items():
            x = curve["episodes"]
            for label, series in curve["series"].items():
                ax = bottom if label == "capture_rate" else top
                name = label.removeprefix("return/")
                color = "black" if label == "capture_rate" else agent_color(name)
                ax.plot(x, series["mean"], styles.get(kind, ":"), color=color, **_marks(name, len(x)))
                if series["ci"] is not None:
                    ax.fill_between(x, series["ci"][0], series["ci"][1], color=color, alpha=0.15, lw=0)
        top.set_title(condition, fontsize=9)
        top.set_ylabel("return", fontsize=8)
        bottom.set_ylabel("capture rate", fontsize=8)
        bottom.set_xlabel("episode", fontsize=8)
        bottom.set_ylim(-0.03, 1.03)  # a rate of 1.0 stays inside the frame
        for ax in (top, bottom):
            ax.tick_params(labelsize=7)
    for j in range(len(conditions), rows * columns):
        axes[2 * (j // columns)][j % columns].set_visible(False)
        axes[2 * (j // columns) + 1][j % columns].set_visible(False)
    per_kind = {kind: max(c[kind]["seeds"] for c in curves.values() if kind in c) for kind in kinds}
    blocks = _block_words(curves)
    if len(set(per_kind.values())) > 1:
        counts = ", ".join(f"{kind} {n}" for kind, n in per_kind.items())
        heading = f"Learning curves ({blocks}): mean over seeds ({counts}), 95 % t-interval over seeds"
    elif seeds > 1:
        heading = f"Learning curves ({blocks}): mean over {seeds} seeds, {interval_words(seeds)}"
    else:
        heading = f"Learning curves of one run ({blocks})"
    if len(kinds) > 1:
        heading += "\n" + ", ".join(
            f"{'solid' if k == 'hierarchical' else 'dashed'}: {k}" for k in kinds if k in styles
        )
    fig.suptitle(heading, fontsize=10)
    names = sorted({k.removeprefix("return/") for c in curves.values() for v in c.values() for k in v["series"]})
    handles = [
        matplotlib.lines.Line2D([], [], color=agent_color(n), label=n, **_marks(n, 1))
        for n in names
        if n != "capture_rate"
    ]
    handles += [matplotlib.lines.Line2D([], [], color="black", label="capture rate")]
    if len(kinds) > 1:  # the line style says the predators' kind (the prey's too: it trained against them)
        handles += [
            matplotlib.lines.Line2D([], [], color="grey", ls=styles.get(k, ":"), label=f"{k} runs") for k in kinds
        ]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.35 / fig.get_figheight(), 1, 1))  # the legend's row at the bottom
    return _png(fig)


def _marks(name: str, points: int) -> dict[str, Any]:
    """How an agent's line is drawn: predator_0 widest, each later predator narrower (drawn over
    it) and with markers at points of its own: with a shared reward the predators' returns nearly
    coincide, and a line under another still shows at its edges. The prey and the capture rate
    plainly."""
    if not name.startswith("predator_"):
        return {"lw": 1.2}
    k = int(name.rsplit("_", 1)[-1])
    if k == 0:
        return {"lw": 2.6}
    every = max(1, points // 10)
    return {
        "lw": max(0.7, 2.6 - 0.9 * k),
        "marker": "os^D"[(k - 1) % 4],
        "ms": 3.5,
        "markevery": ((k - 1) * every // 2 % every, every),
    }


def _block_words(curves: dict[str, dict[str, Any]]) -> str:
    """The block the curves' points are means of, in words: "block means of 100 episodes" (the
    spacing of the points, which sit at the blocks' middles; the largest where they differ)."""
    steps = {
        round(float(s))
        for c in curves.values()
        for curve in c.values()
        for s in np.diff(np.asarray(curve["episodes"], dtype=float))
    }
    if not steps:
        return "block means of the training episodes"
    if steps == {1}:
        return "one point per episode"
    if len(steps) == 1:
        return f"block means of {steps.pop():,} episodes"
    return f"block means of up to {max(steps):,} episodes"


def _bar_label(kind: str) -> str:
    """The trained bar's label: an outside agent's spec by its last part, on a line of its own
    (``external (/long/path/model.zip)`` as ``external`` over ``model.zip``), so the tick fits."""
    head, bracket, spec = kind.partition(" (")
    if not bracket:
        return kind
    return f"{head}\n{Path(spec.removesuffix(')')).name}"


def agent_color(name: str) -> Any:
    """An agent's colour in the learning curves: predator_k the k-th of tab10, the prey red."""
    palette = plt.get_cmap("tab10")
    return palette(3) if name.startswith("prey") else palette(int(name.rsplit("_", 1)[-1]) % 3)


def fig3_png(analysis: dict[str, Any], embeddings: dict[str, Any], closest: dict[str, Any], title: str = "") -> bytes:
    """The paper's Fig. 3: for each predator, its value stream's t-SNE embedding coloured by
    V(s), by its distance to the prey and, with other predators, by whether it is the closest
    (two colours, a legend: a yes/no has no colour bar)."""
    names = list(embeddings)
    several = len(names) > 1
    columns = 3 if several else 2
    fig, axes = plt.subplots(len(names), columns, figsize=(4.2 * columns, 3.8 * len(names)), squeeze=False)
    for row, name in enumerate(names):
        xy = embeddings[name]["xy"]
        score = analysis[name]["organisation"]
        panels = [
            (embeddings[name]["value"], "viridis", f"{name}: V(s) (organisation R² {score['value']:.2f})", "V(s)"),
            (
                embeddings[name]["distance"],
                "magma",
                f"{name}: distance to prey (R² {score['distance']:.2f})",
                "distance to the prey",
            ),
        ]
        for ax, (colour, cmap, panel_title, unit) in zip(axes[row], panels, strict=False):
            points = ax.scatter(xy[:, 0], xy[:, 1], c=colour, cmap=cmap, s=4, linewidths=0)
            ax.set_title(panel_title, fontsize=9)
            fig.colorbar(points, ax=ax, fraction=0.046, pad=0.02).set_label(unit, fontsize=8)
        if several:
            ax = axes[row][2]
            nearest = closest[name].astype(bool)
            ax.scatter(xy[~nearest, 0], xy[~nearest, 1], color="#4c72b0", s=4, linewidths=0, label="another is closer")
            ax.scatter(xy[nearest, 0], xy[nearest, 1], color="#c44e52", s=4, linewidths=0, label="closest to the prey")
            ax.set_title(f"{name}: closest to the prey?", fontsize=9)
            ax.legend(fontsize=7, markerscale=3, loc="best")
        for ax in axes[row]:
            ax.set_xticks([])
            ax.set_yticks([])
    heading = "t-SNE of the value stream's last hidden layer"
    fig.suptitle(f"{title}\n{heading}" if title else heading, fontsize=10)
    fig.tight_layout()
    return _png(fig)


def modes_png(curves: dict[str, dict[str, Any]], title: str) -> bytes:
    """P(chase) against distance to the prey, one line per curve with its 95 % band (over seeds
    when given, else Wilson's for the states of one run), and the number of states behind each
    point as bars below; the x axis ends where the data do."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    colors = plt.get_cmap("tab10")
    for k, (label, curve) in enumerate(curves.items()):
        bins = np.asarray(curve["bins"])
        centres = (bins[:-1] + bins[1:]) / 2
        p = np.array([np.nan if v is None else v for v in curve["p_chase"]], dtype=float)
        top.plot(centres, p, "o-", color=colors(k), ms=3, label=label)
        if curve.get("ci") is not None:
            low, high = (np.array([np.nan if v is None else v for v in c], dtype=float) for c in curve["ci"])
        else:  # one run: Wilson's 95 % interval of a proportion, its states counted as independent
            low, high = wilson_bounds(p, np.asarray(curve["states"], dtype=float))
        top.fill_between(centres, low, high, color=colors(k), alpha=0.15, lw=0)
        width = (bins[1] - bins[0]) / (len(curves) + 1)
        bottom.bar(centres + (k - len(curves) / 2) * width, curve["states"], width=width, color=colors(k))
    filled = [
        c
        for curve in curves.values()
        for c, n in zip(
            (np.asarray(curve["bins"])[:-1] + np.asarray(curve["bins"])[1:]) / 2, curve["states"], strict=True
        )
        if n
    ]
    if filled:  # the x axis ends where the data do
        step = float(np.diff(np.asarray(next(iter(curves.values()))["bins"]))[0])
        top.set_xlim(min(filled) - step, max(filled) + step)
    top.set_ylabel("P(chase)")
    top.set_ylim(-0.02, 1.02)
    top.legend(fontsize=8)
    over_seeds = any(curve.get("ci") is not None for curve in curves.values())
    band = (
        "band: 95 % t-interval over seeds, kept in [0, 1]"
        if over_seeds
        else "band: Wilson's 95 % interval, the bin's states taken as independent (so too narrow)"
    )
    top.set_title(f"{title}\n{band}", fontsize=9)
    bottom.set_ylabel("states")
    bottom.set_xlabel("distance to the prey")
    fig.tight_layout()
    return _png(fig)


def budget_png(rows: list[dict[str, Any]]) -> bytes:
    """The verdicts against the training budget: panels better, equivalent, not resolved and worse
    (Holm-corrected paired tests at each budget), and the strict count per seed (mean, least to most)
    beside the paper's 16."""
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    episodes = [r["episodes"] for r in rows]
    panels = rows[-1]["panels"]
    for key, label, style, color in (
        ("better", "better (significant against both baselines)", "o-", TRAINED_COLOR),
        ("equivalent", "equivalent (within ±0.05 of the better baseline)", "^-", "#8172b3"),
        ("not resolved", "not resolved", "s--", "grey"),
        ("worse", "worse (a baseline significantly ahead)", "v-", "#c44e52"),
    ):
        ax.plot(episodes, [r[key] for r in rows], style, color=color, label=label)
    means = np.array([r["per_seed_mean"] for r in rows])
    spread = [means - [r["per_seed_min"] for r in rows], [r["per_seed_max"] for r in rows] - means]
    ax.errorbar(
        episodes,
        means,
        yerr=spread,
        fmt="D:",
        color="black",
        ms=4,
        capsize=3,
        label="strict count per seed: mean, least–most",
    )
    ax.axhline(16, color="grey", lw=0.8, ls="-.")
    ax.annotate("paper, one seed: 16", (episodes[0], 16), xytext=(3, 3), textcoords="offset points", fontsize=8)
    ax.set_xscale("log")
    ax.set_xticks(episodes, [f"{e / 1000:g}k" for e in episodes], rotation=45, fontsize=8)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_ylim(0, panels + 0.5)
    ax.set_xlabel("training episodes per run")
    ax.set_ylabel(f"panels (of {panels})")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=2)
    ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_title("The hierarchical predator against the baselines, by training budget", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def margins_png(rows: list[dict[str, Any]]) -> bytes:
    """Each panel's margin over its better baseline against the training budget (log axis): the
    mean over seeds with its 95 % t-interval, a panel a line, a condition a colour."""
    budgets = sorted({int(b) for r in rows for b in r["budgets"]})
    conditions = list(dict.fromkeys(r["condition"] for r in rows))
    colors = matplotlib.colormaps["tab10"]
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    for r in rows:
        k = conditions.index(r["condition"])
        shown = [b for b in budgets if str(b) in r["budgets"]]
        means = np.array([r["budgets"][str(b)]["mean"] for b in shown])
        cis = [r["budgets"][str(b)]["ci"] for b in shown]
        offset = 1 + 0.03 * (int(r["predator"].removeprefix("predator_")) - 1)  # panels of a condition side by side
        x = np.array(shown, dtype=float) * offset
        ax.plot(
            x, means, "o-", color=colors(k), ms=4, lw=1, label=r["condition"] if r["predator"] == "predator_0" else None
        )
        if all(ci is not None for ci in cis):
            low, high = np.array(cis).T
            ax.vlines(x, low, high, color=colors(k), lw=0.8)
    ax.axhline(0, color="grey", lw=0.8)
    ax.set_xscale("log")
    ax.set_xticks(budgets, [f"{b / 1000:g}k" for b in budgets], fontsize=8)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("training episodes per run (log)")
    ax.set_ylabel("margin over the better baseline (return)")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("Margins against the training budget (mean over seeds, 95 % t-interval)", fontsize=10)
    fig.tight_layout()
    return _png(fig)


def forest_png(rows: list[dict[str, Any]]) -> bytes:
    """The paired differences (hierarchical minus baseline, mean over seeds), one row per panel
    and baseline, at every budget evaluated (a marker each), each with its 95 % t-interval; rows
    whose final-budget comparison is significant after Holm's correction are named in bold."""
    budgets = sorted({int(b) for r in rows for b in r["budgets"]})
    final = str(budgets[-1])
    fig, ax = plt.subplots(figsize=(7.6, 0.2 * len(rows) + 1.6))
    markers = ["o", "s", "D", "^", "v", "P"]
    shades = plt.get_cmap("viridis")(np.linspace(0.85, 0.1, len(budgets)))
    offsets = np.linspace(-0.3, 0.3, len(budgets))
    for k, budget in enumerate(budgets):
        key = str(budget)
        y = [i + offsets[k] for i, r in enumerate(rows) if key in r["budgets"]]
        entries = [r["budgets"][key] for r in rows if key in r["budgets"]]
        means = np.array([e["mean"] for e in entries])
        low = np.array([e["ci"][0] if e["ci"] else e["mean"] for e in entries])
        high = np.array([e["ci"][1] if e["ci"] else e["mean"] for e in entries])
        ax.errorbar(
            means,
            y,
            xerr=[means - low, high - means],
            fmt=markers[k % len(markers)],
            color=shades[k],
            ms=3.5,
            elinewidth=1.4 if key == final else 0.7,
            capsize=0,
            label=f"{budget} episodes",
        )
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_yticks(
        range(len(rows)),
        [
            f"{r['condition']} {r['predator'].replace('predator_', 'p')} vs {r['baseline'].replace('always_', '')}"
            for r in rows
        ],
        fontsize=6.5,
    )
    for label, r in zip(ax.get_yticklabels(), rows, strict=True):
        e = r["budgets"].get(final, {})
        if min(e.get("p_greater_holm", 1.0), e.get("p_less_holm", 1.0)) <= 0.025:
            label.set_fontweight("bold")
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlabel("hierarchical minus baseline: return per episode (mean over seeds, 95 % t-interval)", fontsize=8)
    ax.legend(fontsize=7, loc="lower right", title="training budget", title_fontsize=7)
    seeds = max((e["n"] for r in rows for e in r["budgets"].values()), default=0)
    ax.set_title(
        f"Hierarchical minus baseline, paired by seed ({seeds} seeds)\n"
        f"bold: significant at {final} episodes after Holm's correction over {len(rows)} comparisons",
        fontsize=9,
    )
    ax.tick_params(axis="x", labelsize=7)
    ax.grid(axis="x", lw=0.3)
    fig.tight_layout()
    return _png(fig)


def counts_png(counts: dict[str, Any]) -> bytes:
    """The paper's strict count one seed at a time: a bar per count, the mean and its 95 %
    t-interval, and the paper's 16 (one seed)."""
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    values = np.array(counts["counts"])
    edges = [k - 0.5 for k in range(counts["panels"] + 2)]
    ax.hist(values, bins=edges, color=TRAINED_COLOR, rwidth=0.8, label=f"our seeds ({len(values)})")
    ax.axvline(counts["mean"], color="black", lw=1.2, label=f"mean {counts['mean']:.1f}")
    if counts["ci"]:
        ax.axvspan(*counts["ci"], color="black", alpha=0.12, lw=0, label="95 % t-interval of the mean")
    ax.axvline(counts["paper"], color="#c44e52", ls="--", lw=1.2, label=f"paper (one seed): {counts['paper']}")
    ax.set_xlim(-0.5, max(counts["panels"], counts["paper"]) + 0.5)  # the paper's count stays in view
    ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    ax.set_xlabel(f"panels where the hierarchical predator beats both baselines (of {counts['panels']})", fontsize=8)
    ax.set_ylabel("seeds")
    ax.legend(fontsize=7, loc="best")
    ax.set_title("The paper's strict count, counted on each seed alone", fontsize=10)
    fig.tight_layout()
    return _png(fig)


LAW_COLORS = {"none": "#8c8c8c", "pp": "#dd8452", "pn": "#55a868", "mixed": "#8172b3", "parallel": "#c44e52"}


def law_png(result: dict[str, Any], title: str) -> bytes:
    """law.png, top: a few segments over their episodes (the episode faint, the segment bold
    from its onset, each law's simulation dashed); bottom: per predator kind and phase, the
    share of segments each law is chosen for, and proportional navigation's N per segment
    (interior fits as dots, fits at the bound as triangles at it)."""
    examples: list[dict[str, Any]] = next(iter(result["examples"].values()), [])
    bounds = result.get("gain_bounds", {"N": [0.0, 15.0]})
    fig = plt.figure(figsize=(11.5, 7.6))
    grid = fig.add_gridspec(2, max(len(examples), 1) * 2, height_ratios=[1.15, 1.0])
    width = 2
    for k, example in enumerate(examples):
        ax = fig.add_subplot(grid[0, k * width : (k + 1) * width])
        episode_p, episode_t = np.array(example["episode_pursuer"]), np.array(example["episode_target"])
        pursuer, target, start = np.array(example["pursuer"]), np.array(example["target"]), example["start"]
        ax.plot(episode_t[:, 0], episode_t[:, 1], color="#4c72b0", lw=0.8, alpha=0.35)
        ax.plot(episode_p[:, 0], episode_p[:, 1], color="black", lw=0.8, alpha=0.35)
        ax.plot(target[start:, 0], target[start:, 1], color="#4c72b0", lw=1.8, label="prey")
        ax.plot(pursuer[start:, 0], pursuer[start:, 1], color="black", lw=2, label="predator (measured)")
        ax.plot(*pursuer[start], "o", color="black", ms=4)
        for law, path in example["simulated"].items():
            path = np.array(path)[start:]
            ax.plot(path[:, 0], path[:, 1], "--", color=LAW_COLORS[law], lw=1, label=f"{law} (simulated)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x (arena units)", fontsize=8)
        ax.set_ylabel("y (arena units)", fontsize=8)
        ax.set_title(
            f"episode {example['episode'] + 1}, {example['phase']} from step {example['onset']}: "
            f"chosen {example['chosen']}",
            fontsize=8,
        )
        ax.tick_params(labelsize=7)
        if k == 0:
            ax.legend(fontsize=6, loc="best")
    rows = [
        (kind, phase, fits[phase])
        for kind, predators in result["kinds"].items()
        for phase in ("chase", "stalk")
        for fits in [_pooled(predators, phase)]
        if fits[phase]["attacks"]
    ]
    half = max(len(examples), 1)
    share_ax = fig.add_subplot(grid[1, :half])
    gain_ax = fig.add_subplot(grid[1, half:])
    labels = [f"{kind.replace('_', ' ')}\n{phase} ({entry['attacks']})" for kind, phase, entry in rows]
    bottom = np.zeros(len(rows))
    for law, color in LAW_COLORS.items():
        shares = np.array([entry["share"][law] for _, _, entry in rows])
        share_ax.bar(range(len(rows)), shares, bottom=bottom, color=color, label=law, width=0.7)
        bottom += shares
    share_ax.set_xticks(range(len(rows)), labels, fontsize=7, rotation=20)
    share_ax.set_ylabel("share of segments: law chosen (BIC)", fontsize=8)
    share_ax.set_ylim(0, 1)
    share_ax.legend(fontsize=6, ncol=5, loc="upper center", bbox_to_anchor=(0.5, 1.13))
    share_ax.tick_params(axis="y", labelsize=7)
    high = bounds["N"][1]
    for x, (_, _, entry) in enumerate(rows):
        pn = entry["laws"]["pn"]
        values = np.array(pn["gains"]["N"])
        at_upper = np.array([c.get("N") == "upper" for c in pn["censored"]], dtype=bool)
        at_lower = np.array([c.get("N") == "lower" for c in pn["censored"]], dtype=bool)
        inner = ~(at_upper | at_lower)
        jitter = np.random.default_rng(x).uniform(-0.15, 0.15, len(values))
        gain_ax.scatter(x + jitter[inner], values[inner], s=7, alpha=0.6, color="#55a868")
        gain_ax.scatter(x + jitter[at_upper], np.full(at_upper.sum(), high), marker="^", s=12, color="#c44e52")
        gain_ax.scatter(x + jitter[at_lower], np.zeros(at_lower.sum()), marker="v", s=12, color="#8c8c8c")
        if inner.any():
            gain_ax.plot([x - 0.3, x + 0.3], [np.median(values[inner])] * 2, color="black", lw=2)
    gain_ax.set_xticks(range(len(rows)), labels, fontsize=7, rotation=20)
    gain_ax.set_ylabel(
        f"proportional navigation's N per segment\n(triangles: at the bound, >{high:g} or 0)", fontsize=8
    )
    gain_ax.set_ylim(-0.8, high + 1.2)
    gain_ax.tick_params(axis="y", labelsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _png(fig)


def _pooled(predators: dict[str, Any], phase: str) -> dict[str, Any]:
    """One kind's predators' fits of one phase pooled (shares recomputed over every segment)."""
    entries = [fits[phase] for fits in predators.values()]
    chosen = [c for e in entries for c in e["chosen"]]
    pn = {
        "gains": {"N": [v for e in entries for v in e["laws"]["pn"]["gains"]["N"]]},
        "censored": [c for e in entries for c in e["laws"]["pn"]["censored"]],
    }
    share = {law: chosen.count(law) / len(chosen) if chosen else 0.0 for law in LAW_COLORS}
    return {phase: {"attacks": len(chosen), "share": share, "laws": {"pn": pn}}}


def robust_png(result: dict[str, Any]) -> bytes:
    """robust.png: per perturbation (rows) and condition (columns), the margin over the better
    baseline against strength, one line per predator kind with its 95 % t-interval over seeds
    (the unperturbed margin at the left); below, each condition's cross-play matrices (seed of
    the predators × seed of the prey) as heat maps, when there are any."""
    summary, crossplay = result["summary"], result["crossplay"]
    conditions = list(summary)
    ladders = result["ladders"]
    kinds = sorted({k for c in summary.values() for k in c}, key=lambda k: (k != "hierarchical", k))
    alone = len(conditions) == 1  # one condition: its ladders side by side, four to a row
    columns = 4 if alone else len(conditions)
    ladder_rows = -(-len(ladders) // 4) if alone else len(ladders)
    rows = ladder_rows + (1 if crossplay else 0)
    heights = [1.0] * ladder_rows + ([1.3] if crossplay else [])
    fig = plt.figure(figsize=(max(3.3 * columns + 0.6, 9.0), 2.1 * sum(heights) + 0.6))
    grid = fig.add_gridspec(rows, columns, height_ratios=heights)
    for col, condition in enumerate(conditions):
        for k, (name, levels) in enumerate(ladders.items()):
            row, place = (k // 4, k % 4) if alone else (k, col)
            ax = fig.add_subplot(grid[row, place])
            for kind in kinds:
                entry = summary[condition].get(kind)
                if entry is None or name not in entry:
                    continue
                rungs = [{"value": 0, **entry["none"]}, *entry[name]]
                x = np.arange(len(rungs))
                y = np.array([r["margin"] for r in rungs])
                color = VARIANT_COLORS.get(kind, "grey")
                ax.plot(x, y, "o-", color=color, ms=3, lw=1.2, label=kind)
                if all(r["ci"] for r in rungs):
                    ax.fill_between(
                        x, [r["ci"][0] for r in rungs], [r["ci"][1] for r in rungs], color=color, alpha=0.18, lw=0
                    )
            ax.axhline(0.0, color="black", lw=0.6)
            neutral = "1" if name in ("damping", "predator-accel", "prey-accel") else "0"
            ax.set_xticks(range(len(levels) + 1), [neutral, *(f"{v:g}" for v in levels)], fontsize=7)
            ax.tick_params(axis="y", labelsize=7)
            ax.set_xlabel(name, fontsize=8)
            if place == 0:
                ax.set_ylabel("margin over the\nbetter baseline", fontsize=7)
            if row == 0 and (place == 0 or not alone):
                ax.set_title(condition, fontsize=9)
            if k == 0 and col == 0:
                ax.legend(fontsize=6, loc="best")
        if crossplay and condition in crossplay:
            cells = grid[ladder_rows, col].subgridspec(1, len(crossplay[condition]), wspace=0.9)
            for k, (kind, c) in enumerate(crossplay[condition].items()):
                ax = fig.add_subplot(cells[0, k])
                matrix = np.array(c["matrix"])
                bound = max(abs(matrix).max(), 1e-6)
                image = ax.imshow(matrix, cmap="RdBu", vmin=-bound, vmax=bound, aspect="auto")  # fills its cell
                seeds = c["seeds"]
                ax.set_xticks(range(len(seeds)), seeds, fontsize=6)
                ax.set_yticks(range(len(seeds)), seeds, fontsize=6)
                ax.set_xlabel("prey's seed", fontsize=7)
                ax.set_ylabel("predators' seed", fontsize=7)
                ax.set_title(f"{kind}: gap {c['gap']['mean']:+.2f}", fontsize=7)
                bar = fig.colorbar(image, ax=ax, fraction=0.046, pad=0.04)
                bar.ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
                bar.ax.tick_params(labelsize=6)
    seeds = max((len(e["none"]["values"]) for c in summary.values() for e in c.values()), default=0)
    fig.suptitle(
        f"Margin over the better baseline under perturbations ({interval_words(seeds)}; "
        f"{result['episodes']} episodes per variant)"
        + (
            "\nbottom: cross-play margins, diagonal = self-play; gap = self-play minus held-out margin"
            if crossplay
            else ""
        ),
        fontsize=9,
    )
    title = 0.65 if crossplay else 0.35  # inches kept for the title: two lines with cross-play, else one
    fig.tight_layout(rect=(0, 0, 1, 1 - title / fig.get_figheight()))
    return _png(fig)


def pool_png(summary: dict[str, Any], measure: str = "pool margin") -> bytes:
    """Learning against budget against one pool of opponents: per condition, each kind's pool
    margin (or the ``measure`` the curves hold: "pool return" for the rule study) (mean over
    predators) at every kept budget, mean over runs with its t-interval. Optional in ``summary``:
    ``runs_label`` (the runs a kind, said in the subtitle), ``opponents`` (whom they played) and
    ``titles`` (a panel's title by condition, else the condition)."""
    curves = summary["curves"]
    conditions = list(curves)
    columns = min(5, max(len(conditions), 1))  # no empty columns beside a study of few conditions
    rows = -(-len(conditions) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.0 * columns, 2.6 * rows + 1.0), squeeze=False)
    colors = {"hierarchical": VARIANT_COLORS["hierarchical"], "flat": VARIANT_COLORS["flat"], "residual": "#dd8452"}
    for i, ax in enumerate(axes.flat):
        if i >= len(conditions):
            ax.set_visible(False)
            continue
        for kind, curve in curves[conditions[i]].items():
            x, mean = np.array(curve["episodes"]), np.array(curve["mean"])
            ax.plot(x, mean, "o-", ms=3, color=colors[kind], label=kind)
            if all(ci is not None for ci in curve["ci"]):
                low, high = np.array(curve["ci"]).T
                ax.fill_between(x, low, high, color=colors[kind], alpha=0.2, lw=0)
        ax.axhline(0.0, color="black", lw=0.6)
        ax.set_xscale("log")
        close = np.r_[np.diff(np.log(x)) < 0.35, False]  # a budget too near the next one goes unlabelled
        ax.set_xticks(x, ["" if c else f"{e / 1000:g}k" for e, c in zip(x, close, strict=True)], fontsize=7)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.tick_params(axis="y", labelsize=7)
        ax.set_title(summary.get("titles", {}).get(conditions[i], conditions[i]), fontsize=9)
        if i % columns == 0:
            ax.set_ylabel(measure, fontsize=8)
    axes.flat[0].legend(fontsize=7, loc="best")
    seeds = summary.get("runs_label") or ", ".join(f"{len(v)} {k}" for k, v in summary["seeds"].items())
    budgets = [b["episodes"] for b in summary["budgets"]]
    lines = [
        ("Margin over the better fixed mode" if measure == "pool margin" else measure.capitalize())
        + f" against {summary.get('opponents', 'one pool of opponents')}, by training episodes: mean over the "
        "condition's predators",
        f"mean over runs ({seeds}), band: 95 % t-interval; "
        f"tick marks at every kept budget ({', '.join(f'{e / 1000:g}k' for e in budgets)}), labelled where they fit",
    ]
    width = int(12 * 3.0 * columns)  # characters a line of the title holds at its size
    fig.suptitle("\n".join(textwrap.fill(line, width) for line in lines), fontsize=10)
    fig.tight_layout()
    return _png(fig)


#: A distance bin of a run with fewer states than this is left out of the corrections figure.
FEWEST_STATES = 10


def correction_shares(by_predator: dict[str, Any], mode: str) -> tuple[np.ndarray, np.ndarray]:
    """A residual run's corrected states and all its states in ``mode``, per distance bin, over its
    predators together (``analyze``'s ``correction_by_distance`` of each)."""
    corrected = states = None
    for entry in by_predator.values():
        n = np.array(entry[mode]["states"], dtype=float)
        share = np.array([0.0 if s is None else s for s in entry[mode]["corrected"]])
        corrected = np.rint(share * n) if corrected is None else corrected + np.rint(share * n)
        states = n if states is None else states + n
    assert corrected is not None and states is not None, "a run without predators"
    return corrected, states


def corrections_png(rows: list[dict[str, Any]], differs: float) -> bytes:
    """Where the residual runs correct the rule: per setting (columns) and mode (rows), each run's
    share of states whose greedy correction is not the rule's direction, by distance to the prey
    (its predators' states together; bins of fewer than :data:`FEWEST_STATES` states left out).
    A thin line per run, red where its pool margin differs from the hierarchical run of its seed by
    more than ``differs``, grey where it does not; thick: each group's mean over runs."""
    settings = list(dict.fromkeys(r["setting"] for r in rows))
    modes = ("stalk", "chase")
    width = max(3.0 * len(settings), 8.0)  # room for the title with one setting
    fig, axes = plt.subplots(2, len(settings), figsize=(width, 6.0), squeeze=False, sharey=True)
    groups = ((True, "#c44e52", "differs"), (False, "#8c8c8c", "does not differ"))
    for column, setting in enumerate(settings):
        for line, mode in enumerate(modes):
            ax = axes[line, column]
            for different, color, label in groups:
                shares = []
                for r in rows:
                    if r["setting"] != setting or bool(r["differs"]) != different:
                        continue
                    bins = np.array(next(iter(r["by_distance"].values()))["bins"])
                    centres = (bins[:-1] + bins[1:]) / 2
                    corrected, states = correction_shares(r["by_distance"], mode)
                    share = np.where(states >= FEWEST_STATES, corrected / np.maximum(states, 1), np.nan)
                    shares.append(share)
                    ax.plot(centres, share, color=color, lw=0.6, alpha=0.5)
                if shares:
                    with np.errstate(all="ignore"):
                        counted = np.sum(~np.isnan(shares), axis=0)
                        mean = np.where(counted > 0, np.nansum(shares, axis=0) / np.maximum(counted, 1), np.nan)
                    ax.plot(centres, mean, color=color, lw=2.2, label=f"{label} ({len(shares)} runs)")
            ax.set_ylim(-0.02, 1.02)
            ax.tick_params(labelsize=7)
            ax.set_title(f"{setting}: {mode}", fontsize=9)
            if column == 0:
                ax.set_ylabel("share of states corrected", fontsize=8)
            if line == 1:
                ax.set_xlabel("distance to the prey", fontsize=8)
            if line == 0:
                ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(
        "Where the residual predator corrects the rule (greedy, at the end of training, against its own prey)\n"
        "thin: one run (its predators together); thick: mean over the runs of a group\n"
        f"red: its pool margin differs from the hierarchical run of its seed by more than {differs:g}",
        fontsize=10,
    )
    fig.tight_layout()
    return _png(fig)
