"""The rule study's report (REPRODUCTION.md, "Protocol of the rule study"): from the judged runs'
compact results (``results/rule-study/runs/``), the primary verdicts and every secondary measure,
as the protocol fixed them. ``pursuit-bench report results/rule-study`` writes them.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.study import pool, rule_study, statistics
from pursuit_bench.study.report import p_text, span_text

KINDS = rule_study.KINDS


def panels(runs: list[dict[str, Any]]) -> list[tuple[str, str]]:
    """Every (condition, predator) the runs hold, in the paper's order."""
    seen = {
        (r["condition"], p): None
        for r in runs
        for p in r["pool"][rule_study.last_budget(r)][rule_study.FLEEING]["panels"]
    }
    return sorted(seen, key=lambda k: (list(CONDITIONS).index(k[0]), k[1]))


def budgets(runs: list[dict[str, Any]]) -> list[str]:
    """The budgets every run was evaluated at, ascending."""
    common = set.intersection(*(set(r["pool"]) for r in runs))
    return sorted(common, key=int)


def _runs_of(runs: list[dict[str, Any]], condition: str, kind: str) -> list[dict[str, Any]]:
    return sorted((r for r in runs if (r["condition"], r["kind"]) == (condition, kind)), key=lambda r: r["seed"])


def rows_of(runs: list[dict[str, Any]], measure: Callable[[dict[str, Any], str], float]) -> list[dict[str, Any]]:
    """One row per panel: each kind's per-run values of ``measure(run, predator)``, by seed."""
    return [
        {"condition": c, "predator": p, **{k: [measure(r, p) for r in _runs_of(runs, c, k)] for k in KINDS}}
        for c, p in panels(runs)
    ]


def head_start(run: dict[str, Any], predator: str, keys: list[str]) -> float:
    """A run's pool return averaged over the budgets on a log-episode axis (trapezoids over the span)."""
    x = np.log([int(b) for b in keys])
    y = np.array([rule_study.pooled(run["pool"][b], predator)["return"] for b in keys])
    return float(np.sum((y[1:] + y[:-1]) / 2 * np.diff(x)) / (x[-1] - x[0]))


def reliability(runs: list[dict[str, Any]], margin: float = rule_study.FAILURE_MARGIN) -> list[dict[str, Any]]:
    """Per panel and kind: failed runs (pool margin at the last budget below ``margin``), their share
    with Wilson's interval; the difference of the shares, Boschloo's test, Holm over the panels."""
    rows = []
    for condition, predator in panels(runs):
        row: dict[str, Any] = {"condition": condition, "predator": predator}
        for kind in KINDS:
            mine = _runs_of(runs, condition, kind)
            count = sum(rule_study.failed(r, predator, margin) for r in mine)
            row[kind] = {
                "failed": count,
                "runs": len(mine),
                "share": count / len(mine),
                "ci": statistics.wilson_interval(count, len(mine)),
            }
        h, f = row["hierarchical"], row["flat"]
        row["difference"] = statistics.share_difference(h["failed"], h["runs"], f["failed"], f["runs"])
        rows.append(row)
    for row, adjusted in zip(rows, statistics.holm([r["difference"]["p"] for r in rows]), strict=True):
        row["difference"]["p_holm"] = float(adjusted)
    return rows


def improvement(rows: list[dict[str, Any]], seed: int = 0, resamples: int = statistics.RESAMPLES) -> dict[str, Any]:
    """P(hierarchical run > flat run) per panel and averaged over panels, with 95 % percentile
    intervals from resampling runs within a condition, jointly for its panels (a run's values in
    the condition's panels stay together)."""
    rng = np.random.default_rng(seed)
    per_panel = np.zeros((resamples, len(rows)))
    for condition in dict.fromkeys(r["condition"] for r in rows):
        index = [i for i, r in enumerate(rows) if r["condition"] == condition]
        h = np.array([rows[i]["hierarchical"] for i in index]).T  # (runs, panels)
        f = np.array([rows[i]["flat"] for i in index]).T
        rh = h[rng.integers(0, len(h), (resamples, len(h)))]  # (resamples, runs, panels)
        rf = f[rng.integers(0, len(f), (resamples, len(f)))]
        for j, i in enumerate(index):
            per_panel[:, i] = statistics._pairs_above(rh[:, :, j], rf[:, :, j])
    values = [statistics.probability_of_improvement([np.array(r["hierarchical"])], [np.array(r["flat"])]) for r in rows]

    def interval(draws: np.ndarray) -> list[float]:
        return [float(q) for q in np.quantile(draws, [0.025, 0.975])]

    return {
        "value": float(np.mean(values)),
        "ci": interval(per_panel.mean(axis=1)),
        "panels": [{"value": v, "ci": interval(per_panel[:, i])} for i, v in enumerate(values)],
        "resamples": resamples,
    }


