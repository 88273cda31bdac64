"""The rule study's report (REPRODUCTION.md, "Protocol of the rule study"): from the judged runs'
compact results (``results/rule-study/runs/``), the primary verdicts and every secondary measure,
as the protocol fixed them. ``pursuit-bench report results/rule-study`` writes them.

The same report serves a study of any number of kinds in the same per-run format (the residual
study, docs/residual.md): its comparisons (``pairs``, first − second) are one Holm family per
budget over every (panel, comparison); a run's panel is its ``setting`` where it has one (a
condition with obstacles), else its condition. Where the runs carry robustness ladders and the
residual kind's corrections, the report adds them (:func:`ladders`, :func:`corrections`).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.reports import pool, rule_study
from pursuit_bench.stats.text import p_text, span_text

KINDS = rule_study.KINDS
#: The rule study's one comparison.
PAIRS: list[tuple[str, str]] = [KINDS]


def setting_of(run: dict[str, Any]) -> str:
    """The panel's first half: the run's setting (its condition, with obstacles where it has them)."""
    return str(run.get("setting", run["condition"]))


def panels(runs: list[dict[str, Any]]) -> list[tuple[str, str]]:
    """Every (setting, predator) the runs hold, in the paper's order of conditions (without
    obstacles first)."""
    order = {setting_of(r): (list(CONDITIONS).index(r["condition"]), r.get("obstacles", 0)) for r in runs}
    seen = {
        (setting_of(r), p): None
        for r in runs
        for p in r["pool"][rule_study.last_budget(r)][rule_study.FLEEING]["panels"]
    }
    return sorted(seen, key=lambda k: (order[k[0]], k[1]))


def budgets(runs: list[dict[str, Any]]) -> list[str]:
    """The budgets every run was evaluated at, ascending."""
    common = set.intersection(*(set(r["pool"]) for r in runs))
    return sorted(common, key=int)


def _runs_of(runs: list[dict[str, Any]], setting: str, kind: str) -> list[dict[str, Any]]:
    return sorted((r for r in runs if (setting_of(r), r["kind"]) == (setting, kind)), key=lambda r: r["seed"])


def rows_of(
    runs: list[dict[str, Any]],
    measure: Callable[[dict[str, Any], str], float],
    kinds: tuple[str, ...] = KINDS,
    pairs: list[tuple[str, str]] = PAIRS,
) -> list[dict[str, Any]]:
    """One row per panel and comparison (:func:`pool.pairwise`; one per panel for the rule
    study): each kind's per-run values of ``measure(run, predator)``, by seed."""
    rows = [
        {"condition": c, "predator": p, **{k: [measure(r, p) for r in _runs_of(runs, c, k)] for k in kinds}}
        for c, p in panels(runs)
    ]
    return pool.pairwise(rows, pairs)


def head_start(run: dict[str, Any], predator: str, keys: list[str]) -> float:
    """A run's pool return averaged over the budgets on a log-episode axis (trapezoids over the span)."""
    x = np.log([int(b) for b in keys])
    y = np.array([rule_study.pooled(run["pool"][b], predator)["return"] for b in keys])
    return float(np.sum((y[1:] + y[:-1]) / 2 * np.diff(x)) / (x[-1] - x[0]))


def reliability(
    runs: list[dict[str, Any]],
    margin: float = rule_study.FAILURE_MARGIN,
    kinds: tuple[str, ...] = KINDS,
    pairs: list[tuple[str, str]] = PAIRS,
) -> list[dict[str, Any]]:
    """Per panel and kind: failed runs (pool margin at the last budget below ``margin``), their share
    with Wilson's interval; the difference of the shares for each comparison, Boschloo's test, Holm
    over the panels and comparisons (``difference`` for the rule study's one, else ``differences``)."""
    rows = []
    for condition, predator in panels(runs):
        row: dict[str, Any] = {"condition": condition, "predator": predator}
        for kind in kinds:
            mine = _runs_of(runs, condition, kind)
            count = sum(rule_study.failed(r, predator, margin) for r in mine)
            row[kind] = {
                "failed": count,
                "runs": len(mine),
                "share": count / len(mine),
                "ci": stats.wilson_interval(count, len(mine)),
            }
        row["differences"] = [
            {"pair": list(pair), **stats.share_difference(*_counts(row[pair[0]]), *_counts(row[pair[1]]))}
            for pair in pairs
        ]
        rows.append(row)
    tests = [d for r in rows for d in r["differences"]]
    for test, adjusted in zip(tests, stats.holm([d["p"] for d in tests]), strict=True):
        test["p_holm"] = float(adjusted)
    if pairs == PAIRS:  # the rule study's layout
        for row in rows:
            row["difference"] = {k: v for k, v in row.pop("differences")[0].items() if k != "pair"}
    return rows


