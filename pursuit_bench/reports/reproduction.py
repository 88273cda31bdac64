"""The paper's claim judged over seeds: what ``pursuit-bench report`` computes from a sweep's
run folders (``eval.json`` and ``metrics.jsonl``, nothing else) or its compact results.

A *panel* is one predator of one condition (22 in the paper). Its *variants* are the trained
predator of each kind the sweep trained (``hierarchical``, ``flat``) and the two baselines,
always-chase and always-stalk, evaluated in place of the trained hierarchical predator with the
other agents fixed, on the same episodes. Each panel's difference from each baseline is paired
by seed; Holm's correction over the family of comparisons gives every panel a verdict (better,
not resolved, worse); the paper's strict count is made seed by seed; the probability of
improvement aggregates over panels; unresolved comparisons get a power figure; the margins'
slope over the last 30 % of training says whether they still move. Every statistic comes from
:mod:`pursuit_bench.stats` (docs/statistics.md); this module arranges the data and writes
the tables and figures.
"""

from __future__ import annotations

import copy
import dataclasses
import gzip
import itertools
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.stats.text import p_text, span_text

BASELINES = ("always_chase", "always_stalk")


@dataclass
class RunResult:
    """One run of a sweep: what it is and what it measured, from its folder or from the
    sweep's compact results (:func:`export`)."""

    name: str
    condition: str
    kind: str
    seed: int
    evaluation: dict[str, Any]
    """The final evaluation (``eval.json``)."""
    milestones: dict[int, dict[str, Any]]
    """Evaluations of kept checkpoints (``eval-epN.json``) by episode count."""
    curve: dict[str, list[float]] | None
    """The learning curve in :data:`CURVE_POINTS` blocks of episodes: ``episodes`` (block
    ends) and the block means of every agent's return, ``captured`` and ``length``."""
    config: dict[str, Any]
    """The run's training configuration."""


#: Blocks a learning curve is kept in (1 % of training each).
CURVE_POINTS = 100
RESULTS_FORMAT = "pursuit-bench-results-1"


def block_curve(rows: list[dict[str, Any]], points: int = CURVE_POINTS) -> dict[str, list[float]] | None:
    """A metrics file's rows in ``points`` equal blocks of episodes (one episode each for a run
    shorter than that): their means; None for a run with no episode."""
    if not rows:
        return None
    points = min(points, len(rows))
    edges = np.linspace(0, len(rows), points + 1).astype(int)
    columns = [c for c in rows[0] if c.startswith("return/")] + ["captured", "length"]
    curve = {"episodes": edges[1:].tolist()}
    for column in columns:
        values = np.array([float(row[column]) for row in rows])
        curve[column] = [float(values[lo:hi].mean()) for lo, hi in itertools.pairwise(edges)]
    return curve


def _from_folder(folder: Path) -> RunResult:
    config = json.loads((folder / "config.json").read_text())["train"]
    milestones = {}
    for path in folder.glob("eval-ep*.json"):
        milestones[int(path.stem.removeprefix("eval-ep"))] = json.loads(path.read_text())
    metrics = folder / "metrics.jsonl"
    rows = [json.loads(line) for line in metrics.read_text().splitlines()] if metrics.exists() else []
    return RunResult(
        folder.name,
        config["condition"],
        config["predator"],
        int(config["seed"]),
        json.loads((folder / "eval.json").read_text()),
        dict(sorted(milestones.items())),
        block_curve(rows),
        config,
    )


def collect(where: Path) -> list[RunResult]:
    """Every evaluated run of a sweep folder (``runs/*/eval.json``) or of a compact results
    folder (:func:`export`); ValueError if there is none."""
    if not where.is_dir():
        raise ValueError(f"{where}: no such folder" if not where.exists() else f"{where}: a file, not a folder")
    if (where / "results.json").is_file():
        return load_results(where)
    results = [_from_folder(eval_json.parent) for eval_json in sorted((where / "runs").glob("*/eval.json"))]
    if not results:
        raise NoRuns(f"{where}: no evaluated run folder (runs/*/eval.json) and no results.json; run the sweep first")
    return results


class NoRuns(ValueError):
    """A folder with neither a sweep's evaluated runs nor compact results: not one this reads."""


def export(results: list[RunResult], out: Path, about: dict[str, Any]) -> int:
    """Write a sweep's results compactly into ``out``: ``results.json`` (``about``: the plan, the
    command) and ``runs/<name>.json.gz`` per run (its evaluations with every episode's return,
    prey checks, its learning curve in blocks, its configuration), enough for :func:`collect`
    to make every table and figure again without the run folders. Returns the bytes written."""
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    total = 0
    for r in results:
        payload = {
            "name": r.name,
            "condition": r.condition,
            "kind": r.kind,
            "seed": r.seed,
            "config": r.config,
            "evaluation": r.evaluation,
            "milestones": {str(n): e for n, e in r.milestones.items()},
            "curve": r.curve,
        }
        data = gzip.compress(json.dumps(payload, separators=(",", ":")).encode(), mtime=0)
        atomic_write_bytes(out / "runs" / f"{r.name}.json.gz", data)
        total += len(data)
    header = {"format": RESULTS_FORMAT, **about, "runs": sorted(r.name for r in results)}
    text = json.dumps(header, indent=2) + "\n"
    atomic_write_text(out / "results.json", text)
    return total + len(text)


