"""The pool study: the hierarchical and the flat predator judged against one pool of opponents
(``pursuit-bench pool``; REPRODUCTION.md, "The pool study").

A sweep trains both kinds on seeds 0 … N-1. The runs of the **pool seeds** (by default the last
two) are not judged: their prey, at the end of training, form each condition's pool, with
``FleeingPrey``; every other run (the **judged** runs) plays every member of its condition's pool
by the paper's protocol (predators greedy, a learned prey ε-greedy with ε 0.1, FleeingPrey as it
is; each predator replaced in turn by always-chase and by always-stalk on the same episodes), at
every budget the sweep kept a checkpoint for. No judged run meets a prey it trained with, and
both kinds meet the same prey on the same episodes, with the same exploration draws (common random
numbers since issue 47: ``pool.json``'s ``protocol``; a result without one was made before, its
variants' draws from one generator in turn): the prey of either kind learned against
predators of its own kind, so the pool holds as many of each.

A run's **pool return** for a predator is its mean return over the pool's members (equal weight);
its **pool margin** is that minus the better of always-chase's and always-stalk's pool returns.
Hierarchical minus flat, per panel and budget: Welch's interval over runs (the two kinds' runs
are independent), Holm over the panels of a budget, and two one-sided tests for equivalence
within :data:`EQUIVALENCE_MARGIN` (Holm too). The head start: each run's pool margin averaged over
the budgets (the area under its curve on a log-episode axis, over its span), compared alike. Cross-kind play:
each judged run's predators against its own prey and against the prey of the other kind's run of
the same seed, at the end of training.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.reports.rule_study import FLEEING, KINDS, pooled
from pursuit_bench.stats.text import p_text, span_text

FORMAT = "pursuit-bench-pool-1"
#: The learned predator kinds a pool study compares, in the order of their comparisons: each kind
#: minus every later one (residual − hierarchical, residual − flat, hierarchical − flat).
ORDER = ("residual", "hierarchical", "flat")
EQUIVALENCE_MARGIN = stats.EQUIVALENCE_MARGIN
VERDICTS = ("rule helps", "flat better", "equivalent", "not resolved")


def kinds_of(runs: list[dict[str, Any]]) -> list[str]:
    """The kinds among ``runs`` (each with a ``kind``), in :data:`ORDER`."""
    return [k for k in ORDER if any(r["kind"] == k for r in runs)]


def pairs_of(kinds: list[str]) -> list[tuple[str, str]]:
    """Every comparison of ``kinds`` (in :data:`ORDER`): each kind minus every later one."""
    return list(itertools.combinations(kinds, 2))


def checkpoint_name(episodes: int, final: int) -> str:
    """The checkpoint a sweep's run keeps at ``episodes`` (its last one at ``final``)."""
    from pursuit_bench.training import runs

    return runs.CHECKPOINT if episodes == final else runs.milestone_checkpoint(episodes)


def plan(sources: list[dict[str, Any]], pool_seeds: tuple[int, ...]) -> dict[str, Any]:
    """Split a sweep's runs (``name``, ``condition``, ``kind``, ``seed``, ``folder``) into the judged
    runs and each condition's pool (FleeingPrey, then the pool seeds' runs of every kind);
    ValueError where the runs hold fewer than two kinds, or a condition lacks a pool run of a kind
    or two judged runs of one."""
    seen: set[tuple[str, str, int]] = set()
    for s in sources:  # a run twice (one sweep given twice, say) would count twice in every interval
        key = (s["condition"], s["kind"], s["seed"])
        if key in seen:
            raise ValueError(f"{s['name']}: {s['kind']} seed {s['seed']} of {s['condition']} given twice")
        seen.add(key)
    kinds = kinds_of(sources)
    if len(kinds) < 2:
        raise ValueError(f"runs of {', '.join(kinds) or 'no'} kind: a pool study compares two kinds or more")
    judged: list[dict[str, Any]] = []
    pools: dict[str, list[dict[str, Any]]] = {}
    for condition in [c for c in CONDITIONS if any(s["condition"] == c for s in sources)]:
        mine = sorted((s for s in sources if s["condition"] == condition), key=lambda s: (s["kind"], s["seed"]))
        pool = [s for s in mine if s["seed"] in pool_seeds]
        rest = [s for s in mine if s["seed"] not in pool_seeds]
        for kind in kinds:
            if not any(s["kind"] == kind for s in pool):
                raise ValueError(f"{condition}: no {kind} run of the pool seeds {list(pool_seeds)}")
            if sum(s["kind"] == kind for s in rest) < 2:
                raise ValueError(f"{condition}: fewer than two judged {kind} runs (seeds outside the pool)")
        pools[condition] = pool
        judged += rest
    return {"judged": judged, "pools": pools}