def _counts(share: dict[str, Any]) -> tuple[int, int]:
    return share["failed"], share["runs"]


def improvement(rows: list[dict[str, Any]], seed: int = 0, resamples: int = stats.RESAMPLES) -> dict[str, Any]:
    """P(first kind's run > second kind's run) per panel and averaged over panels, with 95 %
    percentile intervals from resampling runs within a condition, jointly for its panels (a run's
    values in the condition's panels stay together); for rows of several comparisons, one such
    result per comparison (``pairs``)."""
    pairs = list(dict.fromkeys(pool.pair_of(r) for r in rows))
    if len(pairs) > 1:
        return {
            "pairs": [
                {"pair": list(p), **improvement([r for r in rows if pool.pair_of(r) == p], seed, resamples)}
                for p in pairs
            ]
        }
    rng = np.random.default_rng(seed)
    per_panel = np.zeros((resamples, len(rows)))
    first, second = pairs[0] if pairs else KINDS
    for condition in dict.fromkeys(r["condition"] for r in rows):
        index = [i for i, r in enumerate(rows) if r["condition"] == condition]
        h = np.array([rows[i][first] for i in index]).T  # (runs, panels)
        f = np.array([rows[i][second] for i in index]).T
        rh = h[rng.integers(0, len(h), (resamples, len(h)))]  # (resamples, runs, panels)
        rf = f[rng.integers(0, len(f), (resamples, len(f)))]
        for j, i in enumerate(index):
            per_panel[:, i] = stats.pairs_above(rh[:, :, j], rf[:, :, j])
    values = [stats.probability_of_improvement([np.array(r[first])], [np.array(r[second])]) for r in rows]

    def interval(draws: np.ndarray) -> list[float]:
        return [float(q) for q in np.quantile(draws, [0.025, 0.975])]

    return {
        "value": float(np.mean(values)),
        "ci": interval(per_panel.mean(axis=1)),
        "panels": [{"value": v, "ci": interval(per_panel[:, i])} for i, v in enumerate(values)],
        "resamples": resamples,
    }


def leave_one_out(
    runs: list[dict[str, Any]],
    final: str,
    margin: float,
    kinds: tuple[str, ...] = KINDS,
    pairs: list[tuple[str, str]] = PAIRS,
) -> dict[str, Any]:
    """Per panel (and comparison), the primary difference with each member of the population left
    out: its range; and, each left-out member's comparisons judged as one family, those whose
    verdict changes."""
    members = list(runs[0]["pool"][final])
    base = rows_of(runs, lambda r, p: rule_study.pooled(r["pool"][final], p)["return"], kinds, pairs)
    pool.compare(base, margin)
    out = [
        {
            "condition": r["condition"],
            "predator": r["predator"],
            **({"pair": r["pair"]} if "pair" in r else {}),
            "differences": {},
            "verdicts": {},
        }
        for r in base
    ]
    for member in members:

        def without(r: dict[str, Any], p: str, m: str = member) -> float:
            return rule_study.pooled(r["pool"][final], p, leave_out=m)["return"]

        rows = rows_of(runs, without, kinds, pairs)
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


def curves(runs: list[dict[str, Any]], keys: list[str], kinds: tuple[str, ...] = KINDS) -> dict[str, dict[str, Any]]:
    """Per setting and kind: the pool return (mean over the setting's predators) at each
    budget, mean over runs with its t-interval: the pool-return-by-budget figure."""
    out: dict[str, dict[str, Any]] = {}
    for condition in dict.fromkeys(c for c, _ in panels(runs)):
        for kind in kinds:
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
                "ci": [stats.t_interval(matrix[:, i]) for i in range(len(keys))],
            }
    return out


SeedRule = Callable[[list[dict[str, Any]]], int]
"""A study's seed rule: from one setting's judged runs so far, how many a kind it asks for."""


