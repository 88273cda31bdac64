"""The paper's Fig. 2 over seeds, with confidence intervals: what ``pursuit-bench report``
computes from a sweep's run folders (``eval.json`` and ``metrics.jsonl``, nothing else).

A *panel* is one predator of one condition (22 in the paper). Its *variants* are the trained
predator of each kind the sweep trained (``hierarchical``, ``flat``) and the two baselines,
always-chase and always-stalk, evaluated in place of the trained hierarchical predator (or of
the first kind trained) with the other agents fixed. Over seeds, each variant has a mean and a
95 % interval; the hierarchical predator has, against each baseline, the probability of
improvement: the chance that on a seed drawn at random it scores higher (ties count half),
with its interval. Intervals are percentile bootstraps over seeds from
``scipy.stats.bootstrap`` (seeded, 2000 resamples): a well-tested library rather than our own
resampling; percentile rather than BCa because BCa is undefined with the two or three seeds a
small sweep has.
"""

from __future__ import annotations

import itertools
import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from pursuit_bench.conditions import CONDITIONS

BASELINES = ("always_chase", "always_stalk")
CONFIDENCE = 0.95
RESAMPLES = 2000
#: Learning curves are means over this many blocks of episodes.
CURVE_BLOCKS = 40


@dataclass
class RunResult:
    """One run folder of a sweep: what it is and what it measured."""

    name: str
    folder: Path
    condition: str
    kind: str
    seed: int
    evaluation: dict[str, Any]


def collect(sweep: Path) -> list[RunResult]:
    """Every evaluated run folder under ``sweep/runs``; ValueError if there is none."""
    results = []
    for eval_json in sorted((sweep / "runs").glob("*/eval.json")):
        folder = eval_json.parent
        config = json.loads((folder / "config.json").read_text())["train"]
        evaluation = json.loads(eval_json.read_text())
        results.append(
            RunResult(folder.name, folder, config["condition"], config["predator"], int(config["seed"]), evaluation)
        )
    if not results:
        raise ValueError(f"{sweep}: no evaluated run folder (runs/*/eval.json); run the sweep first")
    return results


def interval(values: np.ndarray) -> list[float] | None:
    """95 % percentile-bootstrap interval of the mean over seeds; None below two seeds."""
    if len(values) < 2:
        return None
    if np.all(values == values[0]):
        return [float(values[0]), float(values[0])]
    result = stats.bootstrap(
        (values,),
        np.mean,
        confidence_level=CONFIDENCE,
        n_resamples=RESAMPLES,
        method="percentile",
        rng=np.random.default_rng(0),
    )
    return [float(result.confidence_interval.low), float(result.confidence_interval.high)]


