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

import dataclasses
import gzip
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
        curve[column] = [round(float(values[lo:hi].mean()), 5) for lo, hi in itertools.pairwise(edges)]
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
    if (where / "results.json").is_file():
        return load_results(where)
    results = [_from_folder(eval_json.parent) for eval_json in sorted((where / "runs").glob("*/eval.json"))]
    if not results:
        raise ValueError(
            f"{where}: no evaluated run folder (runs/*/eval.json) and no results.json; run the sweep first"
        )
    return results


def export(results: list[RunResult], out: Path, about: dict[str, Any]) -> int:
    """Write a sweep's results compactly into ``out``: ``results.json`` (``about``: the plan, the
    command) and ``runs/<name>.json.gz`` per run (its evaluations with every episode's return,
    prey checks, its learning curve in blocks, its configuration), enough for :func:`collect`
    to make every table and figure again without the run folders. Returns the bytes written."""
    from pursuit_bench.files import atomic_write_bytes, atomic_write_text

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
                        "runs": [r.name for r in runs],
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


def best_or_tied(table: list[dict[str, Any]]) -> int:
    """Panels where the hierarchical predator has the highest mean of it and the two baselines,
    or its interval overlaps the best one's (statistically tied with the best)."""
    count = 0
    for entry in table:
        v = entry["variants"]
        if "hierarchical" not in v or not all(b in v for b in BASELINES):
            continue
        top = max(("hierarchical", *BASELINES), key=lambda k: v[k]["mean"])
        ours, theirs = v["hierarchical"]["ci"], v[top]["ci"]
        if top == "hierarchical" or (ours is not None and theirs is not None and ours[1] >= theirs[0]):
            count += 1
    return count


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
    """Per training budget: panels judged, where the hierarchical predator is best, best or
    tied with the best, its interval above both baselines', and its mean ratio to the best."""
    rows = []
    for episodes, evaluated in by_budget(results).items():
        table = panel_table(evaluated)
        totals = summary(table)
        rows.append(
            {
                "episodes": episodes,
                "runs": len(evaluated),
                **{k: totals[k] for k in ("panels", "hierarchical_best", "hierarchical_interval_above_both")},
                "hierarchical_best_or_tied": best_or_tied(table),
                "mean_ratio_to_best": mean_ratio_to_best(table),
            }
        )
    return rows


def mean_ratio_to_best(table: list[dict[str, Any]]) -> float | None:
    """The hierarchical predator's mean return over the best variant's, averaged over panels
    where both are positive (1 where it is the best)."""
    ratios = []
    for entry in table:
        v = entry["variants"]
        if "hierarchical" not in v or not all(b in v for b in BASELINES):
            continue
        top = max(v[k]["mean"] for k in ("hierarchical", *BASELINES))
        if top > 0 and v["hierarchical"]["mean"] > 0:
            ratios.append(v["hierarchical"]["mean"] / top)
    return float(np.mean(ratios)) if ratios else None