def seed_rule_of(about: dict[str, Any], kinds: tuple[str, ...] = KINDS) -> SeedRule | None:
    """The seed rule a study's marker file (``rule-study.json``) records, ``{"first", "step",
    "most"}`` over ``kinds`` (:func:`rule_study.seeds_wanted`), raised where the marker's
    ``seed_floor`` (``{setting: n}``) asks for at least n runs a kind (the residual study's
    plain settings hold as many as the rule study judged there); None where it records no rule;
    ValueError for another form."""
    if "seed_rule" not in about:
        return None
    rule, floors = about["seed_rule"], about.get("seed_floor", {})
    if (
        not isinstance(rule, dict)
        or sorted(rule) != ["first", "most", "step"]
        or not all(type(v) is int and v > 0 for v in rule.values())
        or rule["first"] > rule["most"]
    ):
        raise ValueError(f"seed_rule: expected positive integers first ≤ most, and step, got {rule!r}")
    if not isinstance(floors, dict) or not all(type(v) is int and v > 0 for v in floors.values()):
        raise ValueError(f"seed_floor: expected {{setting: a positive integer}}, got {floors!r}")

    def wanted(runs: list[dict[str, Any]]) -> int:
        floor = floors.get(setting_of(runs[0]), 0) if runs else 0
        return max(rule_study.seeds_wanted(runs, **rule, kinds=kinds), floor)

    return wanted


@dataclass(frozen=True)
class Study:
    """What a study folder's marker says its report is."""

    kinds: tuple[str, ...]
    """The kinds its runs are of."""
    pairs: list[tuple[str, str]]
    """The comparisons it tests, (first, second): first − second."""
    differs: float
    """How far a residual run's margin must lie from its hierarchical twin's to differ."""
    seed_rule: SeedRule | None
    """Its seed rule (:func:`seed_rule_of`), None where it records none."""
    settings: tuple[str, ...] = ()
    """The settings it names, in its order (none named: the rule study's marker)."""


def study_of(where: Path, stem: str = "rule-study") -> Study:
    """A study folder's marker (``<stem>.json``) read. The rule study's records a seed rule at
    most (its kinds and comparison are this module's); another study's names its kinds and
    comparisons. ValueError naming the marker where it is missing or of another form."""
    marker = where / f"{stem}.json"
    expected = "a seed rule if any" if stem == "rule-study" else "kinds and comparisons, and a seed rule if any"
    try:
        about = json.loads(marker.read_text())
        kinds, pairs, differs = KINDS, PAIRS, stats.EQUIVALENCE_MARGIN
        if stem != "rule-study":
            kinds, pairs = tuple(about["kinds"]), [(a, b) for a, b in about["comparisons"]]
            differs = float(about.get("differs", differs))
        return Study(kinds, pairs, differs, seed_rule_of(about, kinds), tuple(about.get("settings", {})))
    except OSError as error:
        raise ValueError(f"{marker}: cannot be read ({error.strerror or error})") from None
    except (ValueError, KeyError, TypeError, AttributeError) as error:
        raise ValueError(f"{marker}: expected {expected} ({error})") from None


def complete_settings(
    runs: list[dict[str, Any]], kinds: tuple[str, ...] = KINDS, seed_rule: SeedRule | None = None
) -> tuple[list[dict[str, Any]], dict[str, dict[str, int]]]:
    """The runs of the settings whose judged runs are complete so far (every kind holds the same
    seeds, two or more: a seed step fully trained and evaluated; and, given the study's
    ``seed_rule``, as many as it asks for), and the runs per kind of the others, which a study
    still running has not finished (with ``wanted``, the seed rule's count, where it asks for
    more): they are left out of every test."""
    seeds: dict[str, dict[str, set[int]]] = {}
    for r in runs:
        seeds.setdefault(setting_of(r), {k: set() for k in kinds}).setdefault(r["kind"], set()).add(r["seed"])
    done = {c for c, by in seeds.items() if len({frozenset(by[k]) for k in kinds}) == 1 and len(by[kinds[0]]) >= 2}
    waiting = {c: {k: len(by[k]) for k in kinds} for c, by in seeds.items() if c not in done}
    if seed_rule is not None:
        for c in sorted(done):
            held = len(seeds[c][kinds[0]])
            if (wanted := seed_rule([r for r in runs if setting_of(r) == c])) > held:
                done.discard(c)
                waiting[c] = {**{k: held for k in kinds}, "wanted": wanted}
    return [r for r in runs if setting_of(r) in done], waiting


