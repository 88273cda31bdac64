"""Robustness of trained predators (``pursuit-bench robust``, docs/robustness.md): the paper's
protocol under a ladder of perturbations (:mod:`pursuit_bench.env.perturbations`), and cross-play
over a sweep's seeds (each seed's predators against every seed's prey).

The quantity throughout is a run's **margin**: per predator, its return as trained minus the
better of always-chase and always-stalk put in its place (same perturbed episodes, same prey),
averaged over the condition's predators. Over seeds it gets a t-interval
(:mod:`pursuit_bench.stats`); its change under a perturbation is paired by seed.
Runs are the unit of every test (:func:`families`): a change is tested within its kind (paired
t), hierarchical against flat by Welch's test on the two kinds' changes (other runs, other prey),
each table's comparisons as one family corrected by Holm, and "holds" only where two one-sided
tests show it within :data:`EQUIVALENCE_MARGIN`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.agents.names import WITH_AND_WITHOUT_RULE
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.perturbations import Perturbations
from pursuit_bench.stats.text import p_text, span_text

#: The strengths tried per perturbation, weakest first; the strongest of each costs
#: always-chase a clear part of its return (docs/robustness.md measures how much).
LADDERS: dict[str, tuple[float, ...]] = {
    "obs-noise": (0.02, 0.05, 0.1),
    "delay": (1, 3, 6),
    "act-noise": (0.1, 0.3, 0.6),
    "damping": (1.5, 2.0, 3.0),
    "predator-accel": (0.9, 0.75, 0.5),
    "prey-accel": (1.1, 1.25, 1.5),
    "obstacles": (2, 4, 6),
}
#: The unperturbed level's name.
NONE = "none"


def perturbation(name: str, value: float) -> Perturbations:
    """One rung of a ladder as :class:`Perturbations`."""
    return Perturbations.parse([f"{name}={value:g}"])


def margins(result: dict[str, Any]) -> dict[str, Any]:
    """From an evaluation (``evaluate_agents``): the run's margin over the better baseline
    (mean over predators), and each variant's mean return over predators."""
    panels = result["panels"]
    per_predator = [p["trained"] - max(p["always_chase"], p["always_stalk"]) for p in panels]
    return {
        "margin": float(np.mean(per_predator)),
        **{key: float(np.mean([p[key] for p in panels])) for key in ("trained", "always_chase", "always_stalk")},
        "capture_rate": result["capture_rate"],
    }


def _evaluate(
    predators_from: Path | str, prey_from: Path | str, perturbations: Perturbations, episodes: int, seed: int
) -> dict[str, Any]:
    """The protocol with the predators of one run (or shipped condition) and the prey of
    another (the same for self-play), under ``perturbations``."""
    import torch

    from pursuit_bench.training.evaluate import evaluate_agents

    torch.set_num_threads(1)
    config, agents, _ = _described(predators_from)
    if prey_from != predators_from:
        other_config, other, _ = _described(prey_from)
        check_opponents(config, other_config, retrainable=not isinstance(predators_from, str))
        agents = {**agents, "prey_0": other["prey_0"]}
    if perturbations.obstacles and config.task_options.get("obstacles"):
        raise ValueError("obstacles=N: for agents trained without obstacles")
    result = evaluate_agents(
        config.condition,
        agents,
        episodes=episodes,
        seed=seed,
        perturbations=perturbations,
        prey_check=False,
        **config.protocol,
    )
    return margins(result)


def _described(source: Path | str) -> tuple[Any, dict[str, Any], dict[str, Any]]:
    from pursuit_bench import pretrained
    from pursuit_bench.training import runs

    if isinstance(source, str):
        return pretrained.described(source)
    return runs.described(source)


