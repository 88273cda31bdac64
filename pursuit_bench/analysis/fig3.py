"""Fig. 3 written into a folder: the analysis of one run's predators (:mod:`pursuit_bench.analysis.behaviour`)
as fig3.png, modes.png, analysis.json and analysis.rrd, and the chase modes of a sweep's runs
over seeds. What ``pursuit-bench analyze`` calls.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.analysis import behaviour as analysis
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.figures.plots import fig3_png, modes_png
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.training import runs
from pursuit_bench.training.train import TrainConfig
from pursuit_bench.trajectories.recording import record_embedding


def analyze_run(folder: Path, config: TrainConfig, agents: dict[str, Any], episodes: int, seed: int) -> dict[str, Any]:
    """Play ``episodes`` evaluation episodes with ``agents`` and write into ``folder``: fig3.png,
    modes.png, analysis.rrd and analysis.json (last: it says the set is complete). Returns the
    analysis by predator; ValueError if the predators are not hierarchical."""
    states = analysis.collect(config.condition, agents, episodes=episodes, seed=seed, task_options=config.task_options)
    if not states:
        raise ValueError(f"{folder}: its predators are {config.predator}, not hierarchical: nothing to analyse")
    result, embeddings = analysis.analyse(states, seed)
    shown = {}
    for name, picked in embeddings.items():
        index = picked[:, 0].astype(int)
        shown[name] = {
            "xy": picked[:, 1:],
            "value": states[name].value[index],
            "distance": states[name].distance[index],
        }
        result[name]["embedding"] = {"state": index.tolist(), "xy": np.round(picked[:, 1:], 3).tolist()}
    payload = {"condition": config.condition, "episodes": episodes, "seed": seed, "predators": result}
    closest = {name: states[name].closest[embeddings[name][:, 0].astype(int)] for name in embeddings}
    title = f"{config.condition}, {config.predator} predators, seed {config.seed} ({folder.name})"
    atomic_write_bytes(folder / "fig3.png", fig3_png(result, shown, closest, title))
    curves = {name: result[name]["chase_by_distance"] for name in result}
    atomic_write_bytes(folder / "modes.png", modes_png(curves, f"{config.condition}: P(chase) by distance to the prey"))
    first = next(iter(embeddings))
    index = embeddings[first][:, 0].astype(int)
    partial = folder / ".analysis.rrd.tmp"
    record_embedding(
        partial,
        list(agents),
        first,
        embeddings[first][:, 1:],
        states[first].value[index],
        states[first].positions[index],
        {"condition": config.condition, "episodes": episodes, "seed": seed},
    )
    os.replace(partial, folder / "analysis.rrd")
    atomic_write_text(folder / "analysis.json", json.dumps(payload) + "\n")
    return result


def analyze_sweep(sweep_folder: Path, episodes: int, seed: int) -> dict[str, Any]:
    """P(chase | distance) and the chase-onset distance of every trained hierarchical run of a
    sweep, grouped by number of predators and chase cost, over seeds: modes.png and
    analysis.json in the sweep folder. Returns the groups; ValueError if no run is trained."""
    groups: dict[tuple[int, str], list[tuple[np.ndarray, list[float], Any]]] = {}
    for folder in sorted((sweep_folder / "runs").glob("*-hierarchical-seed*")):
        try:
            config, _ = runs.read_config(folder)
            agents = runs.load_agents(folder)
        except ValueError:
            continue  # not trained yet
        states = analysis.collect(
            config.condition,
            agents,  # type: ignore[arg-type]
            episodes=episodes,
            seed=seed,
            task_options=config.task_options,
        )
        condition = CONDITIONS[config.condition]
        cost = "low" if condition.chase_cost < 0.05 else "high"
        distance = np.concatenate([s.distance for s in states.values()])
        mode = np.concatenate([s.mode for s in states.values()])
        binned = analysis.chase_by_distance(distance, mode)
        onsets = [float(np.median(s.onsets)) for s in states.values() if len(s.onsets)]
        groups.setdefault((condition.n_predators, cost), []).append(
            (np.array([np.nan if v is None else v for v in binned["p_chase"]]), onsets, binned["states"])
        )
    if not groups:
        raise ValueError(f"{sweep_folder}: no trained hierarchical run to analyse")
    result, curves = {}, {}
    for (n, cost), rows in sorted(groups.items()):
        table = np.stack([r[0] for r in rows])  # (seeds, bins)
        mean = [None if np.isnan(c).all() else float(np.nanmean(c)) for c in table.T]
        cis = [_proportion_interval(c[~np.isnan(c)]) for c in table.T]
        onset = np.array([o for r in rows for o in r[1]])
        label = f"{n} predator{'s' if n > 1 else ''}, {cost} cost"
        result[label] = {
            "runs": len(rows),
            "p_chase": mean,
            "p_chase_ci": cis,
            "chase_onset_median": float(np.median(onset)) if len(onset) else None,
            "chase_onset_ci": stats.t_interval(onset),
        }
        curves[label] = {
            "bins": analysis.DISTANCE_BINS.tolist(),
            "p_chase": mean,
            "states": np.sum([r[2] for r in rows], axis=0).tolist(),
            "ci": [[None if c is None else c[0] for c in cis], [None if c is None else c[1] for c in cis]],
        }
    atomic_write_text(sweep_folder / "analysis.json", json.dumps(result, indent=2) + "\n")
    costs = sorted({cost for _, cost in groups})
    compared = "low vs high chase cost" if len(costs) > 1 else f"{costs[0]} chase cost only"
    seeds = max(len(rows) for rows in groups.values())
    spread = "95 % t-interval" if seeds > 1 else "one run: Wilson interval"
    title = f"P(chase) by distance, {compared} (mean over seeds, {spread})"
    atomic_write_bytes(sweep_folder / "modes.png", modes_png(curves, title))
    return result


def _proportion_interval(values: np.ndarray) -> list[float] | None:
    """The t-interval over seeds of a proportion's mean, kept inside [0, 1]."""
    ci = stats.t_interval(values)
    return None if ci is None else [max(ci[0], 0.0), min(ci[1], 1.0)]