def leave_one_out(runs: list[dict[str, Any]], final: str, margin: float) -> dict[str, Any]:
    """Per panel, the primary difference with each member of the population left out: its range;
    and, each left-out member's 22 panels judged as one family, the panels whose verdict changes."""
    members = list(runs[0]["pool"][final])
    base = rows_of(runs, lambda r, p: rule_study.pooled(r["pool"][final], p)["return"])
    pool.compare(base, margin)
    out = [{"condition": r["condition"], "predator": r["predator"], "differences": {}, "verdicts": {}} for r in base]
    for member in members:

        def without(r: dict[str, Any], p: str, m: str = member) -> float:
            return rule_study.pooled(r["pool"][final], p, leave_out=m)["return"]

        rows = rows_of(runs, without)
        pool.compare(rows, margin)
        for entry, row in zip(out, rows, strict=True):
            entry["differences"][member] = row["difference"]["mean"]
            entry["verdicts"][member] = row["verdict"]
    for entry, row in zip(out, base, strict=True):
        values = list(entry["differences"].values())
        entry["range"] = [min(values), max(values)]
        entry["verdict"] = row["verdict"]
        entry["changes"] = sorted({v for v in entry["verdicts"].values() if v != row["verdict"]})
    return {"members": members, "panels": out}


def curves(runs: list[dict[str, Any]], keys: list[str]) -> dict[str, dict[str, Any]]:
    """Per condition and kind: the pool return (mean over the condition's predators) at each
    budget, mean over runs with its t-interval: the pool-return-by-budget figure."""
    out: dict[str, dict[str, Any]] = {}
    for condition in dict.fromkeys(c for c, _ in panels(runs)):
        for kind in KINDS:
            mine = _runs_of(runs, condition, kind)
            predators = list(mine[0]["pool"][keys[-1]][rule_study.FLEEING]["panels"])
            matrix = np.array(
                [
                    [np.mean([rule_study.pooled(r["pool"][b], p)["return"] for p in predators]) for b in keys]
                    for r in mine
                ]
            )
            out.setdefault(condition, {})[kind] = {
                "episodes": [int(b) for b in keys],
                "mean": matrix.mean(axis=0).tolist(),
                "ci": [statistics.t_interval(matrix[:, i]) for i in range(len(keys))],
            }
    return out


def summarise(runs: list[dict[str, Any]], margin: float = statistics.EQUIVALENCE_MARGIN) -> dict[str, Any]:
    """Everything the study's report says, at full precision: the primary verdicts (pool return at
    the last budget), and each secondary measure labelled as such."""
    if not runs:
        raise ValueError("no judged runs: expected results/rule-study/runs/*.json.gz")
    protocols = {r.get("protocol") for r in runs}
    if len(protocols) != 1:
        raise ValueError(f"the runs were evaluated by different protocols {sorted(map(str, protocols))}: not mixed")
    builds = sorted({r["build"] for r in runs})
    keys = budgets(runs)
    final = keys[-1]

    def at(budget: str, key: str) -> Callable[[dict[str, Any], str], float]:
        return lambda r, p: rule_study.pooled(r["pool"][budget], p)[key]

    primary = rows_of(runs, at(final, "return"))
    counts = pool.compare(primary, margin)
    secondary_margin = rows_of(runs, at(final, "margin"))
    margin_counts = pool.compare(secondary_margin, margin)
    started = rows_of(runs, lambda r, p: head_start(r, p, keys))
    head_counts = pool.compare(started, margin)
    by_budget = []
    for budget in keys[:-1]:
        rows = rows_of(runs, at(budget, "return"))
        by_budget.append({"episodes": int(budget), "counts": pool.compare(rows, margin), "panels": rows})
    return {
        "protocol": runs[0].get("protocol"),
        "builds": builds,
        "equivalence_margin": margin,
        "failure_margin": rule_study.FAILURE_MARGIN,
        "budgets": [int(b) for b in keys],
        "runs": {k: {c: len(_runs_of(runs, c, k)) for c in dict.fromkeys(r["condition"] for r in runs)} for k in KINDS},
        "primary": {"measure": f"pool return at {final} episodes", "counts": counts, "panels": primary},
        "secondary": {
            "margin": {"counts": margin_counts, "panels": secondary_margin},
            "reliability": reliability(runs),
            "reliability_below_zero": reliability(runs, 0.0),
            "head_start": {"counts": head_counts, "panels": started},
            "budgets": by_budget,
            "improvement": improvement(primary),
            "leave_one_out": leave_one_out(runs, final, margin),
        },
        "curves": curves(runs, keys),
    }