def load_results(where: Path) -> list[RunResult]:
    """The runs of a results folder written by :func:`export`."""
    header = json.loads((where / "results.json").read_text())
    if header.get("format") != RESULTS_FORMAT:
        raise ValueError(f"{where / 'results.json'}: not pursuit-bench results (format {RESULTS_FORMAT!r} expected)")
    results = []
    for name in header["runs"]:
        data = json.loads(gzip.decompress((where / "runs" / f"{name}.json.gz").read_bytes()))
        milestones = {int(n): e for n, e in data["milestones"].items()}
        results.append(
            RunResult(
                data["name"],
                data["condition"],
                data["kind"],
                data["seed"],
                data["evaluation"],
                milestones,
                data["curve"],
                data["config"],
            )
        )
    return results


def panel_table(results: list[RunResult]) -> list[dict[str, Any]]:
    """One entry per panel, in the conditions' order: every variant's per-seed values (and the
    runs they come from), mean and t-interval over seeds; the variant with the highest mean
    (``"tie"`` when two share it: a tie is no win); and, where the hierarchical predator and
    the baselines played the same episodes, its paired difference with each baseline
    (:func:`stats.paired_difference`, seed by seed)."""
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
                        "ci": stats.t_interval(values),
                        "seeds": [r.seed for r in runs],
                        "values": values.tolist(),
                        "runs": [r.name for r in runs],
                    }
            order = [k for k in kinds if k in variants] + [b for b in BASELINES if b in variants]
            variants = {k: variants[k] for k in order}  # trained kinds first, then the baselines
            entry: dict[str, Any] = {"condition": condition, "predator": predator, "variants": variants}
            top = max(v["mean"] for v in variants.values())
            leaders = [k for k, v in variants.items() if top - v["mean"] <= stats.TIE]
            entry["best"] = leaders[0] if len(leaders) == 1 else "tie"
            if reference == "hierarchical" and all(b in variants for b in BASELINES):
                ours = np.array(variants["hierarchical"]["values"])
                entry["paired"] = {b: stats.paired_difference(ours, np.array(variants[b]["values"])) for b in BASELINES}
            table.append(entry)
    return table


def judge(
    table: list[dict[str, Any]], alpha: float = stats.ALPHA, margin: float = stats.EQUIVALENCE_MARGIN
) -> dict[str, int]:
    """Holm's correction over the family of paired comparisons in ``table`` (every panel
    against both baselines), each direction its own family at ``alpha``, and the equivalence
    tests within ``margin`` (two one-sided paired tests, :func:`stats.paired_equivalence`) a
    third family; writes the adjusted p-values into each comparison and the panel's ``verdict``
    (:func:`stats.classify`: better, equivalent, not resolved or worse). Returns the count
    of each verdict."""
    comparisons = [c for t in table for c in t.get("paired", {}).values()]
    if comparisons:
        for c in comparisons:
            c["equivalence"] = stats.paired_equivalence(c["differences"], margin)
            c["p_equivalent"] = c["equivalence"]["p"]
        for side in ("p_greater", "p_less", "p_equivalent"):
            adjusted = stats.holm([c[side] for c in comparisons])
            for c, value in zip(comparisons, adjusted, strict=True):
                c[f"{side}_holm"] = float(value)
    counts = dict.fromkeys(VERDICTS, 0)
    for t in table:
        if "paired" in t:
            t["verdict"] = stats.classify(t["paired"], alpha)
            counts[t["verdict"]] += 1
    return counts


VERDICTS = stats.VERDICTS


#: Equivalence margins the sensitivity table re-judges a budget at, beside the chosen one.
SENSITIVITY_MARGINS = (0.02, stats.EQUIVALENCE_MARGIN, 0.1)