def _jobs(
    layout: dict[str, Any], budgets: list[int], episodes: int, cross_episodes: int, seed: int
) -> list[tuple[str, tuple[Any, ...]]]:
    jobs: list[tuple[str, tuple[Any, ...]]] = []
    for run in layout["judged"]:
        opponents = [(FLEEING, None)] + [(m["name"], m["folder"]) for m in layout["pools"][run["condition"]]]
        for budget in budgets:
            checkpoint = checkpoint_name(budget, budgets[-1])
            jobs.append((f"{run['name']}|{budget}", (run["folder"], checkpoint, opponents, episodes, seed)))
        twin = [
            r
            for r in layout["judged"]
            if (r["condition"], r["seed"]) == (run["condition"], run["seed"]) and r["kind"] != run["kind"]
        ]
        crossed = [("own", run["folder"])] + [(other_key(t["kind"], len(twin)), t["folder"]) for t in twin]
        final = checkpoint_name(budgets[-1], budgets[-1])
        jobs.append((f"{run['name']}|cross", (run["folder"], final, crossed, cross_episodes, seed)))
    return jobs


def other_key(kind: str, others: int) -> str:
    """Cross-kind play's key of the prey of another kind's run: "other kind" where there is one
    other kind, else "other kind: <kind>"."""
    return "other kind" if others == 1 else f"other kind: {kind}"


def play(
    predators_from: str, checkpoint: str, opponents: list[tuple[str, str | None]], episodes: int, seed: int
) -> dict[str, Any]:
    """One judged run's predators (at ``checkpoint``) against each opponent (``FleeingPrey`` for
    None, else the prey of that run folder at its end), by the paper's protocol: per opponent,
    each predator's mean return as trained, as always-chase and as always-stalk, and the capture
    rate as trained."""
    import torch

    from pursuit_bench.agents.kinds import ScriptedAgent
    from pursuit_bench.analysis.robustness import check_opponents
    from pursuit_bench.rules.policies import FleeingPrey
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import evaluate_agents

    torch.set_num_threads(1)
    config, agents, _ = runs.described(Path(predators_from), checkpoint)
    out: dict[str, Any] = {}
    for name, prey_from in opponents:
        protocol = dict(config.protocol)
        prey: Any
        if prey_from is None:
            prey = ScriptedAgent("prey_0", FleeingPrey(obstacles=bool(config.task_options.get("obstacles"))))
            protocol["prey_epsilon"] = None
        else:
            other, theirs, _ = runs.described(Path(prey_from))
            check_opponents(config, other)
            prey = theirs["prey_0"]
        result = evaluate_agents(
            config.condition,
            {**{k: v for k, v in agents.items() if k != "prey_0"}, "prey_0": prey},
            episodes=episodes,
            seed=seed,
            prey_check=False,
            **protocol,
        )
        out[name] = {
            "panels": {p["predator"]: [p["trained"], p["always_chase"], p["always_stalk"]] for p in result["panels"]},
            "stderr": {p["predator"]: p["stderr"]["trained"] for p in result["panels"]},
            "capture_rate": result["capture_rate"],
        }
    return out