def check_opponents(
    config: Any, other: Any, mine: str = "the predators' run", theirs: str = "the prey's run", retrainable: bool = True
) -> None:
    """ValueError unless agents trained by ``config`` and ``other`` can meet: the same number of
    predators and the same observation (wall features, obstacles); the message names what
    differs and the training options that would match ``theirs`` (``retrainable``), or, for
    agents a user cannot train again (the shipped ones), the opponents that would match ``mine``."""
    ours, others = CONDITIONS[config.condition], CONDITIONS[other.condition]
    if ours.n_predators != others.n_predators:
        hint = (
            f"train {mine} with --condition {other.condition} to meet {theirs}"
            if retrainable
            else f"choose opponents with {ours.n_predators} predator(s), e.g. a run of --condition {config.condition}"
        )
        raise ValueError(
            f"opponents: {mine} ({config.condition}) has {ours.n_predators} predators and {theirs} "
            f"({other.condition}) {others.n_predators}; the prey's observation differs ({hint})"
        )
    target = other if retrainable else config  # whose options the other side would need
    differ = []
    if config.agent.wall_features != other.agent.wall_features:
        flag = "--wall-features" if target.agent.wall_features else "--no-wall-features"
        on = {True: "on", False: "off"}
        differ.append(
            (
                f"wall features {on[config.agent.wall_features]} in {mine}, {on[other.agent.wall_features]} in "
                f"{theirs}",
                flag + (" (the reproduction preset's)" if target.agent.wall_features else ""),
            )
        )
    if config.task_options != other.task_options:
        wanted = target.task_options.get("obstacles", 0)
        differ.append(
            (
                f"obstacles {config.task_options or 'none'} in {mine}, {other.task_options or 'none'} in {theirs}",
                f"--obstacles {wanted}"
                + (f" --obstacle-radius {target.task_options['obstacle_radius']:g}" if wanted else ""),
            )
        )
    if differ:
        options = " ".join(option for _, option in differ)
        hint = f"train with {options} to meet {theirs}" if retrainable else f"choose opponents trained with {options}"
        raise ValueError(
            "opponents: the agents observe differently: " + "; ".join(what for what, _ in differ) + f" ({hint})"
        )


def _jobs(
    sources: list[dict[str, Any]], episodes: int, seed: int, crossplay: bool
) -> list[tuple[str, tuple[Any, ...]]]:
    jobs: list[tuple[str, tuple[Any, ...]]] = []
    for s in sources:
        trained_with_obstacles = bool(s["config"].task_options.get("obstacles"))
        jobs.append((f"{s['name']}|{NONE}", (s["source"], s["source"], Perturbations(), episodes, seed)))
        for name, levels in LADDERS.items():
            if name == "obstacles" and trained_with_obstacles:
                continue
            for value in levels:
                key = f"{s['name']}|{name}={value:g}"
                jobs.append((key, (s["source"], s["source"], perturbation(name, value), episodes, seed)))
    if crossplay:
        for s in sources:
            for o in sources:
                if o is not s and (s["condition"], s["kind"]) == (o["condition"], o["kind"]):
                    args = (s["source"], o["source"], Perturbations(), episodes, seed)
                    jobs.append((f"{s['name']}|vs|{o['name']}", args))
    return jobs


def run(
    sources: list[dict[str, Any]],
    out: Path,
    *,
    episodes: int,
    seed: int,
    workers: int = 1,
    progress: Callable[[int, int], None] = lambda done, total: None,
) -> dict[str, Any]:
    """Evaluate every source (``name``, ``condition``, ``kind``, ``seed``, ``config``, ``source``:
    a run folder or a shipped condition) on every rung of :data:`LADDERS` and, between sources of
    one condition and kind, in cross-play; each evaluation is kept in ``out/robust-parts/`` as it
    finishes (a rerun goes on from there). Returns :func:`summarise`'s result."""
    from pursuit_bench.training.jobs import run_jobs

    jobs = _jobs(sources, episodes, seed, crossplay=True)
    stamp = {"episodes": episodes, "seed": seed}
    done = run_jobs(jobs, _evaluate, out / "robust-parts", stamp, workers=workers, progress=progress)
    return summarise(sources, done, episodes, seed)


