"""The budget study's report (issue 63; studies/budget/PROTOCOL.md, fixed before any judged run was
evaluated): what ``pursuit-bench report results/budget-study`` writes from the study's compact
results (``runs/*.json.gz``, format ``budget-study-run-1``, written by studies/budget/evaluate.py).

Primary: the pool return at 10^6 episodes against the 10^6-episode population, hierarchical −
flat per panel (Welch), the two one-sided tests within ±0.05, Holm over the 6 panels, the four
verdicts. Secondary, each labelled: the same at every other budget (each budget its own family),
against the 15,000-episode population, the pool margin, failure shares, the paper's own
comparison at 10^6 with the strict count per seed, the prey's wall rate against budget.

A condition enters once both kinds hold all 10 judged seeds. **The families are the protocol's
6 panels**: until every condition is in, each comparison is given with its own interval and
unadjusted p, and no verdict and no Holm-adjusted p are written (a family tested in part is not
the protocol's family).
"""

from __future__ import annotations

import gzip
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.reports import pool, reproduction, rule_report, rule_study

FORMAT = "budget-study-run-1"
MARKER = "budget-study.json"
#: The study's conditions (PROTOCOL.md, "Question"), in the order of the rule study's verdicts.
CONDITIONS = ("3p-low-shared", "2p-high-shared", "1p-high")
KINDS = rule_study.KINDS
SEEDS = tuple(range(10))
BUDGETS = (15_000, 50_000, 150_000, 500_000, 1_000_000)
PANELS = 6  # 3 + 2 + 1 predators
#: The failure margins (PROTOCOL.md, secondary 4): the rule study's, and below zero as the check.
FAILURE_MARGINS = (rule_study.FAILURE_MARGIN, 0.0)


#: What every judged run's compact result must hold (PROTOCOL.md, "Evaluation"): a file made with
#: other settings (the evaluation script's trial options) is refused, not averaged in.
SETTINGS = {"protocol": "crn-1", "episodes": 60, "eval_seed": 12345, "budgets": list(BUDGETS)}
PAPER_EPISODES = 1000
MEMBERS = 9  # FleeingPrey and 8 learned prey a population
#: The same judged runs' first parts played by the paper's protocol at 15,000 episodes
#: (``studies/budget/run.py --paper-first``; added after the protocol, descriptive: PLAN.md,
#: "Fig. 2 at 15,000 episodes"), so that Fig. 2 at 10^6 stands beside the same runs' at 15,000,
#: measured by the same evaluation.
FIRST_PARTS = "paper-15000"
FIRST_PART_FORMAT = "budget-study-paper-1"
VARIANTS = ("trained", "always_chase", "always_stalk")


def read_runs(where: Path) -> list[dict[str, Any]]:
    """Every compact result under ``where/runs``, checked against the protocol's settings: its
    format, name, condition, kind, seed (0–9, each run once), evaluation settings, budgets and
    population size, one training build for all; ValueError naming the file otherwise."""
    runs = []
    for path, run in _judged_files(where / "runs", FORMAT):
        wrong = [k for k, v in SETTINGS.items() if run.get(k) != v]
        if wrong or run["paper"].get("episodes") != PAPER_EPISODES:
            raise ValueError(f"{path}: not the protocol's evaluation ({', '.join(wrong) or 'paper episodes'} differ)")
        if any(len(run["same_budget"][str(b)]) != MEMBERS for b in BUDGETS):
            raise ValueError(f"{path}: a population of other than {MEMBERS} members")
        runs.append(run)
    builds = {r["build"] for r in runs}
    if len(builds) > 1:
        raise ValueError(f"{where}: runs trained by {len(builds)} builds ({', '.join(sorted(builds))}): not mixed")
    return runs