def run(
    sources: list[dict[str, Any]],
    budgets: list[int],
    out: Path,
    *,
    pool_seeds: tuple[int, ...],
    episodes: int,
    cross_episodes: int,
    seed: int,
    workers: int = 1,
    progress: Callable[[int, int], None] = lambda done, total: None,
) -> dict[str, Any]:
    """Every judged run against its pool at every budget, and in cross-kind play; each evaluation
    kept in ``out/pool-parts/`` as it finishes (a rerun goes on from there). Returns the compact
    result (:func:`summarise` reads it)."""
    from pursuit_bench.training.jobs import run_jobs

    layout = plan(sources, pool_seeds)
    jobs = _jobs(layout, budgets, episodes, cross_episodes, seed)
    # a kept evaluation is reused only for the same pool and budgets (an extended sweep's last budget differs)
    from pursuit_bench.training.evaluate import PROTOCOL

    stamp = {
        "protocol": PROTOCOL,  # evaluations kept by an earlier protocol are not reused (none before carried one)
        "episodes": episodes,
        "cross_episodes": cross_episodes,
        "seed": seed,
        "budgets": budgets,
        "pool_seeds": list(pool_seeds),
    }
    done = run_jobs(jobs, play, out / "pool-parts", stamp, workers=workers, progress=progress)
    return {
        "format": FORMAT,
        **stamp,
        "pools": {c: [FLEEING] + [m["name"] for m in members] for c, members in layout["pools"].items()},
        "runs": [
            {
                **{k: r[k] for k in ("name", "condition", "kind", "seed")},
                "pool": {str(b): done[f"{r['name']}|{b}"] for b in budgets},
                "cross": done[f"{r['name']}|cross"],
            }
            for r in layout["judged"]
        ],
    }


def load(path: Path) -> dict[str, Any]:
    """A compact pool result (pool.json), or ValueError."""
    try:
        result = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise ValueError(f"{path}: not readable as a pool result ({error})") from None
    if not isinstance(result, dict) or result.get("format") != FORMAT:
        raise ValueError(f"{path}: not a pursuit-bench pool result (format {FORMAT!r})")
    return result


# --- the judgement -------------------------------------------------------------------------------


def _panels(result: dict[str, Any]) -> list[tuple[str, str]]:
    seen: dict[tuple[str, str], None] = {}
    for r in result["runs"]:
        for predator in r["pool"][str(result["budgets"][-1])][FLEEING]["panels"]:
            seen[(r["condition"], predator)] = None
    return sorted(seen, key=lambda p: (list(CONDITIONS).index(p[0]), p[1]))


def _values(result: dict[str, Any], condition: str, predator: str, kind: str, measure: Callable[[Any], float]) -> Any:
    runs = sorted(
        (r for r in result["runs"] if (r["condition"], r["kind"]) == (condition, kind)), key=lambda r: r["seed"]
    )
    return np.array([measure(r) for r in runs])


def words(pair: tuple[str, str]) -> tuple[str, str]:
    """The verdicts of ``pair[0] − pair[1]`` below and above zero: "flat better" and "rule helps"
    for hierarchical − flat, else "<first> worse than <second>" and "<first> better than <second>"."""
    if tuple(pair) == KINDS:
        return ("flat better", "rule helps")
    return (f"{pair[0]} worse than {pair[1]}", f"{pair[0]} better than {pair[1]}")


def verdicts_of(pairs: list[tuple[str, str]]) -> tuple[str, ...]:
    """What a family of the comparisons ``pairs`` counts, in order: :data:`VERDICTS` for
    hierarchical − flat alone; with several comparisons, each one's better, worse, "<first> −
    <second>: equivalent" and ": not resolved" (:func:`counted`)."""
    if list(pairs) == [KINDS]:
        return VERDICTS
    return tuple(
        v for a, b in pairs for v in (*reversed(words((a, b))), f"{a} − {b}: equivalent", f"{a} − {b}: not resolved")
    )


def counted(row: dict[str, Any], several: bool) -> str:
    """What a row's verdict counts as in its family (:func:`verdicts_of`): the verdict itself, or
    with ``several`` comparisons "equivalent" and "not resolved" named by the comparison."""
    if several and row["verdict"] in ("equivalent", "not resolved"):
        first, second = pair_of(row)
        return f"{first} − {second}: {row['verdict']}"
    return str(row["verdict"])


def pair_of(row: dict[str, Any]) -> tuple[str, str]:
    """The comparison a row holds: its ``pair`` (first − second), hierarchical − flat without one."""
    return (row["pair"][0], row["pair"][1]) if "pair" in row else KINDS