def summarise(
    sources: list[dict[str, Any]], done: dict[str, dict[str, Any]], episodes: int, seed: int
) -> dict[str, Any]:
    """robust.json: every evaluation by run and level; per condition and kind, each rung's margin
    over seeds (t-interval) and its change from the unperturbed margin (paired by seed), and
    always-chase's return; the cross-play matrices with the generalisation gap; and the tests of
    :func:`families`, each family corrected by Holm."""
    by_run: dict[str, dict[str, Any]] = {}
    for key, result in done.items():
        name, level = key.split("|", 1)
        by_run.setdefault(name, {})[level] = result
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for s in sources:
        groups.setdefault((s["condition"], s["kind"]), []).append(s)
    summary: dict[str, Any] = {}
    crossplay: dict[str, Any] = {}
    for (condition, kind), members in groups.items():
        members = sorted(members, key=lambda s: s["seed"])
        plain = np.array([by_run[s["name"]][NONE]["margin"] for s in members])
        entry: dict[str, Any] = {
            NONE: {
                "margin": plain.mean().item(),
                "ci": stats.t_interval(plain),
                "values": plain.tolist(),
                "always_chase": float(np.mean([by_run[s["name"]][NONE]["always_chase"] for s in members])),
            }
        }
        for name, levels in LADDERS.items():
            rungs = []
            for value in levels:
                level = f"{name}={value:g}"
                if not all(level in by_run[s["name"]] for s in members):
                    continue
                margin = np.array([by_run[s["name"]][level]["margin"] for s in members])
                change = stats.paired_difference(margin, plain)
                chase = np.array([by_run[s["name"]][level]["always_chase"] for s in members])
                rungs.append(
                    {
                        "value": value,
                        "margin": margin.mean().item(),
                        "ci": stats.t_interval(margin),
                        "values": margin.tolist(),
                        "change": {k: change[k] for k in ("mean", "ci", "p_greater", "p_less")},
                        "always_chase": chase.mean().item(),
                    }
                )
            if rungs:
                entry[name] = rungs
        summary.setdefault(condition, {})[kind] = entry
        if len(members) > 1 and all(
            f"vs|{o['name']}" in by_run[s["name"]] for s in members for o in members if o is not s
        ):
            matrix = np.array(
                [[by_run[s["name"]][NONE if o is s else f"vs|{o['name']}"]["margin"] for o in members] for s in members]
            )
            held_out = np.array([np.delete(row, i).mean() for i, row in enumerate(matrix)])
            gap = stats.paired_difference(np.diag(matrix), held_out)
            crossplay.setdefault(condition, {})[kind] = {
                "seeds": [s["seed"] for s in members],
                "matrix": matrix.tolist(),
                "self_play": float(np.diag(matrix).mean()),
                "held_out": {"mean": held_out.mean().item(), "ci": stats.t_interval(held_out)},
                "gap": {k: gap[k] for k in ("mean", "ci", "p_greater", "p_less", "differences")},
            }
    return {
        "episodes": episodes,
        "seed": seed,
        "sources": [{k: s[k] for k in ("name", "condition", "kind", "seed")} for s in sources],
        "ladders": {name: list(levels) for name, levels in LADDERS.items()},
        "summary": summary,
        "crossplay": crossplay,
        "families": families(summary, crossplay),
        "runs": by_run,
    }


# --- the tests: families of comparisons, each corrected by Holm ---------------------------------