def read_first_parts(where: Path) -> list[dict[str, Any]]:
    """The first parts' compact results under ``where/paper-15000`` (none where the folder is
    absent), each checked: its format, run, budget and evaluation; ValueError naming the file."""
    parts = []
    for path, run in _judged_files(where / FIRST_PARTS, FIRST_PART_FORMAT):
        if (run.get("budget"), run.get("protocol"), run.get("eval_seed")) != (
            BUDGETS[0],
            SETTINGS["protocol"],
            SETTINGS["eval_seed"],
        ):
            raise ValueError(
                f"{path}: not a first part of {BUDGETS[0]:,} episodes played by {SETTINGS['protocol']}, "
                f"seed {SETTINGS['eval_seed']}"
            )
        if run["paper"].get("episodes") != PAPER_EPISODES:
            raise ValueError(f"{path}: not the paper's protocol ({PAPER_EPISODES} episodes a variant)")
        parts.append(run)
    return parts


def _judged_files(folder: Path, form: str) -> list[tuple[Path, dict[str, Any]]]:
    """Every compact result in ``folder`` (none where it is absent) with its path, its identity
    checked: format ``form``, a judged run of the study (its conditions, kinds, seeds 0–9), named
    after its run, each run once; ValueError naming the file otherwise."""
    out, seen = [], set()
    for path in sorted(folder.glob("*.json.gz")):
        with gzip.open(path, "rt") as file:
            run = json.load(file)
        key = (run.get("condition"), run.get("kind"), run.get("seed"))
        if run.get("format") != form:
            raise ValueError(f"{path}: format {run.get('format')!r}, expected {form!r}")
        if key[0] not in CONDITIONS or key[1] not in KINDS or key[2] not in SEEDS:
            raise ValueError(f"{path}: {key} is not a judged run of the study (its conditions, kinds, seeds 0–9)")
        if path.name != f"{key[0]}-{key[1]}-seed{key[2]}.json.gz" or key in seen:
            raise ValueError(f"{path}: named otherwise than its run {key}, or a second file of it")
        seen.add(key)
        out.append((path, run))
    return out


def fig2(runs: list[dict[str, Any]], first_parts: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The paper's Fig. 2 of the judged runs at 15,000 episodes (their first parts) and at 10^6:
    per kind and panel, at each budget, each variant's mean over the runs, its t-interval and the
    runs' values (the fixed modes played with each run's own co-trained prey). Where a condition's
    first parts of a kind are in, both budgets hold the same runs, those seeds; where none is, 10^6
    holds them all and 15,000 is absent. Descriptive: no test is made on it."""
    rows = []
    for kind in KINDS:
        for condition in CONDITIONS:
            early = sorted((r for r in first_parts if (r["condition"], r["kind"]) == (condition, kind)), key=_seed)
            late = sorted((r for r in runs if (r["condition"], r["kind"]) == (condition, kind)), key=_seed)
            if early:  # the same runs at both budgets
                shared = {r["seed"] for r in early} & {r["seed"] for r in late}
                early, late = ([r for r in held if r["seed"] in shared] for held in (early, late))
            mine = {BUDGETS[0]: early, BUDGETS[-1]: late}
            predators = sorted({p for held in mine.values() for r in held for p in r["paper"]["panels"]})
            for predator in predators:
                budgets: dict[str, dict[str, Any]] = {}
                for budget, held in mine.items():
                    if not held:
                        continue
                    budgets[str(budget)] = {"seeds": [r["seed"] for r in held]}
                    for variant in VARIANTS:
                        values = [float(r["paper"]["panels"][predator][variant]) for r in held]
                        budgets[str(budget)][variant] = {
                            "mean": float(np.mean(values)),
                            "ci": stats.t_interval(values),
                            "values": values,
                        }
                rows.append({"kind": kind, "condition": condition, "predator": predator, "budgets": budgets})
    return rows


def fig2_strict(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The paper's count per seed on Fig. 2's data, comparable across the budgets: per kind, over
    the panels drawn at both budgets (the same runs), for each seed at each budget, in how many of
    them the learned predator's mean is above both fixed modes' (a tie is no win). Descriptive."""
    both = (str(BUDGETS[0]), str(BUDGETS[-1]))
    out: dict[str, Any] = {}
    for kind in KINDS:
        out[kind] = {}
        for budget in both:
            panels = [r["budgets"][budget] for r in rows if r["kind"] == kind and all(b in r["budgets"] for b in both)]
            counts: dict[str, int] = {}
            for entry in panels:
                for i, seed in enumerate(entry["seeds"]):
                    above = above_both({v: entry[v]["values"][i] for v in VARIANTS})
                    counts[str(seed)] = counts.get(str(seed), 0) + int(above)
            out[kind][budget] = {
                "panels": len(panels),
                "per_seed": dict(sorted(counts.items(), key=lambda c: int(c[0]))),
            }
    return out