def convergence(results: list[RunResult]) -> list[dict[str, Any]]:
    """Per condition and kind, for the predators' return (mean over predators), the prey's
    return and the capture rate: the mean over seeds of the last 10 % of training and of the
    10 % before, the seeds' 95 % interval of the last, and whether the change lies inside that
    interval's half-width (the curve has stopped moving by more than the seeds disagree)."""
    rows = []
    for condition in [c for c in CONDITIONS if any(r.condition == c for r in results)]:
        names = CONDITIONS[condition].agent_names
        for kind in sorted({r.kind for r in results if r.condition == condition}):
            runs = [r for r in results if r.condition == condition and r.kind == kind and r.curve is not None]
            if not runs:
                continue
            row: dict[str, Any] = {"condition": condition, "kind": kind, "seeds": len(runs)}
            for label in ("predators", "prey", "capture_rate"):
                per_seed = []
                for r in runs:
                    curve = r.curve or {}
                    if label == "predators":
                        series = np.mean([curve[f"return/{a}"] for a in names[:-1]], axis=0)
                    elif label == "prey":
                        series = np.asarray(curve[f"return/{names[-1]}"])
                    else:
                        series = np.asarray(curve["captured"])
                    tenth = max(len(series) // 10, 1)
                    per_seed.append((series[-tenth:].mean(), series[-2 * tenth : -tenth].mean()))
                last, before = (np.array(v) for v in zip(*per_seed, strict=True))
                ci = interval(last)
                half = (ci[1] - ci[0]) / 2 if ci is not None else None
                change = float(last.mean() - before.mean())
                row[label] = {
                    "last": float(last.mean()),
                    "before": float(before.mean()),
                    "change": change,
                    "interval": ci,
                    "converged": bool(half is not None and abs(change) <= half),
                }
            rows.append(row)
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
            ends = np.array(runs[0].curve["episodes"])  # type: ignore[index]
            starts = np.concatenate([[0], ends[:-1]])
            out.setdefault(condition, {})[kind] = {
                "episodes": ((starts + ends) / 2).tolist(),
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
    """The panel count against budget as a markdown table (REPRODUCTION.md quotes it)."""
    lines = [
        "| episodes per run | runs | panels | hierarchical best | best or tied with the best | "
        "interval above both baselines | mean ratio to the best |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        ratio = f"{r['mean_ratio_to_best']:.0%}" if r["mean_ratio_to_best"] is not None else "–"
        lines.append(
            f"| {r['episodes']} | {r['runs']} | {r['panels']} | {r['hierarchical_best']} | "
            f"{r['hierarchical_best_or_tied']} | {r['hierarchical_interval_above_both']} | {ratio} |"
        )
    return "\n".join(lines) + "\n"


def convergence_markdown(rows: list[dict[str, Any]]) -> str:
    """The convergence verdicts as a markdown table: per condition and kind, the change from
    the second-last to the last tenth of training, and whether it lies within the seeds' spread."""

    def cell(entry: dict[str, Any]) -> str:
        return f"{entry['before']:+.2f} → {entry['last']:+.2f} ({'yes' if entry['converged'] else 'no'})"

    lines = [
        "| condition | kind | seeds | predators' return | prey's return | capture rate |",
        "|---|---|---:|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['condition']} | {r['kind']} | {r['seeds']} | {cell(r['predators'])} | {cell(r['prey'])} | "
            f"{cell(r['capture_rate'])} |"
        )
    return "\n".join(lines) + "\n"


def write(where: Path, out: Path | None = None) -> dict[str, Any]:
    """Collect a sweep's evaluated runs (its folder, or its compact results) and write
    ``report.json``, ``report.md``, ``fig2.png``, ``curves.png`` and, with kept checkpoints,
    ``budget.png`` into ``out`` (default: ``where``). Returns the summary and the files written;
    ValueError if there is no evaluated run."""
    from pursuit_bench.files import atomic_write_bytes, atomic_write_text
    from pursuit_bench.plots import budget_png, curves_png, fig2_png

    out = out or where
    results = collect(where)
    table = panel_table(results)
    totals = {**summary(table), "hierarchical_best_or_tied": best_or_tied(table)}
    learning = curves(results)
    budgets = budget_table(results)
    converged = convergence(results)
    payload = {
        "sweep": str(where),
        "summary": totals,
        "panels": table,
        "budgets": budgets,
        "convergence": converged,
        "curves": learning,
    }
    atomic_write_text(out / "report.json", json.dumps(payload, indent=2) + "\n")
    text = markdown(table, totals, where)
    text += "\n## Panels against the training budget\n\n" + budget_markdown(budgets)
    text += "\n## Convergence (last tenth of training against the tenth before it)\n\n"
    text += convergence_markdown(converged)
    prey = prey_table(results)
    text += "\n## The learned prey (hierarchical runs, final budget)\n\n" + prey_markdown(prey)
    payload["prey"] = prey
    atomic_write_text(out / "report.json", json.dumps(payload, indent=2) + "\n")
    atomic_write_text(out / "report.md", text)
    atomic_write_bytes(out / "fig2.png", fig2_png(table))
    written = ["report.md", "report.json", "fig2.png"]
    if learning:
        atomic_write_bytes(out / "curves.png", curves_png(learning))
        written.append("curves.png")
    if len(budgets) > 1:
        atomic_write_bytes(out / "budget.png", budget_png(budgets))
        written.append("budget.png")
    return {**totals, "written": written, "budgets": budgets}