def summarise(
    runs: list[dict[str, Any]],
    margin: float = stats.EQUIVALENCE_MARGIN,
    kinds: tuple[str, ...] = KINDS,
    pairs: list[tuple[str, str]] = PAIRS,
    differs: float = stats.EQUIVALENCE_MARGIN,
    seed_rule: SeedRule | None = None,
) -> dict[str, Any]:
    """Everything the study's report says, at full precision: the primary verdicts (pool return at
    the last budget; each comparison of ``pairs`` of ``kinds``, one Holm family a budget), and
    each secondary measure labelled as such; the ladders and corrections where the runs have them
    (``differs``: :func:`corrections`). Settings not complete (:func:`complete_settings`, by
    ``seed_rule`` where given) are left out and named."""
    if not runs:
        raise ValueError("no judged runs: expected runs/*.json.gz in the study's folder")
    runs, in_progress = complete_settings(runs, kinds, seed_rule)
    if not runs:
        raise ValueError(f"no setting has its judged runs of every kind yet (in progress: {in_progress})")
    protocols = {r.get("protocol") for r in runs}
    if len(protocols) != 1:
        raise ValueError(f"the runs were evaluated by different protocols {sorted(map(str, protocols))}: not mixed")
    builds = sorted({r["build"] for r in runs})
    keys = budgets(runs)
    final = keys[-1]

    def at(budget: str, key: str) -> Callable[[dict[str, Any], str], float]:
        return lambda r, p: rule_study.pooled(r["pool"][budget], p)[key]

    primary = rows_of(runs, at(final, "return"), kinds, pairs)
    counts = pool.compare(primary, margin)
    secondary_margin = rows_of(runs, at(final, "margin"), kinds, pairs)
    margin_counts = pool.compare(secondary_margin, margin)
    started = rows_of(runs, lambda r, p: head_start(r, p, keys), kinds, pairs)
    head_counts = pool.compare(started, margin)
    by_budget = []
    for budget in keys[:-1]:
        rows = rows_of(runs, at(budget, "return"), kinds, pairs)
        by_budget.append({"episodes": int(budget), "counts": pool.compare(rows, margin), "panels": rows})
    design = {} if (kinds, pairs) == (KINDS, PAIRS) else {"kinds": list(kinds), "comparisons": [list(p) for p in pairs]}
    extra: dict[str, Any] = {}
    if any("ladders" in r for r in runs):
        extra["ladders"] = ladders(runs)
    if any("corrections" in r for r in runs):
        extra["corrections"] = corrections(runs, final, differs)
    return {
        **design,
        "protocol": runs[0].get("protocol"),
        "builds": builds,
        "equivalence_margin": margin,
        "failure_margin": rule_study.FAILURE_MARGIN,
        "budgets": [int(b) for b in keys],
        "runs": {k: {c: len(_runs_of(runs, c, k)) for c in dict.fromkeys(setting_of(r) for r in runs)} for k in kinds},
        **({"in_progress": in_progress} if in_progress else {}),
        "primary": {"measure": f"pool return at {final} episodes", "counts": counts, "panels": primary},
        "secondary": {
            "margin": {"counts": margin_counts, "panels": secondary_margin},
            "reliability": reliability(runs, rule_study.FAILURE_MARGIN, kinds, pairs),
            "reliability_below_zero": reliability(runs, 0.0, kinds, pairs),
            "head_start": {"counts": head_counts, "panels": started},
            "budgets": by_budget,
            "improvement": improvement(primary),
            "leave_one_out": leave_one_out(runs, final, margin, kinds, pairs),
            **extra,
        },
        "curves": curves(runs, keys, kinds),
    }