#: The predator kinds compared, in the order the tables print them.
KINDS = WITH_AND_WITHOUT_RULE
#: What the text may call a change (or margin) that is not there: within this much of zero in
#: return per episode, shown by two one-sided tests. The project's margin
#: (:data:`stats.EQUIVALENCE_MARGIN`: five captures in a hundred episodes, the pool study's).
EQUIVALENCE_MARGIN = stats.EQUIVALENCE_MARGIN
#: The families, in the order docs/robustness.md gives them: what each compares, and the words of
#: its verdicts for a difference below and above zero. Each family is corrected alone (Holm), its
#: differences and its equivalence tests separately, as the pool study's tables are.
FAMILIES: dict[str, dict[str, Any]] = {
    "margins": {
        "what": "each run's margin, unperturbed and at each perturbation's strongest rung, against zero "
        "(one-sample t over runs)",
        "words": ("below zero", "above zero"),
    },
    "changes": {
        "what": "the change of the margin at each perturbation's strongest rung, per condition and kind "
        "(paired t over runs)",
        "words": ("falls", "rises"),
    },
    "kinds": {
        "what": "hierarchical minus flat: the difference of the two kinds' changes at the strongest rung "
        "(Welch over runs)",
        "words": ("hierarchical lower", "hierarchical higher"),
    },
    "ladder": {
        "what": "the change of the margin at every rung, per condition and kind (paired t over runs)",
        "words": ("falls", "rises"),
    },
    "ladder kinds": {
        "what": "hierarchical minus flat: the difference of the two kinds' changes at every rung (Welch over runs)",
        "words": ("hierarchical lower", "hierarchical higher"),
    },
    "gaps": {
        "what": "the generalisation gap, self-play minus held-out margin, per condition and kind "
        "(paired t over the predators' runs)",
        "words": ("gains", "loses"),
    },
    "gap kinds": {
        "what": "hierarchical minus flat: the difference of the two kinds' generalisation gaps (Welch over runs)",
        "words": ("hierarchical lower", "hierarchical higher"),
    },
}


def _one_sample(values: np.ndarray, margin: float | None) -> dict[str, Any]:
    """The mean of per-run ``values`` (a margin, or a change paired within each run) against zero:
    its 95 % t-interval, the two-sided p of the t-test and, given ``margin``, the two one-sided
    tests of equivalence within it."""
    test = stats.paired_difference(values, np.zeros_like(values))
    out: dict[str, Any] = {
        "n": test["n"],
        "mean": test["mean"],
        "ci": test["ci"],
        "p": min(1.0, 2 * min(test["p_greater"], test["p_less"])),
    }
    if margin is not None:
        out["equivalence"] = stats.paired_equivalence(values, margin)
    return out


def _two_sample(ours: np.ndarray, theirs: np.ndarray, margin: float) -> dict[str, Any]:
    """``mean(ours) - mean(theirs)`` for two kinds' runs (independent: other runs, other prey):
    Welch's interval and two-sided p, and the two one-sided Welch tests of equivalence."""
    welch = stats.welch_difference(ours, theirs)
    return {
        "n": [len(ours), len(theirs)],
        "mean": welch["mean"],
        "ci": welch["ci"],
        "p": welch["p"],
        "equivalence": stats.equivalence(ours, theirs, margin),
    }


def correct(rows: list[dict[str, Any]], words: tuple[str, str], alpha: float = stats.ALPHA) -> dict[str, int]:
    """Holm over ``rows`` (one family): each row's two-sided ``p`` and, where it has one, its
    equivalence test's ``p``, adjusted apart (``p_holm``); then its verdict: ``words[0]`` or
    ``words[1]`` (below or above zero) when the adjusted two-sided p is at most ``2 alpha``, else
    ``equivalent`` when the adjusted equivalence p is at most ``alpha``, else ``not resolved``.
    Returns the verdict counts, with the number of rows whose unadjusted p is below ``2 alpha``."""
    for row, adjusted in zip(rows, stats.holm([r["p"] for r in rows]), strict=True):
        row["p_holm"] = float(adjusted)
    tested = [r for r in rows if "equivalence" in r]
    for row, adjusted in zip(tested, stats.holm([r["equivalence"]["p"] for r in tested]), strict=True):
        row["equivalence"]["p_holm"] = float(adjusted)
    for row in rows:
        equivalent = row["equivalence"]["p_holm"] if "equivalence" in row else None
        row["verdict"] = stats.difference_verdict(row["mean"], row["p_holm"], equivalent, words, alpha)
    counts = {v: sum(r["verdict"] == v for r in rows) for v in (*words, "equivalent", "not resolved")}
    return {"comparisons": len(rows), "uncorrected": sum(r["p"] < 2 * alpha for r in rows), **counts}


