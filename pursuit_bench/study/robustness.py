"""Robustness of trained predators (``pursuit-bench robust``, docs/robustness.md): the paper's
protocol under a ladder of perturbations (:mod:`pursuit_bench.env.perturbations`), and cross-play
over a sweep's seeds (each seed's predators against every seed's prey).

The quantity throughout is a run's **margin**: per predator, its return as trained minus the
better of always-chase and always-stalk put in its place (same perturbed episodes, same prey),
averaged over the condition's predators. Over seeds it gets a t-interval
(:mod:`pursuit_bench.study.statistics`); its change under a perturbation is paired by seed.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.perturbations import Perturbations
from pursuit_bench.study import statistics

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
        check_opponents(config, other_config)
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


def check_opponents(config: Any, other: Any, mine: str = "the predators' run", theirs: str = "the prey's run") -> None:
    """ValueError unless agents trained by ``config`` and ``other`` can meet: the same number of
    predators and the same observation (wall features, obstacles); the message names what
    differs and the training options that would match ``theirs``."""
    ours, others = CONDITIONS[config.condition], CONDITIONS[other.condition]
    if ours.n_predators != others.n_predators:
        raise ValueError(
            f"opponents: {mine} ({config.condition}) has {ours.n_predators} predators and {theirs} "
            f"({other.condition}) {others.n_predators}; the prey's observation differs (train {mine} with "
            f"--condition {other.condition} to meet {theirs})"
        )
    differ = []
    if config.agent.wall_features != other.agent.wall_features:
        flag = "--wall-features" if other.agent.wall_features else "--no-wall-features"
        on = {True: "on", False: "off"}
        differ.append(
            (
                f"wall features {on[config.agent.wall_features]} in {mine}, {on[other.agent.wall_features]} in "
                f"{theirs}",
                flag + (" (the reproduction preset's)" if other.agent.wall_features else ""),
            )
        )
    if config.task_options != other.task_options:
        wanted = other.task_options.get("obstacles", 0)
        differ.append(
            (
                f"obstacles {config.task_options or 'none'} in {mine}, {other.task_options or 'none'} in {theirs}",
                f"--obstacles {wanted}"
                + (f" --obstacle-radius {other.task_options['obstacle_radius']:g}" if wanted else ""),
            )
        )
    if differ:
        raise ValueError(
            "opponents: the agents observe differently: "
            + "; ".join(what for what, _ in differ)
            + f" (train with {' '.join(option for _, option in differ)} to meet {theirs})"
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
    from pursuit_bench.study.jobs import run_jobs

    jobs = _jobs(sources, episodes, seed, crossplay=True)
    stamp = {"episodes": episodes, "seed": seed}
    done = run_jobs(jobs, _evaluate, out / "robust-parts", stamp, workers=workers, progress=progress)
    return summarise(sources, done, episodes, seed)


def summarise(
    sources: list[dict[str, Any]], done: dict[str, dict[str, Any]], episodes: int, seed: int
) -> dict[str, Any]:
    """robust.json: every evaluation by run and level; per condition and kind, each rung's margin
    over seeds (t-interval) and its change from the unperturbed margin (paired by seed), and
    always-chase's return; the cross-play matrices with the generalisation gap."""
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
                "ci": statistics.t_interval(plain),
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
                change = statistics.paired_difference(margin, plain)
                chase = np.array([by_run[s["name"]][level]["always_chase"] for s in members])
                rungs.append(
                    {
                        "value": value,
                        "margin": margin.mean().item(),
                        "ci": statistics.t_interval(margin),
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
            gap = statistics.paired_difference(np.diag(matrix), held_out)
            crossplay.setdefault(condition, {})[kind] = {
                "seeds": [s["seed"] for s in members],
                "matrix": matrix.tolist(),
                "self_play": float(np.diag(matrix).mean()),
                "held_out": {"mean": held_out.mean().item(), "ci": statistics.t_interval(held_out)},
                "gap": {k: gap[k] for k in ("mean", "ci", "p_greater", "p_less", "differences")},
            }
    return {
        "episodes": episodes,
        "seed": seed,
        "sources": [{k: s[k] for k in ("name", "condition", "kind", "seed")} for s in sources],
        "ladders": {name: list(levels) for name, levels in LADDERS.items()},
        "summary": summary,
        "crossplay": crossplay,
        "runs": by_run,
    }


def resummarised(result: dict[str, Any]) -> dict[str, Any]:
    """:func:`summarise` again from a robust.json's own evaluations (``runs``, ``sources``): the
    summaries and cross-play a compact result regenerates without the run folders."""
    done = {f"{name}|{level}": value for name, levels in result["runs"].items() for level, value in levels.items()}
    return summarise(result["sources"], done, result["episodes"], result["seed"])


def markdown(result: dict[str, Any]) -> str:
    """The tables docs/robustness.md quotes: per perturbation the margin at its strongest rung by
    condition and kind beside the unperturbed one, and the cross-play gaps."""

    def span(ci: list[float] | None) -> str:
        return f" [{ci[0]:+.3f}, {ci[1]:+.3f}]" if ci else ""

    summary = result["summary"]
    kinds = sorted({k for c in summary.values() for k in c}, key=lambda k: (k != "hierarchical", k))
    lines = [
        "Each run's margin over the better of always-chase and always-stalk put in its place (mean over "
        "its predators), mean over seeds [95 % t-interval], unperturbed and at each perturbation's "
        "strongest rung:",
        "",
        "| condition | kind | seeds | unperturbed | "
        + " | ".join(f"{name}={levels[-1]:g}" for name, levels in LADDERS.items())
        + " |",
        "|---|---|---:|" + "---:|" * (len(LADDERS) + 1),
    ]
    for condition, by_kind in summary.items():
        for kind in kinds:
            if kind not in by_kind:
                continue
            e = by_kind[kind]
            cells = [f"{e[NONE]['margin']:+.3f}{span(e[NONE]['ci'])}"]
            for name in LADDERS:
                top = e.get(name, [])
                cells.append(f"{top[-1]['margin']:+.3f}{span(top[-1]['ci'])}" if top else "–")
            lines.append(f"| {condition} | {kind} | {len(e[NONE]['values'])} | " + " | ".join(cells) + " |")
    if not result["crossplay"]:
        return "\n".join([*lines, "", "Cross-play needs two or more seeds of a condition and kind: none here."]) + "\n"
    lines += [
        "",
        "Cross-play: each seed's predators against every other seed's prey of the same condition and kind "
        "(held-out); the gap is self-play minus held-out, paired by the predators' seed:",
        "",
        "| condition | kind | self-play margin | held-out margin | generalisation gap [95 % t-interval] |",
        "|---|---|---:|---:|---:|",
    ]
    for condition, by_kind in result["crossplay"].items():
        for kind in kinds:
            if kind in by_kind:
                c = by_kind[kind]
                lines.append(
                    f"| {condition} | {kind} | {c['self_play']:+.3f} | {c['held_out']['mean']:+.3f} "
                    f"| {c['gap']['mean']:+.3f}{span(c['gap']['ci'])} |"
                )
    return "\n".join(lines) + "\n"


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