def ladders(runs: list[dict[str, Any]], kinds: tuple[str, str] = ("residual", "hierarchical")) -> dict[str, Any]:
    """The robustness ladders (secondary): per ladder, setting and rung, each run's change of its
    margin from the unperturbed level, ``kinds[0]`` − ``kinds[1]`` paired by seed (paired t), one
    Holm family per ladder over its (setting, rung) cells."""
    out: dict[str, Any] = {}
    settings = list(dict.fromkeys(c for c, _ in panels(runs)))
    levels = list(dict.fromkeys(level for r in runs if "ladders" in r for level in r["ladders"]))
    for level in [v for v in levels if "=" in v]:
        ladder, rung = level.split("=", 1)
        for setting in settings:
            first, second = (
                {r["seed"]: r for r in _runs_of(runs, setting, k) if level in r.get("ladders", {})} for k in kinds
            )
            seeds = sorted(set(first) & set(second))
            if len(seeds) < 2:
                continue

            def change(run: dict[str, Any], level: str = level) -> float:
                return float(run["ladders"][level]["margin"] - run["ladders"]["none"]["margin"])

            a = np.array([change(first[s]) for s in seeds])
            b = np.array([change(second[s]) for s in seeds])
            d = stats.paired_difference(a, b)
            p = min(1.0, 2 * min(d["p_greater"], d["p_less"]))
            cell = {
                "setting": setting,
                "rung": float(rung),
                "seeds": seeds,
                "change": {kinds[0]: float(a.mean()), kinds[1]: float(b.mean())},
                "difference": {"mean": d["mean"], "ci": d["ci"], "p": p},
            }
            out.setdefault(ladder, {"pair": list(kinds), "cells": []})["cells"].append(cell)
    for family in out.values():
        for cell, adjusted in zip(
            family["cells"], stats.holm([c["difference"]["p"] for c in family["cells"]]), strict=True
        ):
            cell["difference"]["p_holm"] = float(adjusted)
    return out


def mean_turn(by_predator: dict[str, Any]) -> float | None:
    """How far a residual run turns the rule where it corrects it: the mean of |k| × 30° over the
    corrected states of all its predators (``analyze``'s counts of each correction), None if none."""
    used: dict[int, int] = {}
    for c in by_predator.values():
        for k, n in c["correction_by_distance"]["used"].items():
            used[int(k)] = used.get(int(k), 0) + int(n)
    corrected = {k: n for k, n in used.items() if k != 0 and n > 0}
    if not corrected:
        return None
    return 30.0 * sum(abs(k) * n for k, n in corrected.items()) / sum(corrected.values())


def corrections(runs: list[dict[str, Any]], final: str, differs: float) -> list[dict[str, Any]]:
    """Where and how much each residual run corrects the rule (secondary, descriptive): its pool
    margin and return at ``final`` (means over its predators) beside those of the hierarchical run
    of its seed, whether the margins differ by more than ``differs``, its share of corrected states
    and its share of states in chase (per predator)."""
    rows = []
    for setting in dict.fromkeys(c for c, _ in panels(runs)):
        hierarchical = {r["seed"]: r for r in _runs_of(runs, setting, "hierarchical")}
        for run in _runs_of(runs, setting, "residual"):
            if "corrections" not in run:
                continue
            predators = list(run["pool"][final][rule_study.FLEEING]["panels"])

            def pooled(r: dict[str, Any], predators: list[str] = predators) -> dict[str, float]:
                each = [rule_study.pooled(r["pool"][final], p) for p in predators]
                return {m: float(np.mean([e[m] for e in each])) for m in ("margin", "return")}

            twin = hierarchical.get(run["seed"])
            mine, theirs = pooled(run), None if twin is None else pooled(twin)
            row: dict[str, Any] = {
                "setting": setting,
                "seed": run["seed"],
                "margin": mine["margin"],
                "hierarchical_margin": None if theirs is None else theirs["margin"],
                "return": mine["return"],
                "hierarchical_return": None if theirs is None else theirs["return"],
                "corrected": {p: c["corrected"] for p, c in run["corrections"].items()},
                "in_chase": {p: c["p_chase"] for p, c in run["corrections"].items()},
                "turn": mean_turn(run["corrections"]),
                "by_distance": {p: c["correction_by_distance"] for p, c in run["corrections"].items()},
            }
            row["differs"] = (
                None if twin is None else abs(row["margin"] - row["hierarchical_margin"]) > differs + stats.TIE
            )
            rows.append(row)
    return rows


# --- tables -------------------------------------------------------------------------------------


def _title(pair: tuple[str, str]) -> str:
    return f"{pair[0]} − {pair[1]}"