def verdict(
    difference: dict[str, Any],
    equivalent: dict[str, Any],
    alpha: float = stats.ALPHA,
    pair: tuple[str, str] = KINDS,
) -> str:
    """A panel's verdict from ``pair[0]`` minus ``pair[1]`` (:func:`stats.welch_difference`
    with a Holm-adjusted two-sided ``p_holm``) and its equivalence test (:func:`stats.equivalence`
    with ``p_holm``): a significant difference first (two-sided at ``2 alpha``, ``alpha`` a
    direction; :func:`words`), then equivalence within the margin, else not resolved."""
    return stats.difference_verdict(difference["mean"], difference["p_holm"], equivalent["p_holm"], words(pair), alpha)


def pairwise(rows: list[dict[str, Any]], pairs: list[tuple[str, str]]) -> list[dict[str, Any]]:
    """Rows of per-kind values (``condition``, ``predator``, one list a kind) as rows of
    comparisons: one per row and pair, with its ``pair`` and the two kinds' values. Hierarchical −
    flat alone stays as the rows were (the layout of every report before the residual kind)."""
    if [tuple(p) for p in pairs] == [KINDS]:
        return rows
    return [
        {"condition": r["condition"], "predator": r["predator"], "pair": list(p), p[0]: r[p[0]], p[1]: r[p[1]]}
        for r in rows
        for p in pairs
    ]


def compare(
    rows: list[dict[str, Any]], margin: float = EQUIVALENCE_MARGIN, alpha: float = stats.ALPHA
) -> dict[str, int]:
    """Fill each row (a comparison: :func:`pair_of`, and each of its two kinds' per-run values)
    with the first kind minus the second (Welch), the equivalence test, both Holm-adjusted over the
    rows (one family), and the verdict; returns the verdict counts (:func:`verdicts_of`)."""
    for row in rows:
        first, second = pair_of(row)
        a, b = np.asarray(row[first]), np.asarray(row[second])
        row["means"] = {first: float(a.mean()), second: float(b.mean())}
        row["difference"] = stats.welch_difference(a, b)
        row["equivalence"] = stats.equivalence(a, b, margin, alpha)
    for key in ("difference", "equivalence"):
        for row, adjusted in zip(rows, stats.holm([r[key]["p"] for r in rows]), strict=True):
            row[key]["p_holm"] = float(adjusted)
    for row in rows:
        row["verdict"] = verdict(row["difference"], row["equivalence"], alpha, pair_of(row))
    pairs = list(dict.fromkeys(pair_of(r) for r in rows)) or [KINDS]
    several = pairs != [KINDS]
    return {v: sum(counted(r, several) == v for r in rows) for v in verdicts_of(pairs)}


def summarise(result: dict[str, Any], margin: float = EQUIVALENCE_MARGIN) -> dict[str, Any]:
    """Everything the docs quote from a compact pool result: per budget and panel each kind's
    pool margin and return over runs, hierarchical minus flat with its verdict (Holm over the
    budget's panels); the probability of improvement at the last budget; the head start; the
    cross-kind play per condition."""
    budgets = [str(b) for b in result["budgets"]]
    panels = _panels(result)
    kinds = kinds_of(result["runs"])
    pairs = pairs_of(kinds)

    def at(budget: str, predator: str, key: str) -> Callable[[Any], float]:
        return lambda r: pooled(r["pool"][budget], predator)[key]

    by_budget = []
    for budget in budgets:
        entry: dict[str, Any] = {"episodes": int(budget)}
        for key in ("margin", "return"):
            rows = [
                {
                    "condition": c,
                    "predator": p,
                    **{k: _values(result, c, p, k, at(budget, p, key)).tolist() for k in kinds},
                }
                for c, p in panels
            ]
            rows = pairwise(rows, pairs)
            entry[key] = {"counts": compare(rows, margin), "panels": rows}
        by_budget.append(entry)
    last = by_budget[-1]
    improvement: dict[str, Any] = {}
    for key in ("margin", "return"):
        by_pair = [
            {
                "pair": list(pair),
                **stats.improvement_interval(
                    [np.array(r[pair[0]]) for r in last[key]["panels"] if pair_of(r) == pair],
                    [np.array(r[pair[1]]) for r in last[key]["panels"] if pair_of(r) == pair],
                ),
            }
            for pair in pairs
        ]
        improvement[key] = {k: v for k, v in by_pair[0].items() if k != "pair"} if pairs == [KINDS] else by_pair

    span = np.log([int(b) for b in budgets])  # a log axis: the early budgets weigh as the late ones

    def area(predator: str) -> Callable[[Any], float]:
        def measure(r: dict[str, Any]) -> float:
            c = np.array([pooled(r["pool"][b], predator)["margin"] for b in budgets])
            return float(np.sum((c[1:] + c[:-1]) / 2 * np.diff(span)) / (span[-1] - span[0]))

        return measure

    speed = [
        {"condition": c, "predator": p, **{k: _values(result, c, p, k, area(p)).tolist() for k in kinds}}
        for c, p in panels
    ]
    speed = pairwise(speed, pairs)
    speed_counts = compare(speed, margin)
    return {
        "episodes": result["episodes"],
        "episode_noise": episode_noise(result),
        "cross_episodes": result["cross_episodes"],
        "seed": result["seed"],
        "equivalence_margin": margin,
        "pools": result["pools"],
        "seeds": {kind: sorted({r["seed"] for r in result["runs"] if r["kind"] == kind}) for kind in kinds},
        "budgets": by_budget,
        "improvement": improvement,
        "learning_speed": {"counts": speed_counts, "panels": speed},  # the head start (the key kept for readers)
        "cross_kind": cross_kind(result),
        "curves": curves(result),
    }