def margin_sensitivity(table: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The verdict counts of ``table`` re-judged at each of :data:`SENSITIVITY_MARGINS`: only
    *equivalent* and *not resolved* can trade panels (the margin enters no other test)."""
    return [{"margin": m, **judge(copy.deepcopy(table), margin=m)} for m in SENSITIVITY_MARGINS]


def verdicts_by_condition(table: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per condition, how many of its judged panels got each verdict: a condition's predators
    share runs (the same seeds, the same prey), so its panels are not independent findings."""
    rows = []
    for condition in dict.fromkeys(t["condition"] for t in table if "verdict" in t):
        panels = [t for t in table if t["condition"] == condition and "verdict" in t]
        rows.append(
            {
                "condition": condition,
                "panels": len(panels),
                **{v: sum(t["verdict"] == v for t in panels) for v in VERDICTS},
            }
        )
    return rows


def above_both_on_means(table: list[dict[str, Any]]) -> int:
    """The paper's count on the means over seeds: panels where the hierarchical predator's mean
    is strictly above both baselines' (a tie is no win)."""
    return sum(
        all(t["variants"]["hierarchical"]["mean"] > t["variants"][b]["mean"] for b in BASELINES)
        for t in table
        if "paired" in t
    )


def strict_counts(table: list[dict[str, Any]]) -> dict[str, Any]:
    """The paper's count, one seed at a time as the paper counted its one seed: on each seed,
    the panels where the hierarchical predator's return is strictly above both baselines'.
    The counts, their mean, spread and t-interval, and where the paper's 16 falls among them."""
    judged = [t for t in table if "paired" in t]
    if not judged:
        return {"seeds": [], "counts": []}
    # the seeds every judged panel has (a sweep still running may have more seeds of one condition)
    seeds = sorted(set.intersection(*(set(t["variants"]["hierarchical"]["seeds"]) for t in judged)))
    if not seeds:
        return {"seeds": [], "counts": []}
    counts = []
    for seed in seeds:
        wins = 0
        for t in judged:
            v = t["variants"]
            i = v["hierarchical"]["seeds"].index(seed)
            ours = v["hierarchical"]["values"][i]
            wins += all(ours > v[b]["values"][i] + stats.TIE for b in BASELINES)
        counts.append(wins)
    values = np.array(counts, dtype=float)
    return {
        "seeds": seeds,
        "counts": counts,
        "panels": len(judged),
        "mean": float(values.mean()),
        "sd": float(values.std(ddof=1)) if len(values) > 1 else None,
        "ci": stats.t_interval(values),
        "min": int(values.min()),
        "max": int(values.max()),
        "seeds_at_or_above_paper": int(np.sum(values >= PAPER_COUNT)),
        "paper": PAPER_COUNT,
    }


PAPER_COUNT = 16


def close_calls(results: list[RunResult], table: list[dict[str, Any]]) -> dict[str, int]:
    """How many per-seed panel decisions (hierarchical against its better baseline on that seed)
    lie within two paired standard errors of the evaluation's own episode noise: decisions a
    rerun of the evaluation with other episodes could turn."""
    by_name = {r.name: r for r in results}
    close = total = 0
    for t in (t for t in table if "paired" in t):
        p = int(t["predator"].removeprefix("predator_"))
        for name in t["variants"]["hierarchical"]["runs"]:
            returns = by_name[name].evaluation["panels"][p].get("episode_returns")
            if not returns:
                continue
            ours = np.asarray(returns["trained"], dtype=float)
            differences = [ours - np.asarray(returns[b], dtype=float) for b in BASELINES]
            closest = min(differences, key=lambda d: d.mean())  # the better baseline on this seed
            total += 1
            close += int(abs(closest.mean()) < 2 * closest.std(ddof=1) / np.sqrt(len(closest)))
    return {"decisions": total, "within_two_standard_errors": close}


def improvement(results: list[RunResult], table: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """The probability of improvement of the hierarchical predator over each baseline (its own
    prey's seed: the same opponents), aggregated over panels as rliable does (Mann–Whitney per
    panel, averaged), with a stratified bootstrap interval (seeds resampled within each panel).
    Not over the flat ablation: its runs meet other prey (:mod:`pursuit_bench.reports.pool` compares
    the two kinds against the same opponents)."""
    out: dict[str, dict[str, Any]] = {}
    judged = [t for t in table if "hierarchical" in t["variants"]]
    for other in BASELINES:
        panels = [t for t in judged if other in t["variants"]]
        if not panels:
            continue
        xs = [np.array(t["variants"]["hierarchical"]["values"]) for t in panels]
        ys = [np.array(t["variants"][other]["values"]) for t in panels]
        out[other] = stats.improvement_interval(xs, ys)
    return out


#: Margins the power table sizes seeds for (returns per episode).
POWER_MARGINS = (0.02, 0.05)


def power_table(table: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """For every panel not resolved, each of its undecided comparisons: the seed-level spread and the seeds a paired
    one-sided t-test at level ALPHA needs to detect a margin of 0.02 and of 0.05 with 80 % power
    (per comparison; ``*_family``: at the level Holm's first step demands of the whole family,
    ALPHA over the number of comparisons)."""
    family = sum(len(t.get("paired", {})) for t in table)
    rows = []
    for t in table:
        if t.get("verdict") != "not resolved":
            continue
        for baseline, c in t["paired"].items():
            if min(c["p_greater_holm"], c["p_less_holm"]) <= stats.ALPHA:
                continue  # this comparison is decided; the other one holds the panel back
            row: dict[str, Any] = {
                "condition": t["condition"],
                "predator": t["predator"],
                "baseline": baseline,
                "mean": c["mean"],
                "sd": c["sd"],
                "seeds": c["n"],
            }
            for margin in POWER_MARGINS:
                row[f"seeds_for_{margin}"] = stats.seeds_for_power(c["sd"], margin)
                row[f"seeds_for_{margin}_family"] = stats.seeds_for_power(c["sd"], margin, stats.ALPHA / family)
            rows.append(row)
    return rows


def by_budget(results: list[RunResult]) -> dict[int, list[RunResult]]:
    """The hierarchical runs as evaluated at each training budget (episodes): every kept
    checkpoint's evaluation and the final one, each a complete Fig. 2 of its own."""
    budgets: dict[int, list[RunResult]] = {}
    for r in results:
        if r.kind != "hierarchical":
            continue
        final = int(r.evaluation.get("trained_episodes") or r.config["episodes"])
        for episodes, evaluation in [*r.milestones.items(), (final, r.evaluation)]:
            budgets.setdefault(episodes, []).append(dataclasses.replace(r, evaluation=evaluation, milestones={}))
    return dict(sorted(budgets.items()))


def budget_table(results: list[RunResult]) -> list[dict[str, Any]]:
    """Per training budget, its own family of tests: the panels better, equivalent, not resolved
    and worse (Holm-corrected paired tests), the strict count on the means over seeds (ties no win), and
    the strict count per seed (mean, least, most)."""
    rows = []
    for episodes, evaluated in by_budget(results).items():
        table = panel_table(evaluated)
        verdicts = judge(table)
        per_seed = strict_counts(table)
        rows.append(
            {
                "episodes": episodes,
                "runs": len(evaluated),
                "panels": sum(verdicts.values()),
                **verdicts,
                "hierarchical_best": above_both_on_means(table),
                "per_seed_mean": per_seed.get("mean"),
                "per_seed_min": per_seed.get("min"),
                "per_seed_max": per_seed.get("max"),
            }
        )
    return rows


def margins_by_budget(results: list[RunResult]) -> list[dict[str, Any]]:
    """The 44 paired differences (panel × baseline) at every budget the hierarchical runs were
    evaluated at: mean, t-interval and Holm-adjusted p-values within that budget's family (the
    forest plot's rows)."""
    rows: dict[tuple[str, str, str], dict[str, Any]] = {}
    for episodes, evaluated in by_budget(results).items():
        table = panel_table(evaluated)
        judge(table)
        for t in table:
            for baseline, c in t.get("paired", {}).items():
                row = rows.setdefault(
                    (t["condition"], t["predator"], baseline),
                    {"condition": t["condition"], "predator": t["predator"], "baseline": baseline, "budgets": {}},
                )
                row["budgets"][str(episodes)] = {
                    k: c[k]
                    for k in ("n", "mean", "ci", "p_greater_holm", "p_less_holm", "p_equivalent_holm", "differences")
                }
    return list(rows.values())


def seed_margins(entry: dict[str, Any]) -> np.ndarray:
    """A panel's margin over its better baseline, seed by seed: the trained predator's return
    minus the higher of the two baselines' on that seed's evaluation."""
    v = entry["variants"]
    return np.array(v["hierarchical"]["values"]) - np.maximum(*(np.array(v[b]["values"]) for b in BASELINES))


def margin_by_budget(results: list[RunResult]) -> list[dict[str, Any]]:
    """Per panel, its margin over the better baseline at every budget: per seed the trained
    predator's return minus the higher of the two baselines' on that seed's evaluation, the mean
    over seeds and its 95 % t-interval (the figure of margins against budget)."""
    rows: dict[tuple[str, str], dict[str, Any]] = {}
    for episodes, evaluated in by_budget(results).items():
        for t in (t for t in panel_table(evaluated) if "paired" in t):
            margins = seed_margins(t)
            row = rows.setdefault(
                (t["condition"], t["predator"]), {"condition": t["condition"], "predator": t["predator"], "budgets": {}}
            )
            row["budgets"][str(episodes)] = {
                "seeds": len(margins),
                "mean": float(margins.mean()),
                "ci": stats.t_interval(margins),
                "values": margins.tolist(),
            }
    return list(rows.values())


def margin_budget_markdown(rows: list[dict[str, Any]]) -> str:
    """The margin over the better baseline at every budget, mean [95 % t-interval] over seeds."""
    budgets = sorted({int(b) for r in rows for b in r["budgets"]})
    lines = [
        "| condition | predator | " + " | ".join(f"{b} episodes" for b in budgets) + " |",
        "|---|---|" + "---:|" * len(budgets),
    ]
    for r in rows:
        cells = [f"{c['mean']:+.3f}{span_text(c['ci'])}" if (c := r["budgets"].get(str(b))) else "–" for b in budgets]
        lines.append(f"| {r['condition']} | {r['predator']} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


#: What counts as a margin that has stopped moving: less than this change over the last 30 %
#: of training (an equivalence bound for the slope test).
STEADY_CHANGE = 0.02
LAST_PART = 0.3
#: The fewest budgets the slope test looks at: with budgets spread out (15,000 … 150,000
#: episodes) the last 30 % may hold only the final one, so the window reaches back to hold three.
LAST_BUDGETS = 3


def convergence(results: list[RunResult]) -> list[dict[str, Any]]:
    """Per panel, whether the margin over its better baseline (per seed, the trained predator's
    return minus the higher of the baselines' on that seed's evaluation) still moves over the
    last 30 % of training: the evaluations kept there (``--keep-checkpoints``) and the final
    one (at least the last three budgets), a least-squares slope per seed, the slopes' t-interval over seeds
    (:func:`stats.slope_test`, episodes in thousands): ``rising``, ``falling``, ``flat``
    (the interval within ±0.02 over that stretch) or ``not resolved``, with the slope the test
    would have detected."""
    rows: list[dict[str, Any]] = []
    budgets = by_budget(results)
    if not budgets:
        return rows
    final = max(budgets)
    window = sorted(set([e for e in budgets if e >= (1 - LAST_PART) * final] + list(budgets)[-LAST_BUDGETS:]))
    if len(window) < 2:
        return rows
    span = (max(window) - min(window)) / 1000
    tables = {e: panel_table(budgets[e]) for e in window}
    for i, t in enumerate(tables[final]):
        if "paired" not in t:
            continue
        curves = np.array([seed_margins(tables[e][i]) for e in window]).T  # (seeds, budgets)
        test = stats.slope_test(list(curves), np.array(window) / 1000, STEADY_CHANGE / span)
        rows.append(
            {
                "condition": t["condition"],
                "predator": t["predator"],
                "budgets": window,
                "margins": curves.mean(axis=0).tolist(),
                **test,
            }
        )
    return rows


def curves(results: list[RunResult]) -> dict[str, dict[str, Any]]:
    """Learning curves per condition and kind, from each run's curve in blocks: for every
    agent's return and the capture rate, the mean over seeds of each block, with a 95 %
    interval."""
    out: dict[str, dict[str, Any]] = {}
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        names = CONDITIONS[condition].agent_names
        for kind in sorted({r.kind for r in results if r.condition == condition}):
            runs = [r for r in results if r.condition == condition and r.kind == kind and r.curve is not None]
            if not runs:
                continue
            series: dict[str, Any] = {}
            columns = [(f"return/{a}", f"return/{a}") for a in names] + [("captured", "capture_rate")]
            for column, label in columns:
                per_run = np.array([r.curve[column] for r in runs])  # type: ignore[index]  # (seeds, blocks)
                entry: dict[str, Any] = {"mean": per_run.mean(axis=0).tolist(), "ci": None}
                if len(runs) > 1:
                    bounds = np.array([stats.t_interval(block) for block in per_run.T])  # (blocks, 2)
                    entry["ci"] = [bounds[:, 0].tolist(), bounds[:, 1].tolist()]
                series[label] = entry
            ends = np.array(runs[0].curve["episodes"])  # type: ignore[index]
            starts = np.concatenate([[0], ends[:-1]])
            out.setdefault(condition, {})[kind] = {
                "episodes": ((starts + ends) / 2).tolist(),
                "seeds": len(runs),
                "series": series,
            }
    return out


def classification_markdown(table: list[dict[str, Any]]) -> str:
    """The claim panel by panel: the verdict, and against each baseline the mean paired
    difference over seeds with its 95 % t-interval and three Holm-adjusted p-values: the
    trained predator ahead, behind, and within the equivalence margin."""
    lines = [
        "| condition | predator | verdict | − always chase [95 % t-interval] | p ahead / behind / equivalent (Holm) "
        "| − always stalk [95 % t-interval] | p ahead / behind / equivalent (Holm) |",
        "|---|---|---|---:|---:|---:|---:|",
    ]
    for t in (t for t in table if "paired" in t):
        cells = []
        for b in BASELINES:
            c = t["paired"][b]
            sides = ("p_greater_holm", "p_less_holm", "p_equivalent_holm")
            cells += [f"{c['mean']:+.3f}{span_text(c['ci'])}", " / ".join(p_text(c.get(side)) for side in sides)]
        lines.append(f"| {t['condition']} | {t['predator']} | **{t['verdict']}** | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def sensitivity_markdown(rows: list[dict[str, Any]]) -> str:
    """The verdict counts at each equivalence margin of :func:`margin_sensitivity`."""
    lines = ["| equivalence margin | " + " | ".join(VERDICTS) + " |", "|---:|" + "---:|" * len(VERDICTS)]
    for r in rows:
        lines.append(f"| ±{r['margin']:g} | " + " | ".join(str(r[v]) for v in VERDICTS) + " |")
    return "\n".join(lines) + "\n"


def by_condition_markdown(rows: list[dict[str, Any]]) -> str:
    """The verdicts counted by condition beside the panels' total (a condition's panels share runs)."""
    lines = [
        "| condition | panels | " + " | ".join(VERDICTS) + " |",
        "|---|---:|" + "---:|" * len(VERDICTS),
    ]
    for r in rows:
        lines.append(f"| {r['condition']} | {r['panels']} | " + " | ".join(str(r[v]) for v in VERDICTS) + " |")
    totals = {v: sum(r[v] for r in rows) for v in VERDICTS}
    conditions = {v: sum(r[v] > 0 for r in rows) for v in VERDICTS}
    lines.append(
        f"| **panels** | {sum(r['panels'] for r in rows)} | " + " | ".join(str(totals[v]) for v in VERDICTS) + " |"
    )
    lines.append(
        f"| **conditions with one or more** | {len(rows)} | " + " | ".join(str(conditions[v]) for v in VERDICTS) + " |"
    )
    return "\n".join(lines) + "\n"


def variants_markdown(table: list[dict[str, Any]]) -> str:
    """Fig. 2 as a table: each variant's mean return over seeds with its 95 % t-interval, and
    the variant with the highest mean (``tie`` when shared)."""

    def cell(v: dict[str, Any] | None) -> str:
        return "–" if v is None else f"{v['mean']:+.3f}{span_text(v['ci'], 2)}"

    kinds = sorted({k for t in table for k in t["variants"]} - set(BASELINES), key=lambda k: (k != "hierarchical", k))
    lines = [
        "| condition | predator | " + " | ".join(kinds) + " | always chase | always stalk | highest mean |",
        "|---|---|" + "---:|" * (len(kinds) + 2) + "---|",
    ]
    for t in table:
        v = t["variants"]
        row = [
            t["condition"],
            t["predator"],
            *[cell(v.get(k)) for k in (*kinds, *BASELINES)],
            t["best"].replace("_", " "),
        ]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def counts_markdown(counts: dict[str, Any]) -> str:
    """The strict count per seed as a one-row table, with its mean and interval."""
    if not counts.get("counts"):
        return "No panel has both baselines.\n"
    header = " | ".join(f"seed {s}" for s in counts["seeds"])
    values = " | ".join(str(c) for c in counts["counts"])
    spread = f"{counts['mean']:.1f}" + (span_text(counts["ci"], 1).replace("+", "") if counts["ci"] else "")
    return (
        f"| {header} | mean [95 % t-interval] | seeds at or above the paper's {counts['paper']} |\n"
        f"|{'---:|' * (len(counts['seeds']) + 2)}\n"
        f"| {values} | {spread} | {counts['seeds_at_or_above_paper']} of {len(counts['seeds'])} |\n"
    )


def improvement_markdown(poi: dict[str, dict[str, Any]]) -> str:
    """The probability of improvement over each other variant, aggregated over panels."""
    lines = ["| hierarchical over | P(hierarchical > other) [95 % stratified bootstrap] | panels |", "|---|---:|---:|"]
    for other, entry in poi.items():
        ci = entry["ci"]
        lines.append(
            f"| {LABELS.get(other, other)} | {entry['value']:.2f} [{ci[0]:.2f}, {ci[1]:.2f}] | {entry['panels']} |"
        )
    return "\n".join(lines) + "\n"


LABELS = {"always_chase": "always chase", "always_stalk": "always stalk"}


def power_markdown(rows: list[dict[str, Any]]) -> str:
    """Seeds needed, per comparison of each panel not resolved, to detect margins of 0.02 and
    0.05 at 80 % power."""
    if not rows:
        return "Every panel is resolved.\n"

    def n(value: int | None) -> str:
        return ">100000" if value is None else str(value)

    a, b = POWER_MARGINS
    lines = [
        f"| condition | predator | against | mean difference | seed-level sd | seeds for {a} | seeds for {b} "
        f"| seeds for {a}, family level | seeds for {b}, family level |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['condition']} | {r['predator']} | {LABELS.get(r['baseline'], r['baseline'])} | {r['mean']:+.3f} "
            f"| {r['sd']:.3f} | {n(r[f'seeds_for_{a}'])} | {n(r[f'seeds_for_{b}'])} "
            f"| {n(r[f'seeds_for_{a}_family'])} | {n(r[f'seeds_for_{b}_family'])} |"
        )
    return "\n".join(lines) + "\n"


def prey_table(results: list[RunResult]) -> list[dict[str, Any]]:
    """Per condition, the hierarchical runs' learned prey against their trained predators,
    means over seeds: greedy (its capture, wall-exit and survival rates and return, beside
    ``FleeingPrey`` in its place) and at ε = 0.1 as the paper evaluates (capture rate, mean
    episode length)."""
    rows = []
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        runs = [r for r in results if r.condition == condition and r.kind == "hierarchical"]
        checks = [r.evaluation["prey_check"] for r in runs if r.evaluation.get("prey_check")]
        if not checks:
            continue
        greedy = {k: float(np.mean([c["learned_greedy"][k] for c in checks])) for k in checks[0]["learned_greedy"]}
        fleeing = {k: float(np.mean([c["fleeing_prey"][k] for c in checks])) for k in checks[0]["fleeing_prey"]}
        beats = sum(c["learned_greedy"]["return"] > c["fleeing_prey"]["return"] for c in checks)
        rows.append(
            {
                "condition": condition,
                "seeds": len(checks),
                "greedy": greedy,
                "fleeing_prey": fleeing,
                "beats_fleeing_prey": beats,
                "epsilon_capture_rate": float(np.mean([r.evaluation["capture_rate"] for r in runs])),
                "epsilon_episode_length": float(np.mean([r.evaluation["episode_length"] for r in runs])),
            }
        )
    return rows


def prey_by_budget(results: list[RunResult]) -> list[dict[str, Any]]:
    """:func:`prey_table` at every budget the hierarchical runs were evaluated at: whether the
    learned prey still beats ``FleeingPrey`` as training goes on (a prey that stops learning
    moves every margin)."""
    return [{"episodes": episodes, "rows": prey_table(runs)} for episodes, runs in by_budget(results).items()]


def prey_budget_markdown(budgets: list[dict[str, Any]]) -> str:
    """The learned prey against ``FleeingPrey`` at each budget: per condition, the greedy prey's
    return beside FleeingPrey's in its place, and the seeds where the learned prey does better."""
    conditions = list(dict.fromkeys(r["condition"] for b in budgets for r in b["rows"]))
    lines = [
        "| condition | " + " | ".join(f"{b['episodes']} episodes" for b in budgets) + " |",
        "|---|" + "---:|" * len(budgets),
    ]
    for condition in conditions:
        cells = []
        for b in budgets:
            row = next((r for r in b["rows"] if r["condition"] == condition), None)
            cells.append(
                "–"
                if row is None
                else f"{row['greedy']['return']:+.2f} / {row['fleeing_prey']['return']:+.2f} "
                f"({row['beats_fleeing_prey']} of {row['seeds']})"
            )
        lines.append(f"| {condition} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def flat_table(results: list[RunResult]) -> list[dict[str, Any]]:
    """The flat ablation against the hierarchical predator at the same budget, per condition:
    each kind's margin over its own better baseline (its runs' own evaluations, against its own
    prey; mean over predators), its return, and its captures of ``FleeingPrey`` (one scripted
    opponent for both kinds); the hierarchical minus flat differences with Welch's t-intervals
    over seeds (different runs: nothing to pair)."""
    rows = []
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        kinds: dict[str, list[RunResult]] = {
            kind: sorted((r for r in results if r.condition == condition and r.kind == kind), key=lambda r: r.seed)
            for kind in ("hierarchical", "flat")
        }
        if not all(len(runs) >= 2 for runs in kinds.values()):
            continue
        row: dict[str, Any] = {"condition": condition, "seeds": {k: len(v) for k, v in kinds.items()}}
        measures = {
            "margin": lambda e: float(np.mean([p["trained"] - max(p[b] for b in BASELINES) for p in e["panels"]])),
            "return": lambda e: float(np.mean([p["trained"] for p in e["panels"]])),
            "fleeing_prey_captured": lambda e: float(e["prey_check"]["fleeing_prey"]["captured"]),
        }
        for name, measure in measures.items():
            values = {k: np.array([measure(r.evaluation) for r in v]) for k, v in kinds.items()}
            row[name] = {
                **{k: {"mean": float(v.mean()), "ci": stats.t_interval(v)} for k, v in values.items()},
                "difference": stats.welch_difference(values["hierarchical"], values["flat"]),
            }
        rows.append(row)
    return rows


def flat_markdown(rows: list[dict[str, Any]]) -> str:
    """The flat ablation table as markdown (REPRODUCTION.md quotes it)."""
    lines = [
        "| condition | seeds (hier. / flat) | margin over its better baseline: hierarchical / flat | difference "
        "[95 % Welch] | return: hierarchical / flat | captures of FleeingPrey: hierarchical / flat | difference "
        "[95 % Welch] |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        m, ret, cap = r["margin"], r["return"], r["fleeing_prey_captured"]
        lines.append(
            f"| {r['condition']} | {r['seeds']['hierarchical']} / {r['seeds']['flat']} "
            f"| {m['hierarchical']['mean']:+.3f} / {m['flat']['mean']:+.3f} "
            f"| {m['difference']['mean']:+.3f}{span_text(m['difference']['ci'])} "
            f"| {ret['hierarchical']['mean']:+.2f} / {ret['flat']['mean']:+.2f} "
            f"| {cap['hierarchical']['mean']:.0%} / {cap['flat']['mean']:.0%} "
            f"| {cap['difference']['mean']:+.2f}{span_text(cap['difference']['ci'], 2)} |"
        )
    return "\n".join(lines) + "\n"


def prey_markdown(rows: list[dict[str, Any]]) -> str:
    """The prey table as markdown (REPRODUCTION.md quotes it)."""
    lines = [
        "| condition | greedy prey: caught | left the arena | survived 300 steps | return | FleeingPrey: return "
        "| seeds beating FleeingPrey | prey ε = 0.1: caught | mean length |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        g = r["greedy"]
        lines.append(
            f"| {r['condition']} | {g['captured']:.0%} | {g['left_area']:.0%} | {g['survived']:.0%} | "
            f"{g['return']:+.2f} | {r['fleeing_prey']['return']:+.2f} | {r['beats_fleeing_prey']} of {r['seeds']} | "
            f"{r['epsilon_capture_rate']:.0%} | {r['epsilon_episode_length']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def budget_markdown(rows: list[dict[str, Any]]) -> str:
    """The verdicts against budget as a markdown table (REPRODUCTION.md quotes it)."""
    lines = [
        "| episodes per run | runs | panels | better | equivalent | not resolved | worse | highest mean (strict) "
        "| per-seed strict count: mean (least–most) |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['episodes']} | {r['runs']} | {r['panels']} | {r['better']} | {r['equivalent']} "
            f"| {r['not resolved']} | {r['worse']} "
            f"| {r['hierarchical_best']} | {r['per_seed_mean']:.1f} ({r['per_seed_min']}–{r['per_seed_max']}) |"
        )
    return "\n".join(lines) + "\n"


def convergence_markdown(rows: list[dict[str, Any]]) -> str:
    """The margins' slope over the last 30 % of training as a markdown table: per panel the
    mean slope per 1000 episodes with its interval, the verdict, and the slope the test would
    have detected with 80 % power."""
    if not rows:
        return "No evaluations were kept in the last 30 % of training (`--keep-checkpoints`).\n"
    lines = [
        "| condition | predator | margin at each budget (mean over seeds) | slope per 1000 episodes [95 % t-interval] "
        "| verdict | detectable slope (80 % power) |",
        "|---|---|---|---:|---|---:|",
    ]
    for r in rows:
        margins = " → ".join(f"{m:+.3f}" for m in r["margins"])
        lines.append(
            f"| {r['condition']} | {r['predator']} | {margins} | {r['mean']:+.4f}{span_text(r['ci'], 4)} "
            f"| {r['verdict']} | {r['detectable']:.4f} |"
        )
    return "\n".join(lines) + "\n"


def write(where: Path, out: Path | None = None) -> dict[str, Any]:
    """Collect a sweep's evaluated runs (its folder, or its compact results) and write
    ``report.json`` (every figure at full precision), ``report.md``, ``fig2.png``,
    ``curves.png``, ``counts.png`` and, with kept checkpoints, ``forest.png``, ``budget.png`` and
    ``margins.png``
    into ``out`` (default: ``where``). Returns the summary and the files written; ValueError
    if there is no evaluated run."""
    from pursuit_bench.figures.plots import budget_png, counts_png, curves_png, fig2_png, forest_png, margins_png
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    out = out or where
    results = collect(where)
    table = panel_table(results)
    verdicts = judge(table)
    counts = strict_counts(table)
    totals: dict[str, Any] = {
        "panels": sum(verdicts.values()),
        **verdicts,
        "hierarchical_best": above_both_on_means(table),
        "per_seed": counts,
        "close_calls": close_calls(results, table),
        "improvement": improvement(results, table),
        "alpha_per_direction": stats.ALPHA,
        "equivalence_margin": stats.EQUIVALENCE_MARGIN,
        "comparisons": sum(len(t.get("paired", {})) for t in table),
        "by_condition": verdicts_by_condition(table),
        "margin_sensitivity": margin_sensitivity(table),
    }
    power = power_table(table)
    learning = curves(results)
    budgets = budget_table(results)
    forest = margins_by_budget(results)
    margin_budgets = margin_by_budget(results)
    converged = convergence(results)
    prey = prey_table(results)
    prey_budgets = prey_by_budget(results)
    flat = flat_table(results)
    payload = {
        "sweep": str(where),
        "summary": totals,
        "panels": table,
        "power": power,
        "budgets": budgets,
        "margins": forest,
        "margin_by_budget": margin_budgets,
        "convergence": converged,
        "prey": prey,
        "prey_by_budget": prey_budgets,
        "flat": flat,
        "curves": learning,
    }
    text = "\n".join(
        [
            f"# The hierarchical predator against the baselines: {where}",
            "",
            f"Seeds are the unit: each panel's difference from each baseline is paired by seed (same prey, same "
            f"evaluation episodes), with a 95 % t-interval over seeds and a one-sided paired t-test per direction, "
            f"Holm-corrected over the {totals['comparisons']} comparisons at {stats.ALPHA} a direction, and "
            f"two one-sided paired tests for equivalence within ±{stats.EQUIVALENCE_MARGIN} (Holm alike) "
            "(docs/statistics.md).",
            "",
            f"- **{totals['better']} better, {totals['equivalent']} equivalent, {totals['not resolved']} not "
            f"resolved, {totals['worse']} worse** of {totals['panels']} panels.",
            f"- Highest mean of it and the two baselines (strictly; the paper's count on means over seeds): "
            f"{totals['hierarchical_best']}.",
            f"- Per-seed decisions within two paired standard errors of the evaluation's episode noise: "
            f"{totals['close_calls']['within_two_standard_errors']} of {totals['close_calls']['decisions']}.",
            "",
            "## Panel by panel",
            "",
            classification_markdown(table),
            "## Verdicts by condition",
            "",
            by_condition_markdown(totals["by_condition"]),
            "## The verdicts at other equivalence margins",
            "",
            sensitivity_markdown(totals["margin_sensitivity"]),
            "## The paper's strict count, seed by seed",
            "",
            counts_markdown(counts),
            "## Probability of improvement over panels",
            "",
            improvement_markdown(totals["improvement"]),
            "## Seeds needed where a panel is not resolved",
            "",
            power_markdown(power),
            "## Fig. 2: every variant's mean return",
            "",
            variants_markdown(table),
            "## Panels against the training budget",
            "",
            budget_markdown(budgets),
            "## The margin over the better baseline at each budget (mean [95 % t-interval] over seeds)",
            "",
            margin_budget_markdown(margin_budgets),
            "## Convergence: the margin over the better baseline at the last budgets (the last 30 % of training, at "
            "least three)",
            "",
            convergence_markdown(converged),
            "## The learned prey (hierarchical runs, final budget)",
            "",
            prey_markdown(prey),
            "## The learned prey against FleeingPrey at each budget (greedy return: learned / FleeingPrey, seeds "
            "where the learned prey does better)",
            "",
            prey_budget_markdown(prey_budgets),
            "## The flat ablation at the same budget",
            "",
            flat_markdown(flat) if flat else "No condition has two or more runs of both kinds.\n",
        ]
    )
    atomic_write_text(out / "report.json", json.dumps(payload, indent=2) + "\n")
    atomic_write_text(out / "report.md", text)
    atomic_write_bytes(out / "fig2.png", fig2_png(table))
    written = ["report.md", "report.json", "fig2.png"]
    if counts.get("counts"):
        atomic_write_bytes(out / "counts.png", counts_png(counts))
        written.append("counts.png")
    if learning:
        atomic_write_bytes(out / "curves.png", curves_png(learning))
        written.append("curves.png")
    if forest:
        atomic_write_bytes(out / "forest.png", forest_png(forest))
        written.append("forest.png")
    if len(budgets) > 1:
        atomic_write_bytes(out / "budget.png", budget_png(budgets))
        atomic_write_bytes(out / "margins.png", margins_png(margin_budgets))
        written += ["budget.png", "margins.png"]
    return {**totals, "written": written, "budgets": budgets}