def reliability_markdown(rows: list[dict[str, Any]]) -> str:
    if "difference" in rows[0]:  # the rule study's one comparison
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
    kinds = [k for k in rows[0] if k not in ("condition", "predator", "differences")]
    pairs = [tuple(d["pair"]) for d in rows[0]["differences"]]
    head = " | ".join(f"{k} failed [95 % Wilson]" for k in kinds)
    tests = " | ".join(f"{_title(p)} | p (Boschloo, Holm)" for p in pairs)
    lines = [f"| condition | predator | {head} | {tests} |", "|---|---|" + "---:|" * (len(kinds) + 2 * len(pairs))]
    for r in rows:
        shares = " | ".join(f"{r[k]['failed']}/{r[k]['runs']}{span_text(r[k]['ci'])}" for k in kinds)
        differences = " | ".join(f"{d['difference']:+.2f} | {p_text(d['p_holm'])}" for d in r["differences"])
        lines.append(f"| {r['condition']} | {r['predator']} | {shares} | {differences} |")
    return "\n".join(lines) + "\n"


def leave_one_out_markdown(entry: dict[str, Any]) -> str:
    several = any("pair" in r for r in entry["panels"])
    what = "comparison | difference" if several else "hierarchical − flat"
    lines = [f"| condition | predator | verdict | {what}, one member left out: range | verdicts it changes to |"]
    lines.append("|---|---|---|" + ("---|" if several else "") + "---:|---|")
    for r in entry["panels"]:
        low, high = r["range"]
        named = f" {_title(r['pair'])} |" if several else ""
        lines.append(
            f"| {r['condition']} | {r['predator']} | {r['verdict']} |{named} {low:+.3f} to {high:+.3f} "
            f"| {', '.join(r['changes']) or '—'} |"
        )
    return "\n".join(lines) + "\n"


def improvement_markdown(poi: dict[str, Any], rows: list[dict[str, Any]]) -> str:
    if "pairs" in poi:
        return "\n".join(
            improvement_markdown(p, [r for r in rows if list(pool.pair_of(r)) == p["pair"]]) for p in poi["pairs"]
        )
    first, second = pool.pair_of(rows[0]) if rows else KINDS
    lines = [f"| panel | P({first} run > {second} run) [95 %, runs resampled within condition] |", "|---|---:|"]
    lines.append(f"| all panels | {poi['value']:.2f}{span_text(poi['ci'], 2)} |")
    for row, p in zip(rows, poi["panels"], strict=True):
        lines.append(f"| {row['condition']} {row['predator']} | {p['value']:.2f}{span_text(p['ci'], 2)} |")
    return "\n".join(lines) + "\n"


def ladders_markdown(families: dict[str, Any]) -> str:
    lines = []
    for ladder, family in families.items():
        a, b = family["pair"]
        lines += [
            f"{ladder} (one Holm family of {len(family['cells'])}):",
            "",
            f"| setting | rung | seeds | {a}: change of margin | {b}: change of margin "
            f"| {a} − {b} [95 % t, paired by seed] | p (Holm) |",
            "|---|---:|---:|---:|---:|---:|---:|",
        ]
        for c in family["cells"]:
            d = c["difference"]
            lines.append(
                f"| {c['setting']} | {c['rung']:g} | {len(c['seeds'])} | {c['change'][a]:+.3f} | {c['change'][b]:+.3f} "
                f"| {d['mean']:+.3f}{span_text(d['ci'])} | {p_text(d['p_holm'])} |"
            )
        lines.append("")
    return "\n".join(lines)


def corrections_markdown(rows: list[dict[str, Any]], differs: float) -> str:
    lines = [
        f"| setting | seed | residual pool margin | hierarchical's, same seed | differs by more than {differs} "
        "| states corrected (per predator) | mean turn where corrected |",
        "|---|---:|---:|---:|---|---|---:|",
    ]
    for r in sorted(rows, key=lambda r: (not r["differs"], r["setting"], r["seed"])):
        twin = "—" if r["hierarchical_margin"] is None else f"{r['hierarchical_margin']:+.3f}"
        shares = ", ".join(f"{v:.1%}" for v in r["corrected"].values())
        turn = "—" if r.get("turn") is None else f"{r['turn']:.0f}°"
        lines.append(
            f"| {r['setting']} | {r['seed']} | {r['margin']:+.3f} | {twin} | {r['differs']} | {shares} | {turn} |"
        )
    return "\n".join(lines) + "\n"