def episode_noise(result: dict[str, Any]) -> dict[str, Any]:
    """At the last budget, per panel and kind: the standard error a run's pool return carries from
    its episodes (its opponents' standard errors combined, root mean square over runs) beside the
    standard deviation of the pool return between runs; the medians and ranges over panels and
    kinds. Every run plays the same episodes, so much of that error is shared by all runs."""
    final = str(result["budgets"][-1])
    errors, spreads = [], []
    for condition, predator in _panels(result):
        for kind in kinds_of(result["runs"]):
            runs = [r for r in result["runs"] if (r["condition"], r["kind"]) == (condition, kind)]
            returns = np.array([pooled(r["pool"][final], predator)["return"] for r in runs])
            per_run = [
                np.sqrt(sum(e["stderr"][predator] ** 2 for e in r["pool"][final].values())) / len(r["pool"][final])
                for r in runs
            ]
            errors.append(float(np.sqrt(np.mean(np.square(per_run)))))
            spreads.append(float(returns.std(ddof=1)))
    return {
        "stderr": {"median": float(np.median(errors)), "range": [min(errors), max(errors)]},
        "between_runs_sd": {"median": float(np.median(spreads)), "range": [min(spreads), max(spreads)]},
        "cells": len(errors),
    }


def _condition_margin(evaluation: dict[str, Any]) -> float:
    """A run's margin against one prey, mean over the condition's predators."""
    return float(np.mean([v[0] - max(v[1], v[2]) for v in evaluation["panels"].values()]))


def cross_kind(result: dict[str, Any]) -> list[dict[str, Any]]:
    """Per condition, kind and other kind: the margin (mean over predators) against the run's own
    prey, against the prey of the other kind's run of the same seed, and against the pool, over
    runs; the change from own prey to the other kind's, paired by run."""
    rows: list[dict[str, Any]] = []
    final = str(result["budgets"][-1])
    kinds = kinds_of(result["runs"])
    for condition, kind, other_kind in [
        (c, k, o)
        for c in CONDITIONS
        if any(r["condition"] == c for r in result["runs"])
        for k in kinds
        for o in kinds
        if o != k
    ]:
        key = other_key(other_kind, len(kinds) - 1)
        runs = sorted(
            (r for r in result["runs"] if (r["condition"], r["kind"]) == (condition, kind)), key=lambda r: r["seed"]
        )
        runs = [r for r in runs if key in r["cross"]]
        if len(runs) < 2:
            continue
        own = np.array([_condition_margin(r["cross"]["own"]) for r in runs])
        other = np.array([_condition_margin(r["cross"][key]) for r in runs])
        pool = np.array(
            [np.mean([pooled(r["pool"][final], p)["margin"] for p in r["cross"]["own"]["panels"]]) for r in runs]
        )
        change = stats.paired_difference(other, own)
        rows.append(
            {
                "condition": condition,
                "kind": kind,
                **({} if len(kinds) == 2 else {"other_kind": other_kind}),
                "runs": len(runs),
                "own_prey": {"mean": float(own.mean()), "ci": stats.t_interval(own)},
                "other_kind_prey": {"mean": float(other.mean()), "ci": stats.t_interval(other)},
                "pool": {"mean": float(pool.mean()), "ci": stats.t_interval(pool)},
                "change": {k: change[k] for k in ("mean", "ci", "p_greater", "p_less")},
            }
        )
    two_sided = [min(1.0, 2 * min(r["change"]["p_greater"], r["change"]["p_less"])) for r in rows]
    for row, adjusted in zip(rows, stats.holm(two_sided) if rows else [], strict=True):
        row["change"]["p_holm"] = float(adjusted)  # the table is one family
    return rows