def above_both(cell: dict[str, float]) -> bool:
    """Whether a panel's learned predator (``trained``) is above both fixed modes (a tie is no win):
    the paper's count, one seed's panel."""
    return all(cell["trained"] > cell[b] + stats.TIE for b in ("always_chase", "always_stalk"))


def _seed(run: dict[str, Any]) -> int:
    return int(run["seed"])


def complete(runs: list[dict[str, Any]]) -> tuple[list[str], dict[str, dict[str, int]]]:
    """The conditions whose judged runs are all in (both kinds, seeds 0–9), and for the others the
    runs each kind holds so far."""
    done, waiting = [], {}
    for condition in CONDITIONS:
        held = {k: sorted(r["seed"] for r in runs if (r["condition"], r["kind"]) == (condition, k)) for k in KINDS}
        if all(tuple(seeds) == SEEDS for seeds in held.values()):
            done.append(condition)
        else:
            waiting[condition] = {k: len(seeds) for k, seeds in held.items()}
    return done, waiting


def evaluations(run: dict[str, Any], budget: int, population: str) -> dict[str, Any]:
    """A run's evaluation at ``budget`` per member: against the population of the same budget
    (``same``), or of the first budget (``first``; at the first budget they are one)."""
    if population == "first" and budget != BUDGETS[0]:
        return dict(run["first_population"][str(budget)])
    return dict(run["same_budget"][str(budget)])


def views(runs: list[dict[str, Any]], budgets: tuple[int, ...], population: str = "same") -> list[dict[str, Any]]:
    """The runs as the rule study's reports read them: ``pool`` holding the ``budgets``' evaluations."""
    return [
        {
            "kind": r["kind"],
            "seed": r["seed"],
            "condition": r["condition"],
            "pool": {str(b): evaluations(r, b, population) for b in budgets},
        }
        for r in runs
    ]