# --- tables -------------------------------------------------------------------------------------


def reliability_markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| condition | predator | hierarchical failed [95 % Wilson] | flat failed [95 % Wilson] "
        "| difference | p (Boschloo, Holm) |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        h, f = r["hierarchical"], r["flat"]
        lines.append(
            f"| {r['condition']} | {r['predator']} | {h['failed']}/{h['runs']}{span_text(h['ci'])} "
            f"| {f['failed']}/{f['runs']}{span_text(f['ci'])} | {r['difference']['difference']:+.2f} "
            f"| {p_text(r['difference']['p_holm'])} |"
        )
    return "\n".join(lines) + "\n"


def leave_one_out_markdown(entry: dict[str, Any]) -> str:
    lines = [
        "| condition | predator | verdict | hierarchical − flat, one member left out: range | verdicts it changes to |"
    ]
    lines.append("|---|---|---|---:|---|")
    for r in entry["panels"]:
        low, high = r["range"]
        lines.append(
            f"| {r['condition']} | {r['predator']} | {r['verdict']} | {low:+.3f} to {high:+.3f} "
            f"| {', '.join(r['changes']) or '—'} |"
        )
    return "\n".join(lines) + "\n"


def improvement_markdown(poi: dict[str, Any], rows: list[dict[str, Any]]) -> str:
    lines = ["| panel | P(hierarchical run > flat run) [95 %, runs resampled within condition] |", "|---|---:|"]
    lines.append(f"| all panels | {poi['value']:.2f}{span_text(poi['ci'], 2)} |")
    for row, p in zip(rows, poi["panels"], strict=True):
        lines.append(f"| {row['condition']} {row['predator']} | {p['value']:.2f}{span_text(p['ci'], 2)} |")
    return "\n".join(lines) + "\n"


def counts_line(counts: dict[str, int]) -> str:
    return ", ".join(f"{counts[v]} {v}" for v in pool.VERDICTS)


def markdown(summary: dict[str, Any]) -> str:
    """rule-study.md: the primary verdicts first, then each secondary measure, labelled."""
    final = summary["budgets"][-1]
    s = summary["secondary"]
    budget_lines = [f"- {b['episodes']} episodes: {counts_line(b['counts'])}" for b in s["budgets"]]
    return "\n".join(
        [
            f"## Primary: the pool return at {final} episodes, hierarchical − flat",
            "",
            f"{counts_line(summary['primary']['counts'])} (Welch, Holm over "
            f"{len(summary['primary']['panels'])} panels, "
            f"equivalence within ±{summary['equivalence_margin']}). Protocol {summary['protocol']}; builds "
            f"{', '.join(b[:10] for b in summary['builds'])}.",
            "",
            pool.panels_markdown(summary["primary"]["panels"], "pool return"),
            f"## Secondary: the pool margin at {final} episodes",
            "",
            counts_line(s["margin"]["counts"]),
            "",
            pool.panels_markdown(s["margin"]["panels"], "pool margin"),
            f"## Secondary: reliability (a run fails with a pool margin below {summary['failure_margin']})",
            "",
            reliability_markdown(s["reliability"]),
            "Sensitivity (secondary): failures counted at a pool margin below 0.",
            "",
            reliability_markdown(s["reliability_below_zero"]),
            "## Secondary: the head start (pool return averaged over the budgets, log-episode axis)",
            "",
            counts_line(s["head_start"]["counts"]),
            "",
            pool.panels_markdown(s["head_start"]["panels"], "head start"),
            "## Secondary: the primary measure at every budget",
            "",
            *budget_lines,
            "",
            "## Secondary: probability of improvement on the primary measure",
            "",
            improvement_markdown(s["improvement"], summary["primary"]["panels"]),
            "## Secondary: leave one member of the population out",
            "",
            leave_one_out_markdown(s["leave_one_out"]),
        ]
    )


def write_report(where: Path, out: Path) -> dict[str, Any]:
    """From the study's folder (``runs/*.json.gz``): rule-study-report.json, rule-study.md and
    rule-study.png in ``out``; returns the summary."""
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
    from pursuit_bench.study.plots import pool_png

    summary = summarise(rule_study.read_runs(where / "runs"))
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "rule-study-report.json", json.dumps(summary, indent=2) + "\n")
    atomic_write_text(out / "rule-study.md", markdown(summary))
    figure = {
        "curves": summary["curves"],
        "seeds": {k: list(range(max(v.values()))) for k, v in summary["runs"].items()},
        "budgets": [{"episodes": b} for b in summary["budgets"]],
    }
    atomic_write_bytes(out / "rule-study.png", pool_png(figure, measure="pool return"))
    return summary