def families(
    summary: dict[str, Any], crossplay: dict[str, Any], margin: float = EQUIVALENCE_MARGIN
) -> dict[str, dict[str, Any]]:
    """Every comparison the text may lean on, in the families of :data:`FAMILIES`, each corrected
    by :func:`correct`: per family its rows (condition, kind or ``hierarchical − flat``,
    perturbation and rung, the test) and its counts. Runs are the unit: a margin's change is
    paired within each run, the two kinds' runs are independent (Welch). Only groups of two or
    more runs are tested."""
    rows: dict[str, list[dict[str, Any]]] = {name: [] for name in FAMILIES}
    for condition, by_kind in summary.items():
        tested = {k: by_kind[k] for k in KINDS if k in by_kind and len(by_kind[k][NONE]["values"]) > 1}
        for kind, e in tested.items():
            rows["margins"].append(
                {"condition": condition, "kind": kind, "perturbation": NONE, "value": None}
                | _one_sample(np.array(e[NONE]["values"]), None)
            )
        for name in LADDERS:
            for kind, e in tested.items():
                if name in e:
                    top = e[name][-1]
                    rows["margins"].append(
                        {"condition": condition, "kind": kind, "perturbation": name, "value": top["value"]}
                        | _one_sample(np.array(top["values"]), None)
                    )
            depth = max((len(e.get(name, [])) for e in tested.values()), default=0)
            for i in range(depth):
                changes: dict[str, np.ndarray] = {}
                for kind, e in tested.items():
                    if len(e.get(name, [])) != depth:
                        continue
                    rung = e[name][i]
                    changes[kind] = np.array(rung["values"]) - np.array(e[NONE]["values"])
                    row = {
                        "condition": condition,
                        "kind": kind,
                        "perturbation": name,
                        "value": rung["value"],
                        "unperturbed": e[NONE]["margin"],
                        "perturbed": rung["margin"],
                        "perturbed_ci": rung["ci"],
                    } | _one_sample(changes[kind], margin)
                    rows["ladder"].append(row)
                    if i == depth - 1:
                        rows["changes"].append(dict(row, equivalence=dict(row["equivalence"])))
                if len(changes) == len(KINDS):
                    h, f = (changes[k] for k in KINDS)
                    row = {
                        "condition": condition,
                        "kind": "hierarchical − flat",
                        "perturbation": name,
                        "value": tested[KINDS[0]][name][i]["value"],
                        "hierarchical": float(h.mean()),
                        "flat": float(f.mean()),
                    } | _two_sample(h, f, margin)
                    rows["ladder kinds"].append(row)
                    if i == depth - 1:
                        rows["kinds"].append(dict(row, equivalence=dict(row["equivalence"])))
    for condition, by_kind in crossplay.items():
        gaps = {k: np.array(by_kind[k]["gap"]["differences"]) for k in KINDS if k in by_kind}
        for kind, gap in gaps.items():
            c = by_kind[kind]
            rows["gaps"].append(
                {"condition": condition, "kind": kind, "self_play": c["self_play"], "held_out": c["held_out"]["mean"]}
                | _one_sample(gap, margin)
            )
        if len(gaps) == len(KINDS):
            h, f = (gaps[k] for k in KINDS)
            rows["gap kinds"].append(
                {
                    "condition": condition,
                    "kind": "hierarchical − flat",
                    "hierarchical": float(h.mean()),
                    "flat": float(f.mean()),
                }
                | _two_sample(h, f, margin)
            )
    out: dict[str, dict[str, Any]] = {}
    for name, about in FAMILIES.items():
        counts = correct(rows[name], about["words"])
        out[name] = {"what": about["what"], "margin": margin, "counts": counts, "rows": rows[name]}
    return out


def resummarised(result: dict[str, Any]) -> dict[str, Any]:
    """:func:`summarise` again from a robust.json's own evaluations (``runs``, ``sources``): the
    summaries and cross-play a compact result regenerates without the run folders."""
    done = {f"{name}|{level}": value for name, levels in result["runs"].items() for level, value in levels.items()}
    return summarise(result["sources"], done, result["episodes"], result["seed"])


def _level(name: str, value: float | None) -> str:
    return "unperturbed" if name == NONE else f"{name}={value:g}"