def counts_line(counts: dict[str, int]) -> str:
    return ", ".join(f"{n} {v}" for v, n in counts.items())


def in_progress_text(waiting: dict[str, dict[str, int]]) -> str:
    """The settings still running, each with its runs per kind: ``3p-low-individual (10
    hierarchical, 10 residual, 10 flat, of the 30 a kind its seed rule (and floor, where it has one) asks for); …``."""
    return "; ".join(f"{c} ({_held(by)})" for c, by in waiting.items())


def _held(by: dict[str, int]) -> str:
    """A setting in progress: its runs per kind, and the seed rule's count where it asks for more."""
    held = ", ".join(f"{n} {k}" for k, n in by.items() if k != "wanted")
    if "wanted" not in by:
        return held
    return held + f", of the {by['wanted']} a kind its seed rule (and floor, where it has one) asks for"


def markdown(summary: dict[str, Any], differs: float = stats.EQUIVALENCE_MARGIN) -> str:
    """The report: the primary verdicts first, then each secondary measure, labelled."""
    final = summary["budgets"][-1]
    s = summary["secondary"]
    budget_lines = [f"- {b['episodes']} episodes: {counts_line(b['counts'])}" for b in s["budgets"]]
    pairs = [tuple(p) for p in summary.get("comparisons", PAIRS)]
    compared = ", ".join(_title(p) for p in pairs)
    tests = len(summary["primary"]["panels"])
    family = f"{tests} panels" if pairs == PAIRS else f"{tests} tests: every panel and comparison"
    extra = []
    if "ladders" in s:
        extra += [
            "## Secondary: the robustness ladders (change of margin, paired by seed)",
            "",
            ladders_markdown(s["ladders"]),
        ]
    if "corrections" in s:
        extra += [
            "## Secondary: where the residual predator corrects the rule (descriptive)",
            "",
            corrections_markdown(s["corrections"], differs),
        ]
    if summary.get("in_progress"):
        waiting = in_progress_text(summary["in_progress"])
        extra_top = [f"**Not yet judged** (their runs are still being trained or evaluated; left out): {waiting}.", ""]
    else:
        extra_top = []
    return "\n".join(
        [
            *extra_top,
            f"## Primary: the pool return at {final} episodes, {compared}",
            "",
            f"{counts_line(summary['primary']['counts'])} (Welch, Holm over "
            f"{family}, "
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
            *extra,
        ]
    )


def write_report(
    where: Path,
    out: Path,
    stem: str = "rule-study",
    kinds: tuple[str, ...] = KINDS,
    pairs: list[tuple[str, str]] = PAIRS,
    differs: float = stats.EQUIVALENCE_MARGIN,
    seed_rule: SeedRule | None = None,
) -> dict[str, Any]:
    """From the study's folder (``runs/*.json.gz``): ``<stem>-report.json``, ``<stem>.md`` and
    ``<stem>.png`` in ``out`` (rule-study-…, or a study of ``kinds`` compared by ``pairs``), and
    where the runs hold a residual kind's corrections ``<stem>-corrections.png``; returns the summary."""
    from pursuit_bench.figures.plots import corrections_png, pool_png
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    runs = rule_study.read_runs(where / "runs")
    if not runs:
        raise ValueError(f"{where}: no judged runs yet (expected {where / 'runs'}/*.json.gz)")
    summary = summarise(runs, kinds=kinds, pairs=pairs, differs=differs, seed_rule=seed_rule)
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / f"{stem}-report.json", json.dumps(summary, indent=2) + "\n")
    atomic_write_text(out / f"{stem}.md", markdown(summary, differs))
    held = {c: sorted({by[c] for by in summary["runs"].values()}) for c in summary["curves"]}
    figure = {
        "curves": summary["curves"],
        "titles": {c: f"{c} ({'/'.join(map(str, n))} runs a kind)" for c, n in held.items()},
        "runs_label": "the runs a kind in each panel's title",
        "opponents": "the population",
        "budgets": [{"episodes": b} for b in summary["budgets"]],
    }
    atomic_write_bytes(out / f"{stem}.png", pool_png(figure, measure="pool return"))
    if corrected := summary["secondary"].get("corrections"):
        atomic_write_bytes(out / f"{stem}-corrections.png", corrections_png(corrected, differs))
    return summary