def curves(result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """Per condition and kind: the pool margin (mean over predators) at each budget, mean over
    runs and t-interval: the efficiency figure."""
    out: dict[str, dict[str, Any]] = {}
    budgets = [str(b) for b in result["budgets"]]
    for condition in [c for c in CONDITIONS if any(r["condition"] == c for r in result["runs"])]:
        for kind in kinds_of(result["runs"]):
            runs = [r for r in result["runs"] if (r["condition"], r["kind"]) == (condition, kind)]
            matrix = np.array(
                [
                    [
                        np.mean([pooled(r["pool"][b], p)["margin"] for p in r["pool"][b][FLEEING]["panels"]])
                        for b in budgets
                    ]
                    for r in runs
                ]
            )
            out.setdefault(condition, {})[kind] = {
                "episodes": [int(b) for b in budgets],
                "mean": matrix.mean(axis=0).tolist(),
                "ci": [stats.t_interval(matrix[:, i]) for i in range(len(budgets))],
            }
    return out


# --- tables --------------------------------------------------------------------------------------


def panels_markdown(rows: list[dict[str, Any]], what: str) -> str:
    """One budget's comparisons: each kind's mean ``what`` over runs, the first minus the second
    with its 95 % Welch interval and Holm p, the equivalence test's Holm p and the bound it
    reaches, and the verdict (hierarchical − flat alone: one column a kind, as before the residual
    kind; otherwise a row per comparison)."""
    if any("pair" in r for r in rows):
        lines = [
            f"| condition | predator | comparison | {what}: first | second | first − second [95 % Welch] | p (Holm) "
            "| equivalence p (Holm) | within ± (unadjusted) | verdict |",
            "|---|---|---|---:|---:|---:|---:|---:|---:|---|",
        ]
    else:
        lines = [
            f"| condition | predator | {what}: hierarchical | flat | hierarchical − flat [95 % Welch] | p (Holm) "
            "| equivalence p (Holm) | within ± (unadjusted) | verdict |",
            "|---|---|---:|---:|---:|---:|---:|---:|---|",
        ]
    for r in rows:
        d, e = r["difference"], r["equivalence"]
        first, second = pair_of(r)
        named = f" {first} − {second} |" if "pair" in r else ""
        lines.append(
            f"| {r['condition']} | {r['predator']} |{named} {r['means'][first]:+.3f} | {r['means'][second]:+.3f} "
            f"| {d['mean']:+.3f}{span_text(d['ci'])} | {p_text(d['p_holm'])} | {p_text(e['p_holm'])} "
            f"| {e['bound']:.3f} | **{r['verdict']}** |"
        )
    return "\n".join(lines) + "\n"


def counts_markdown(summary: dict[str, Any]) -> str:
    """The verdict counts at every budget, on the pool margin and on the pool return, and for
    the head start."""
    verdicts = list(summary["budgets"][-1]["return"]["counts"])
    lines = [
        "| budget (episodes) | measure | " + " | ".join(verdicts) + " |",
        "|---:|---|" + "---:|" * len(verdicts),
    ]
    for entry in summary["budgets"]:
        for key in ("margin", "return"):
            counts = entry[key]["counts"]
            lines.append(f"| {entry['episodes']} | pool {key} | " + " | ".join(str(counts[v]) for v in verdicts) + " |")
    counts = summary["learning_speed"]["counts"]
    counted = " | ".join(str(counts[v]) for v in verdicts)
    lines.append(f"| all budgets | head start (margin averaged over the budgets) | {counted} |")
    return "\n".join(lines) + "\n"


def improvement_markdown(summary: dict[str, Any]) -> str:
    """The probability of improvement of each kind over each other (the hierarchical predator over
    the flat one where those are the kinds)."""
    budget = summary["budgets"][-1]["episodes"]
    if all(isinstance(v, dict) for v in summary["improvement"].values()):
        lines = ["| compared on | P(hierarchical > flat) [95 % stratified bootstrap] | panels |", "|---|---:|---:|"]
        for key, poi in summary["improvement"].items():
            low, high = poi["ci"]
            interval = f"{poi['value']:.2f} [{low:.2f}, {high:.2f}]"
            lines.append(f"| pool {key}, {budget} episodes | {interval} | {poi['panels']} |")
        return "\n".join(lines) + "\n"
    lines = ["| compared on | P(first > second) [95 % stratified bootstrap] | panels |", "|---|---:|---:|"]
    for key, by_pair in summary["improvement"].items():
        for poi in by_pair:
            low, high = poi["ci"]
            interval = f"{poi['value']:.2f} [{low:.2f}, {high:.2f}]"
            first, second = poi["pair"]
            lines.append(f"| pool {key}, {budget} episodes, {first} > {second} | {interval} | {poi['panels']} |")
    return "\n".join(lines) + "\n"


def cross_markdown(rows: list[dict[str, Any]]) -> str:
    """Cross-kind play: the margin against the run's own prey, the other kind's prey and the pool."""
    lines = [
        "| condition | predators | runs | margin against own prey | against the other kind's prey | change "
        "[95 % t, paired by run] | p (Holm) | against the pool |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        kind = r["kind"] + (f" (prey of {r['other_kind']})" if "other_kind" in r else "")
        lines.append(
            f"| {r['condition']} | {kind} | {r['runs']} | {r['own_prey']['mean']:+.3f} "
            f"| {r['other_kind_prey']['mean']:+.3f} | {r['change']['mean']:+.3f}{span_text(r['change']['ci'])} "
            f"| {p_text(r['change']['p_holm'])} | {r['pool']['mean']:+.3f} |"
        )
    return "\n".join(lines) + "\n"


def markdown(summary: dict[str, Any]) -> str:
    """pool.md: every table the docs quote."""
    final = summary["budgets"][-1]
    noise = summary["episode_noise"]
    se, sd = noise["stderr"], noise["between_runs_sd"]
    noise_text = (
        f"At {final['episodes']} episodes a run's pool return carries a standard error of {se['median']:.3f} from its "
        f"episodes (median over panels and kinds; {se['range'][0]:.3f} to {se['range'][1]:.3f}); the runs of a kind "
        f"spread by a standard deviation of {sd['median']:.3f} ({sd['range'][0]:.3f} to {sd['range'][1]:.3f}). "
        "Every run plays the same episodes, so much of that error is common to all runs."
    )
    return "\n".join(
        [
            "## Verdicts by budget",
            "",
            counts_markdown(summary),
            noise_text,
            "",
            f"## Panels at {final['episodes']} episodes: the pool margin",
            "",
            panels_markdown(final["margin"]["panels"], "pool margin"),
            f"## Panels at {final['episodes']} episodes: the pool return",
            "",
            panels_markdown(final["return"]["panels"], "pool return"),
            "## Probability of improvement",
            "",
            improvement_markdown(summary),
            "## Head start: the pool margin averaged over the budgets (log-episode axis)",
            "",
            panels_markdown(summary["learning_speed"]["panels"], "mean pool margin"),
            "## Cross-kind play at the end of training",
            "",
            cross_markdown(summary["cross_kind"]),
        ]
    )


def write_report(result: dict[str, Any], out: Path) -> dict[str, Any]:
    """From a compact pool result: pool-report.json (every figure at full precision), pool.md and
    pool.png in ``out``; returns the summary."""
    from pursuit_bench.figures.plots import pool_png
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    summary = summarise(result)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "pool-report.json", json.dumps(summary, indent=2) + "\n")
    atomic_write_text(out / "pool.md", markdown(summary))
    atomic_write_bytes(out / "pool.png", pool_png(summary))
    return summary