def curves(runs: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per condition and kind, the pool return (mean over the condition's predators) against the
    same-budget population at every budget, mean over runs with its t-interval: the figure's data."""
    drawn = rule_report.curves(views(runs, BUDGETS), [str(b) for b in BUDGETS])
    return {c: drawn[c] for c in CONDITIONS if c in drawn}  # the protocol's order, not the alphabet's


def judged(rows: list[dict[str, Any]], whole: bool, margin: float = stats.EQUIVALENCE_MARGIN) -> dict[str, Any]:
    """One family's rows (hierarchical and flat per-run values a panel) filled with the
    difference (Welch) and the equivalence test; Holm and the verdicts only for the whole family
    (``whole``), else marked interim."""
    if whole and len(rows) != PANELS:
        raise ValueError(f"the family has {len(rows)} panels, the protocol's {PANELS}")
    counts = pool.compare(rows, margin)
    if whole:
        return {"interim": False, "counts": counts, "panels": rows}
    for row in rows:  # a family tested in part: its Holm and verdicts are not the protocol's
        del row["difference"]["p_holm"], row["equivalence"]["p_holm"], row["verdict"]
    return {"interim": True, "panels": rows}


def family(runs: list[dict[str, Any]], budget: int, key: str, population: str, whole: bool) -> dict[str, Any]:
    """The panels' hierarchical − flat of the pool ``key`` (return or margin) at ``budget``."""
    measure: Callable[[dict[str, Any], str], float] = lambda r, p: rule_study.pooled(r["pool"][str(budget)], p)[key]  # noqa: E731
    return {"episodes": budget, **judged(rule_report.rows_of(views(runs, (budget,), population), measure), whole)}


def failures(runs: list[dict[str, Any]], budget: int, margin: float, whole: bool) -> list[dict[str, Any]]:
    """Failure shares at ``budget`` (a run fails in a panel when its pool margin there is below
    ``margin``): per panel and kind with Wilson's interval, Boschloo's test of the two shares;
    Holm over the panels only for the whole family."""
    rows = rule_report.reliability(views(runs, (budget,)), margin)
    if not whole:
        for row in rows:
            row["difference"].pop("p_holm", None)
    return rows


def paper(runs: list[dict[str, Any]], whole: bool, margin: float = stats.EQUIVALENCE_MARGIN) -> dict[str, Any]:
    """Secondary 5: at 10^6, each kind's learned predator against always-chase and always-stalk
    with its own co-trained prey (paired by seed), the panel's verdict (Holm over the kind's
    panels × 2 baselines, the whole family only), and the strict count per seed: in how many of
    the kind's panels the learned predator's mean is the highest of the three."""
    out: dict[str, Any] = {}
    for kind in KINDS:
        mine = sorted(
            (r for r in runs if r["kind"] == kind), key=lambda r: (CONDITIONS.index(r["condition"]), r["seed"])
        )
        panels = [
            (c, p)
            for c in CONDITIONS
            for p in sorted({p for r in mine if r["condition"] == c for p in r["paper"]["panels"]})
        ]
        rows = []
        for condition, predator in panels:
            cells = [r["paper"]["panels"][predator] for r in mine if r["condition"] == condition]
            paired = {
                b: stats.paired_difference([c["trained"] for c in cells], [c[b] for c in cells])
                for b in ("always_chase", "always_stalk")
            }
            rows.append({"condition": condition, "predator": predator, "paired": paired})
        if whole:  # REPRODUCTION.md's judgement of the paper's claim: Holm, then the panel's verdict
            reproduction.judge(rows, margin=margin)
        else:
            for compared in (c for row in rows for c in row["paired"].values()):
                compared["p_equivalent"] = stats.paired_equivalence(compared["differences"], margin)["p"]
        seeds = sorted({r["seed"] for r in mine})
        strict = {
            str(s): sum(
                above_both(r["paper"]["panels"][p]) for r in mine if r["seed"] == s for p in r["paper"]["panels"]
            )
            for s in seeds
        }
        out[kind] = {"panels": rows, "strict_count": strict, "of": len(panels)}
    return out


def wall_rates(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Secondary 6 (descriptive): the share of episodes whose prey left the arena (``left_area``,
    the trained variant's episodes), per condition, kind and budget: of the population's learned
    members (averaged over them, then over the runs, with a t-interval over the runs), and at 10^6
    of each run's co-trained prey (the paper's protocol's episodes)."""
    out: dict[str, Any] = {}
    for condition in CONDITIONS:
        for kind in KINDS:
            mine = [r for r in runs if (r["condition"], r["kind"]) == (condition, kind)]
            if not mine:
                continue
            by_budget = {}
            for budget in BUDGETS:
                values = [
                    float(
                        np.mean(
                            [
                                m["prey"]["left_area"]
                                for name, m in evaluations(r, budget, "same").items()
                                if name != rule_study.FLEEING
                            ]
                        )
                    )
                    for r in mine
                ]
                by_budget[str(budget)] = {
                    "mean": float(np.mean(values)),
                    "ci": stats.t_interval(values),
                    "runs": len(values),
                }
            own = [float(r["paper"]["prey"]["left_area"]) for r in mine]
            out.setdefault(condition, {})[kind] = {
                "population": by_budget,
                "own_prey_at_end": {"mean": float(np.mean(own)), "ci": stats.t_interval(own), "runs": len(own)},
            }
    return out


def summarise(runs: list[dict[str, Any]], first_parts: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """Everything the report says, at full precision, over the conditions complete so far;
    ``first_parts`` (:func:`read_first_parts`) give Fig. 2 its 15,000-episode side."""
    if not runs:
        raise ValueError("no judged runs: expected runs/*.json.gz in the study's folder")
    done, waiting = complete(runs)
    if not done:
        raise ValueError(f"no condition has its 10 judged runs of both kinds yet (so far: {waiting})")
    runs = [r for r in runs if r["condition"] in done]
    read_parts = len(first_parts or [])
    first_parts = [r for r in first_parts or [] if r["condition"] in done]
    if other := {r["build"] for r in first_parts} - {r["build"] for r in runs}:
        raise ValueError(f"first parts trained by {', '.join(sorted(other))}, not the judged runs' build")
    whole = len(done) == len(CONDITIONS)
    final = BUDGETS[-1]
    return {
        "study": "budget",
        "protocol": "studies/budget/PROTOCOL.md",
        "complete": done,
        "in_progress": waiting,
        "whole_family": whole,
        "builds": sorted({r["build"] for r in runs}),
        "evaluated_by": sorted({r["evaluated_by"] for r in runs}),
        "primary": {
            "measure": f"pool return at {final:,} episodes against the {final:,}-episode population",
            **family(runs, final, "return", "same", whole),
        },
        "secondary": {
            "budgets": [family(runs, b, "return", "same", whole) for b in BUDGETS[:-1]],
            "first_population": [family(runs, b, "return", "first", whole) for b in BUDGETS],
            "margin": [family(runs, b, "margin", "same", whole) for b in BUDGETS],
            "failures": {
                str(m): [{"episodes": b, "panels": failures(runs, b, m, whole)} for b in BUDGETS]
                for m in FAILURE_MARGINS
            },
            "paper": paper(runs, whole),
            "wall_rates": wall_rates(runs),
        },
        "curves": curves(runs),
        "fig2": (drawn := fig2(runs, first_parts)),
        "fig2_strict": fig2_strict(drawn),
        "first_parts": {
            "in": read_parts,
            "of": len(CONDITIONS) * len(KINDS) * len(SEEDS),
            "drawn": len(first_parts),
            "same_as_judged": sum(bool(r.get("same_as_judged")) for r in first_parts),
        },
    }


def _num(value: float | None, spec: str = "+.3f") -> str:
    return "–" if value is None or value != value else format(value, spec).replace("-", "−")


def _share(entry: dict[str, Any]) -> str:
    """A mean over runs with its t-interval and the number of runs."""
    low, high = entry["ci"] or [None, None]
    return f"{entry['mean']:.3f} [{_num(low, '.3f')}, {_num(high, '.3f')}] ({entry['runs']})"


def _p(value: float) -> str:
    return "<0.001" if value < 0.001 else f"{value:.3f}"


def family_markdown(entry: dict[str, Any]) -> list[str]:
    """A family's table: one row a panel, hierarchical − flat with its interval; the Holm columns
    and the verdict once the family is whole."""
    whole = not entry["interim"]
    head = "| panel | hierarchical | flat | hierarchical − flat [95 % CI] | p | equivalence p (±0.05) |"
    head += " p (Holm) | equivalence p (Holm) | verdict |" if whole else ""
    lines = [head, "|---|---:|---:|---:|---:|---:|" + ("---:|---:|---|" if whole else "")]
    for row in entry["panels"]:
        d = row["difference"]
        cells = [
            f"{row['condition']} {row['predator']}",
            _num(row["means"][KINDS[0]]),
            _num(row["means"][KINDS[1]]),
            f"{_num(d['mean'])} [{_num(d['ci'][0])}, {_num(d['ci'][1])}]",
            _p(d["p"]),
            _p(row["equivalence"]["p"]),
        ]
        if whole:
            cells += [_p(d["p_holm"]), _p(row["equivalence"]["p_holm"]), row["verdict"]]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def markdown(summary: dict[str, Any]) -> str:
    """The report: the primary measure first, then each secondary, labelled."""
    final = BUDGETS[-1]
    out = ["# The budget study: does the answer at 15,000 episodes hold at 10^6?", ""]
    running = [f"{c} ({n[KINDS[0]]} + {n[KINDS[1]]} of 10 + 10 runs)" for c, n in summary["in_progress"].items()]
    out += [
        f"Protocol: `{summary['protocol']}` (fixed before any judged run was evaluated). Conditions in: "
        f"{', '.join(summary['complete'])}" + (f"; still running: {', '.join(running)}" if running else "") + ".",
        "",
    ]
    if not summary["whole_family"]:
        out += [
            f"**Interim**: {len(summary['primary']['panels'])} of the protocol's {PANELS} panels. "
            "Each comparison is given with its own interval and unadjusted p; the Holm-adjusted p-values and "
            "the verdicts are written only once all 6 panels are in (a family tested in part is not the "
            "protocol's family).",
            "",
        ]
    out += [f"## Primary: {summary['primary']['measure']}", "", *family_markdown(summary["primary"]), ""]
    if summary["whole_family"]:
        out += ["Verdicts: " + ", ".join(f"{v} {n}" for v, n in summary["primary"]["counts"].items()) + ".", ""]
    second = summary["secondary"]
    for title, entries in (
        ("every other budget, against the same-budget population (pool return)", second["budgets"]),
        (
            "against the 15,000-episode population (pool return; comparable with the rule study)",
            second["first_population"],
        ),
        ("the pool margin (pool return − the better fixed mode), against the same-budget population", second["margin"]),
    ):
        out += [f"## Secondary: {title}", ""]
        for entry in entries:
            out += [f"At {entry['episodes']:,} episodes:", "", *family_markdown(entry), ""]
    out += ["## Secondary: failure shares (a run fails in a panel when its pool margin is below the margin)", ""]
    for margin, entries in second["failures"].items():
        out += [
            f"Margin {_num(float(margin), '+.2f')}:",
            "",
            "| episodes | panel | hierarchical failed | flat failed | Boschloo p |"
            + (" p (Holm) |" if summary["whole_family"] else ""),
            "|---:|---|---:|---:|---:|" + ("---:|" if summary["whole_family"] else ""),
        ]
        for entry in entries:
            for row in entry["panels"]:
                h, f, d = row[KINDS[0]], row[KINDS[1]], row["difference"]
                cells = [f"{entry['episodes']:,}", f"{row['condition']} {row['predator']}"]
                cells += [f"{s['failed']} of {s['runs']} [{s['ci'][0]:.2f}, {s['ci'][1]:.2f}]" for s in (h, f)]
                cells += [_p(d["p"])] + ([_p(d["p_holm"])] if "p_holm" in d else [])
                out.append("| " + " | ".join(cells) + " |")
        out.append("")
    out += [
        f"## Secondary: the paper's own comparison at {final:,} episodes (own co-trained prey, 1000 episodes "
        "a variant)",
        "",
    ]
    for kind, entry in second["paper"].items():
        out += [
            f"{kind.capitalize()}: strict count per seed (of {entry['of']} panels): "
            + ", ".join(f"seed {s}: {n}" for s, n in entry["strict_count"].items())
            + ".",
            "",
        ]
        suffix = " (Holm)" if summary["whole_family"] else ""
        out += [
            f"| panel | − always-chase [95 % CI] | ahead, behind, equivalent p{suffix} | − always-stalk [95 % CI] "
            f"| ahead, behind, equivalent p{suffix} | verdict |",
            "|---|---:|---|---:|---|---|",
        ]
        for row in entry["panels"]:
            cells = [f"{row['condition']} {row['predator']}"]
            for baseline in ("always_chase", "always_stalk"):
                c = row["paired"][baseline]
                low, high = c["ci"] or [None, None]
                cells.append(f"{_num(c['mean'])} [{_num(low)}, {_num(high)}]")
                keys = [f"{k}_holm" if suffix else k for k in ("p_greater", "p_less", "p_equivalent")]
                cells.append(", ".join(_p(c[k]) for k in keys))
            cells.append(row.get("verdict", "– (interim)"))
            out.append("| " + " | ".join(cells) + " |")
        out.append("")
    out += fig2_markdown(summary["fig2"], summary["first_parts"])
    for kind, budgets in summary["fig2_strict"].items():
        panels = next(iter(budgets.values()))["panels"]
        said = [
            f"at {int(b):,} episodes " + ", ".join(f"seed {s}: {n}" for s, n in c["per_seed"].items())
            for b, c in budgets.items()
        ]
        out += [
            f"{kind.capitalize()}: of the {panels} panels played at both budgets, those where the learned predator "
            "is above both fixed modes, per seed: " + ("; ".join(said) if panels else "none yet") + ".",
            "",
        ]
    out += ["## Secondary: the prey's wall rate against budget (descriptive)", ""]
    out += [
        "| condition | predators | " + " | ".join(f"{b:,}" for b in BUDGETS) + " | own prey at 10^6 |",
        "|---|---|" + "---:|" * (len(BUDGETS) + 1),
    ]
    for condition, kinds in second["wall_rates"].items():
        for kind, entry in kinds.items():
            cells = [_share(entry["population"][str(b)]) for b in BUDGETS]
            out.append(f"| {condition} | {kind} | " + " | ".join(cells) + f" | {_share(entry['own_prey_at_end'])} |")
    out.append("")
    return "\n".join(out)


def fig2_markdown(rows: list[dict[str, Any]], parts: dict[str, int]) -> list[str]:
    """Fig. 2's table: per kind and panel, each variant's mean [95 % t-interval] over the runs at
    15,000 episodes (the first parts) and at 10^6, with the runs each holds."""
    first, final = (str(b) for b in (BUDGETS[0], BUDGETS[-1]))
    out = [
        f"## The paper's Fig. 2 of the same runs at {BUDGETS[0]:,} and {BUDGETS[-1]:,} episodes (descriptive; added "
        "after the protocol)",
        "",
        f"Each run against always-chase and always-stalk with its own co-trained prey, {PAPER_EPISODES} episodes "
        f"a variant (seed {SETTINGS['eval_seed']}); at {BUDGETS[0]:,} episodes the runs' first parts, trained "
        "again by the pinned build and replayed to the bit against the rule study's result, then played by the "
        f"same protocol (`run.py --paper-first`; {parts['in']} of the {parts['of']} first parts in, "
        f"{parts['drawn']} drawn: those of the conditions whose judged runs are all in; {parts['same_as_judged']} "
        "of them also checked to the bit against the judged run's own result at that budget, committed before "
        "they were played). Where a kind's first parts are in, both budgets hold those runs only. Mean [95 % "
        "t-interval] over the runs.",
        "",
        "| kind | panel | episodes | runs | trained | always-chase | always-stalk |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        for budget in (first, final):
            if budget not in row["budgets"]:
                cells = ["not yet played", "", "", ""]
            else:
                entry = row["budgets"][budget]
                cells = [str(len(entry["seeds"]))]
                for variant in VARIANTS:
                    v = entry[variant]
                    low, high = v["ci"] or [None, None]
                    cells.append(f"{_num(v['mean'])} [{_num(low)}, {_num(high)}]")
            head = [row["kind"], f"{row['condition']} {row['predator']}", f"{int(budget):,}"]
            out.append("| " + " | ".join(head + cells) + " |")
    return [*out, ""]


def write_report(where: Path, out: Path) -> dict[str, Any]:
    """From the study's folder: ``budget-study-report.json`` (full precision), ``budget-study.md``,
    ``budget-study.png`` (pool return against budget, log axis, per kind per condition) and
    ``budget-fig2.png`` (the paper's Fig. 2 of the same runs at 15,000 and 10^6 episodes)."""
    from pursuit_bench.figures.plots import fig2_budgets_png, pool_png

    summary = summarise(read_runs(where), read_first_parts(where))
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "budget-study-report.json", json.dumps(summary, indent=1) + "\n")
    atomic_write_text(out / "budget-study.md", markdown(summary))
    figure = {
        "curves": summary["curves"],
        "runs_label": f"{len(SEEDS)} a kind",
        "opponents": "the population trained as long",
        "budgets": [{"episodes": b} for b in BUDGETS],
    }
    atomic_write_bytes(out / "budget-study.png", pool_png(figure, measure="pool return"))
    atomic_write_bytes(
        out / "budget-fig2.png", fig2_budgets_png(summary["fig2"], [str(BUDGETS[0]), str(BUDGETS[-1])], PAPER_EPISODES)
    )
    return summary