def improvement(ours: np.ndarray, theirs: np.ndarray) -> dict[str, Any]:
    """P(ours > theirs) on a seed drawn at random (paired by seed, ties half), with a
    percentile-bootstrap interval over seeds."""

    def probability(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
        return np.mean((a > b) + 0.5 * (a == b), axis=axis)

    value = float(probability(ours, theirs))
    if len(ours) < 2:
        return {"value": value, "ci": None}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a degenerate resample distribution is reported as is
        result = stats.bootstrap(
            (ours, theirs),
            probability,
            paired=True,
            vectorized=True,
            confidence_level=CONFIDENCE,
            n_resamples=RESAMPLES,
            method="percentile",
            rng=np.random.default_rng(0),
        )
    low, high = result.confidence_interval
    ci = [float(low), float(high)] if np.isfinite(low) and np.isfinite(high) else [value, value]
    return {"value": value, "ci": ci}


def panel_table(results: list[RunResult]) -> list[dict[str, Any]]:
    """One entry per panel, in the conditions' order: every variant's per-seed values (and the
    runs they come from), mean and interval; the best variant; the hierarchical predator's
    probability of improvement over each baseline."""
    kinds = sorted({r.kind for r in results}, key=lambda k: (k != "hierarchical", k))
    reference = kinds[0]  # whose evaluations hold the baselines
    table = []
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        for p, predator in enumerate(CONDITIONS[condition].agent_names[:-1]):
            variants: dict[str, dict[str, Any]] = {}
            for kind in kinds:
                runs = sorted((r for r in results if r.condition == condition and r.kind == kind), key=lambda r: r.seed)
                if not runs:
                    continue
                keys = [("trained", kind)] + ([(b, b) for b in BASELINES] if kind == reference else [])
                for key, label in keys:
                    values = np.array([r.evaluation["panels"][p][key] for r in runs])
                    variants[label] = {
                        "mean": float(values.mean()),
                        "ci": interval(values),
                        "seeds": [r.seed for r in runs],
                        "values": values.tolist(),
                        "runs": [str(r.folder) for r in runs],
                    }
            order = [k for k in kinds if k in variants] + [b for b in BASELINES if b in variants]
            variants = {k: variants[k] for k in order}  # trained kinds first, then the baselines
            entry: dict[str, Any] = {"condition": condition, "predator": predator, "variants": variants}
            entry["best"] = max(variants, key=lambda v: variants[v]["mean"])
            if "hierarchical" in variants and all(b in variants for b in BASELINES):
                ours = np.array(variants["hierarchical"]["values"])
                entry["improvement"] = {b: improvement(ours, np.array(variants[b]["values"])) for b in BASELINES}
            table.append(entry)
    return table


def summary(table: list[dict[str, Any]]) -> dict[str, Any]:
    """The paper's claim, counted: panels where the hierarchical predator has the highest mean
    of it and the two baselines; where its interval lies above both baselines' intervals; its
    mean ratio to the best where it is not the best (over panels where both means are positive)."""
    judged = [t for t in table if "hierarchical" in t["variants"] and all(b in t["variants"] for b in BASELINES)]
    best, above, ratios = 0, 0, []
    for entry in judged:
        v = entry["variants"]
        contenders = {k: v[k]["mean"] for k in ("hierarchical", *BASELINES)}
        top = max(contenders, key=lambda k: contenders[k])
        if top == "hierarchical":
            best += 1
        elif contenders[top] > 0 and contenders["hierarchical"] > 0:  # a ratio of returns means little otherwise
            ratios.append(contenders["hierarchical"] / contenders[top])
        ours = v["hierarchical"]["ci"]
        if ours is not None and all(v[b]["ci"] is not None and ours[0] > v[b]["ci"][1] for b in BASELINES):
            above += 1
    return {
        "panels": len(judged),
        "hierarchical_best": best,
        "hierarchical_interval_above_both": above,
        "mean_ratio_to_best_where_not_best": float(np.mean(ratios)) if ratios else None,
        "ratio_panels": len(ratios),
        "paper": {"hierarchical_best": "16 of 22", "mean_ratio_to_best_where_not_best": 0.96},
    }


def curves(results: list[RunResult], blocks: int = CURVE_BLOCKS) -> dict[str, dict[str, Any]]:
    """Learning curves per condition and kind: episode blocks, and for every agent's return and
    the capture rate the mean over seeds of each block's mean, with a 95 % interval."""
    out: dict[str, dict[str, Any]] = {}
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        names = CONDITIONS[condition].agent_names
        for kind in sorted({r.kind for r in results if r.condition == condition}):
            runs = [r for r in results if r.condition == condition and r.kind == kind]
            rows = [[json.loads(line) for line in (r.folder / "metrics.jsonl").read_text().splitlines()] for r in runs]
            length = min(len(r) for r in rows)
            if length < blocks:
                continue
            edges = np.linspace(0, length, blocks + 1).astype(int)
            series: dict[str, Any] = {}
            columns = [(f"return/{a}", f"return/{a}") for a in names] + [("captured", "capture_rate")]
            for column, label in columns:
                per_run = np.array(
                    [
                        [np.mean([float(row[column]) for row in run[lo:hi]]) for lo, hi in itertools.pairwise(edges)]
                        for run in rows
                    ]
                )  # (seeds, blocks)
                entry: dict[str, Any] = {"mean": per_run.mean(axis=0).tolist(), "ci": None}
                if len(runs) > 1:
                    result = stats.bootstrap(
                        (per_run,),
                        np.mean,
                        axis=0,
                        confidence_level=CONFIDENCE,
                        n_resamples=RESAMPLES,
                        method="percentile",
                        rng=np.random.default_rng(0),
                    )
                    low, high = result.confidence_interval
                    entry["ci"] = [np.nan_to_num(low, nan=0).tolist(), np.nan_to_num(high, nan=0).tolist()]
                series[label] = entry
            out.setdefault(condition, {})[kind] = {
                "episodes": ((edges[:-1] + edges[1:]) / 2).tolist(),
                "seeds": len(runs),
                "series": series,
            }
    return out


def markdown(table: list[dict[str, Any]], totals: dict[str, Any], sweep: Path) -> str:
    """report.md: the claim counted, then one row per panel."""

    def cell(v: dict[str, Any] | None) -> str:
        if v is None:
            return "–"
        ci = v["ci"]
        return f"{v['mean']:+.3f}" + (f" [{ci[0]:+.2f}, {ci[1]:+.2f}]" if ci else "")

    kinds = sorted({k for t in table for k in t["variants"]} - set(BASELINES), key=lambda k: (k != "hierarchical", k))
    ratio = totals["mean_ratio_to_best_where_not_best"]
    lines = [
        f"# Fig. 2 over seeds: {sweep}",
        "",
        f"- Panels judged: {totals['panels']}.",
        f"- Hierarchical best (highest mean of it and the two baselines): {totals['hierarchical_best']} "
        "(paper: 16 of 22).",
        f"- Hierarchical interval above both baselines' intervals: {totals['hierarchical_interval_above_both']}.",
        "- Mean ratio to the best where it is not the best: "
        + (f"{ratio:.0%} over {totals['ratio_panels']} panels" if ratio is not None else "–")
        + " (paper: 96 %).",
        "",
        "Means over seeds with 95 % percentile-bootstrap intervals (scipy.stats.bootstrap); P(>) is the "
        "probability that the hierarchical predator beats the baseline on a seed drawn at random.",
        "",
        "| condition | predator | "
        + " | ".join(kinds)
        + " | always chase | always stalk | best | P(> chase) | P(> stalk) |",
        "|---|---|" + "---:|" * (len(kinds) + 2) + "---|---:|---:|",
    ]
    for t in table:
        v = t["variants"]
        poi = t.get("improvement", {})
        pcells = [f"{poi[b]['value']:.2f}" if b in poi else "–" for b in BASELINES]
        row = [t["condition"], t["predator"], *[cell(v.get(k)) for k in kinds]]
        row += [cell(v.get(b)) for b in BASELINES] + [t["best"].replace("_", " "), *pcells]
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "Each value's runs are listed in report.json (`variants.<name>.runs`)."]
    return "\n".join(lines) + "\n"