def _verdict(row: dict[str, Any]) -> str:
    """A row's verdict as the tables print it: a difference or equivalence shown in bold; the
    equivalence test's Holm p in brackets after any verdict that is not a difference."""
    verdict = row["verdict"]
    shown = f"**{verdict}**" if verdict != "not resolved" else verdict
    if verdict in ("equivalent", "not resolved") and "equivalence" in row:
        return f"{shown} ({p_text(row['equivalence']['p_holm'])})"
    return shown


def _split(name: str, rows: list[dict[str, Any]]) -> str:
    """How a family's size is made, counted from its rows, for the captions."""
    groups = len({(r["condition"], r["kind"]) for r in rows})
    conditions = len({r["condition"] for r in rows})
    perturbations = len({r.get("perturbation") for r in rows})
    rungs = len({(r.get("perturbation"), r.get("value")) for r in rows})
    return {
        "margins": f"{groups} condition-and-kind rows × {rungs} (the unperturbed margin and {rungs - 1} strongest "
        "rungs)",
        "changes": f"{groups} condition-and-kind rows × {perturbations} perturbations",
        "kinds": f"{conditions} conditions × {perturbations} perturbations",
        "ladder": f"{groups} condition-and-kind rows × {rungs} rungs",
        "ladder kinds": f"{conditions} conditions × {rungs} rungs",
        "gaps": "one per condition and kind",
        "gap kinds": "one per condition",
    }[name]


def _family_text(name: str, family: dict[str, Any]) -> str:
    """A family as the captions name it: its size, how the size is made, its verdict counts."""
    counts, words = family["counts"], FAMILIES[name]["words"]
    verdicts = ", ".join(f"{counts[w]} {w}" for w in (*words, "equivalent", "not resolved"))
    return f"family `{name}`: {counts['comparisons']} comparisons, {_split(name, family['rows'])}; {verdicts}"


def families_markdown(result: dict[str, Any]) -> str:
    """The families of comparisons, each corrected by Holm alone: their sizes, how many
    comparisons have an unadjusted p below 0.05, and the verdicts after the correction."""
    fams = result["families"]
    lines = [
        "The families of comparisons. Each is corrected by Holm on its own: its differences from zero "
        f"(two-sided, significant at an adjusted p of {2 * stats.ALPHA:g}) and, apart, its equivalence tests "
        f"(two one-sided tests within ±{EQUIVALENCE_MARGIN:g}, at {stats.ALPHA:g} a side):",
        "",
        "| family | compares | comparisons | unadjusted p < 0.05 | different after Holm | equivalent after Holm "
        "| not resolved |",
        "|---|---|---:|---:|---|---:|---:|",
    ]
    for name, family in fams.items():
        c, words = family["counts"], FAMILIES[name]["words"]
        shown = sum(c[w] for w in words)
        split = ", ".join(f"{c[w]} {w}" for w in words if c[w])
        equivalent = str(c["equivalent"]) if any("equivalence" in r for r in family["rows"]) else "–"
        lines.append(
            f"| {name} | {family['what']} | {c['comparisons']} | {c['uncorrected']} "
            f"| {shown}{f': {split}' if split else ''} | {equivalent} | {c['not resolved']} |"
        )
    return "\n".join(lines) + "\n"


def margins_markdown(result: dict[str, Any]) -> str:
    """Each condition and kind's margin, unperturbed and at each perturbation's strongest rung:
    mean over seeds, t-interval and the Holm p of the ``margins`` family."""
    summary, family = result["summary"], result["families"]["margins"]
    tested = {(r["condition"], r["kind"], r["perturbation"]): r for r in family["rows"]}
    kinds = sorted({k for c in summary.values() for k in c}, key=lambda k: (k != "hierarchical", k))
    lines = [
        "Each run's margin over the better of always-chase and always-stalk put in its place (mean over "
        "its predators), mean over seeds [95 % t-interval] and, in brackets, the Holm p of the margin against "
        f"zero ({_family_text('margins', family)}), unperturbed and at each "
        "perturbation's strongest rung:",
        "",
        "| condition | kind | seeds | unperturbed | "
        + " | ".join(f"{name}={levels[-1]:g}" for name, levels in LADDERS.items())
        + " |",
        "|---|---|---:|" + "---:|" * (len(LADDERS) + 1),
    ]

    def cell(condition: str, kind: str, name: str, entry: dict[str, Any]) -> str:
        row = tested.get((condition, kind, name))
        p = f" ({p_text(row['p_holm'])})" if row else ""
        return f"{entry['margin']:+.3f}{span_text(entry['ci'])}{p}"

    for condition, by_kind in summary.items():
        for kind in kinds:
            if kind not in by_kind:
                continue
            e = by_kind[kind]
            cells = [cell(condition, kind, NONE, e[NONE])]
            for name in LADDERS:
                top = e.get(name, [])
                cells.append(cell(condition, kind, name, top[-1]) if top else "–")
            lines.append(f"| {condition} | {kind} | {len(e[NONE]['values'])} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def changes_markdown(result: dict[str, Any], name: str = "changes") -> str:
    """One family of changes (``changes``: the strongest rungs; ``ladder``: every rung), a row per
    condition and rung, a column group per kind: the change [95 % t-interval, paired by run],
    its Holm p and verdict; for the ladder, first the margin at the rung [95 % t-interval] (the
    margins of the strongest rungs are tested in ``margins``: these, only described)."""
    family = result["families"][name]
    ladder = name != "changes"
    rows: dict[tuple[str, str, Any], dict[str, dict[str, Any]]] = {}
    for r in family["rows"]:
        rows.setdefault((r["condition"], r["perturbation"], r["value"]), {})[r["kind"]] = r
    kinds = [k for k in KINDS if any(k in by_kind for by_kind in rows.values())]
    where = "every rung" if ladder else "each perturbation's strongest rung"
    described = (
        "Each kind's margin at the rung first [95 % t-interval; described, not tested]; then the" if ladder else "The"
    )
    lines = [
        f"{described} change of each run's margin from its unperturbed one at {where}, mean over seeds [95 % "
        f"t-interval, paired by run], with its Holm p (two-sided) and verdict; {_family_text(name, family)}. "
        f"After a verdict that is not a difference, in brackets: the Holm p of the two one-sided tests that the "
        f"change lies within ±{family['margin']:g} (over the same family):",
        "",
        "| condition | perturbation | "
        + " | ".join(
            (f"{k}: margin [95 % t] | change [95 % t]" if ladder else f"{k}: change [95 % t]") + " | p (Holm) | verdict"
            for k in kinds
        )
        + " |",
        "|---|---|" + ("---:|" * ladder + "---:|---:|---|") * len(kinds),
    ]
    for (condition, perturbation, value), by_kind in rows.items():
        cells = []
        for k in kinds:
            r = by_kind.get(k)
            margin = [f"{r['perturbed']:+.3f}{span_text(r['perturbed_ci'])}" if r else "–"] if ladder else []
            cells += margin + (
                [f"{r['mean']:+.3f}{span_text(r['ci'])}", p_text(r["p_holm"]), _verdict(r)] if r else ["–", "–", "–"]
            )
        lines.append(f"| {condition} | {_level(perturbation, value)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def kinds_markdown(result: dict[str, Any], name: str = "kinds") -> str:
    """Hierarchical minus flat (``kinds``: the strongest rungs; ``ladder kinds``: every rung): each
    kind's mean change, the difference with its 95 % Welch interval, Holm p and verdict."""
    family = result["families"][name]
    where = "each perturbation's strongest rung" if name == "kinds" else "every rung"
    lines = [
        f"Hierarchical against flat at {where}: each kind's change of its margin (mean over seeds), and the "
        "difference of the changes, hierarchical minus flat, with its 95 % Welch interval over runs (the kinds' runs "
        f"are independent); {_family_text(name, family)}. In brackets after a verdict that is not a "
        f"difference: the Holm p of the two one-sided Welch tests within ±{family['margin']:g}:",
        "",
        "| condition | perturbation | hierarchical change | flat change | hierarchical − flat [95 % Welch] "
        "| p (Holm) | verdict |",
        "|---|---|---:|---:|---:|---:|---|",
    ]
    for r in family["rows"]:
        lines.append(
            f"| {r['condition']} | {_level(r['perturbation'], r['value'])} | {r['hierarchical']:+.3f} "
            f"| {r['flat']:+.3f} | {r['mean']:+.3f}{span_text(r['ci'])} | {p_text(r['p_holm'])} | {_verdict(r)} |"
        )
    return "\n".join(lines) + "\n"


def crossplay_markdown(result: dict[str, Any]) -> str:
    """Cross-play: per condition and kind the self-play and held-out margins and the gap with its
    Holm p and verdict (family ``gaps``); the two kinds' gaps compared (family ``gap kinds``)."""
    if not result["crossplay"]:
        return "Cross-play needs two or more seeds of a condition and kind: none here.\n"
    gaps, kinds = result["families"]["gaps"], result["families"]["gap kinds"]
    lines = [
        "Cross-play: each seed's predators against every other seed's prey of the same condition and kind "
        "(held-out); the gap is self-play minus held-out margin, paired by the predators' seed, with its Holm p "
        f"(two-sided) and verdict; {_family_text('gaps', gaps)}. In brackets after a verdict that is not a "
        f"difference: the Holm p of the two one-sided tests that the gap lies within ±{gaps['margin']:g}:",
        "",
        "| condition | kind | self-play margin | held-out margin | generalisation gap [95 % t] | p (Holm) | verdict |",
        "|---|---|---:|---:|---:|---:|---|",
    ]
    for r in gaps["rows"]:
        lines.append(
            f"| {r['condition']} | {r['kind']} | {r['self_play']:+.3f} | {r['held_out']:+.3f} "
            f"| {r['mean']:+.3f}{span_text(r['ci'])} | {p_text(r['p_holm'])} | {_verdict(r)} |"
        )
    if kinds["rows"]:
        lines += [
            "",
            "The two kinds' gaps compared: hierarchical minus flat, 95 % Welch interval over runs; "
            f"{_family_text('gap kinds', kinds)}:",
            "",
            "| condition | hierarchical gap | flat gap | hierarchical − flat [95 % Welch] | p (Holm) | verdict |",
            "|---|---:|---:|---:|---:|---|",
        ]
        for r in kinds["rows"]:
            lines.append(
                f"| {r['condition']} | {r['hierarchical']:+.3f} | {r['flat']:+.3f} "
                f"| {r['mean']:+.3f}{span_text(r['ci'])} | {p_text(r['p_holm'])} | {_verdict(r)} |"
            )
    return "\n".join(lines) + "\n"


def sections(result: dict[str, Any]) -> dict[str, str]:
    """Every table docs/robustness.md holds, by the name of its generated block."""
    return {
        "families": families_markdown(result),
        "margins": margins_markdown(result),
        "changes": changes_markdown(result, "changes"),
        "kinds": kinds_markdown(result, "kinds"),
        "crossplay": crossplay_markdown(result),
        "chase": chase_markdown(result),
        "ladder": changes_markdown(result, "ladder") + "\n" + kinds_markdown(result, "ladder kinds"),
    }


def markdown(result: dict[str, Any]) -> str:
    """robust.md: every table of :func:`sections`, in order."""
    return "\n".join(sections(result).values())


def chase_markdown(result: dict[str, Any]) -> str:
    """Always-chase's return (mean over predators, runs and conditions) at each rung: what each
    perturbation costs a predator with no learning at all."""
    summary = result["summary"]
    entries = [e for by_kind in summary.values() for e in by_kind.values()]
    plain = float(np.mean([e[NONE]["always_chase"] for e in entries]))
    lines = ["| perturbation | " + " | ".join(f"rung {i + 1}" for i in range(3)) + " |", "|---|---:|---:|---:|"]
    lines.insert(
        0,
        "What each perturbation costs a predator with no learning at all: always-chase's return (mean over "
        f"predators, runs and conditions) at each rung; unperturbed {plain:+.3f}.\n",
    )
    for name, levels in LADDERS.items():
        cells = []
        for i, value in enumerate(levels):
            values = [e[name][i]["always_chase"] for e in entries if name in e and len(e[name]) > i]
            cells.append(f"{value:g}: {np.mean(values):+.3f}" if values else "–")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
