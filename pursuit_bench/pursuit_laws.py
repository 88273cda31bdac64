"""Which pursuit law the predators follow: evaluation episodes played, every predator's pursuit
cut out, the three laws of :mod:`pursuit_bench.guidance` fitted to each, and summaries per
predator kind; what ``pursuit-bench law`` writes (``law.json``, ``law.png``).

A *pursuit* is one predator's whole approach in one episode: its positions and the prey's from
the episode's start to its end (capture, a wall exit or the time limit), kept when it lasts at
least :data:`MIN_STEPS` steps (1 s) and the predator moved at least :data:`MIN_PATH` on it.
The hierarchical predator's stalking is part of its approach: the fit says how its heading
follows the prey over the whole hunt, both modes together. Reference predators play the same
episodes' seeds against the same prey: always-chase (parallel navigation alone), always-stalk
and pure pursuit.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from pursuit_bench import guidance, statistics
from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.conditions import CONDITIONS
from pursuit_bench.evaluate import Actor, run_episodes
from pursuit_bench.policies import AlwaysChase, AlwaysStalk, PurePursuitPredator
from pursuit_bench.world import DT

MIN_STEPS = 10
MIN_PATH = 0.05
#: Scripted predators fitted beside the trained ones, by the name law.json gives them.
REFERENCES = {"always_chase": AlwaysChase, "always_stalk": AlwaysStalk, "pure_pursuit": PurePursuitPredator}


def pursuits(
    condition: str,
    agents: dict[str, Actor],
    episodes: int,
    seed: int,
    prey_epsilon: float | None = 0.1,
    task_options: Mapping[str, Any] | None = None,
) -> dict[str, list[tuple[np.ndarray, np.ndarray]]]:
    """Play ``episodes`` episodes (predators greedy, the prey ε-greedy as in the paper's
    evaluation; ``task_options``: obstacles) and return every predator's pursuits: (pursuer,
    prey) position arrays (T, 2)."""
    names = list(agents)
    predators, prey = names[:-1], names[-1]
    tracks: dict[int, list[np.ndarray]] = {}
    found: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {p: [] for p in predators}

    def on_step(obs: np.ndarray, actions: np.ndarray, done: np.ndarray) -> None:
        for arena in range(len(obs)):
            tracks.setdefault(arena, []).append(obs[arena, :, 0:2].copy())  # each agent's own position
            if done[arena]:
                track = np.array(tracks.pop(arena))
                for i, name in enumerate(predators):
                    path = np.linalg.norm(np.diff(track[:, i], axis=0), axis=1)
                    if len(track) >= MIN_STEPS and path.sum() >= MIN_PATH and path[0] > 1e-9:
                        found[name].append((track[:, i], track[:, -1]))

    epsilons = {prey: prey_epsilon} if prey_epsilon is not None else {}
    run_episodes(
        condition,
        agents,
        episodes,
        seed=seed,
        num_envs=min(16, episodes),
        epsilons=epsilons,
        on_step=on_step,
        task_options=task_options,
    )
    return found


def fit_pursuits(found: list[tuple[np.ndarray, np.ndarray]]) -> dict[str, Any]:
    """Every law fitted to every pursuit: per law the fitted gains, delays, errors and r² of
    each pursuit and their medians; how often each law wins (:func:`guidance.winner`)."""
    rows = []
    for pursuer, target in found:
        fits = guidance.fit_all(pursuer, target, DT)
        rows.append((fits, guidance.winner(fits)))
    summary: dict[str, Any] = {"pursuits": len(rows), "laws": {}}
    for law in guidance.LAWS:
        fitted = [fits[law] for fits, _ in rows]
        entry: dict[str, Any] = {
            "gains": {g: [round(f.gains[g], 4) for f in fitted] for g in guidance.LAW_GAINS[law]},
            "delay": [round(f.delay, 3) for f in fitted],
            "error": [round(f.error, 5) for f in fitted],
            "r2": [round(f.r2, 4) for f in fitted],
        }
        if fitted:
            entry["median"] = {
                **{g: float(np.median(v)) for g, v in entry["gains"].items()},
                "delay": float(np.median(entry["delay"])),
                "error": float(np.median(entry["error"])),
                "r2": float(np.median(entry["r2"])),
            }
        summary["laws"][law] = entry
    wins = [w for _, w in rows]
    summary["wins"] = {law: wins.count(law) / len(wins) if wins else 0.0 for law in guidance.LAWS}
    summary["winner"] = max(summary["wins"], key=lambda law: summary["wins"][law]) if wins else None
    return summary


def examples(found: list[tuple[np.ndarray, np.ndarray]], count: int = 3) -> list[dict[str, Any]]:
    """A few pursuits with the trajectory of each fitted law, for the figure."""
    shown = []
    for pursuer, target in found[:count]:
        fits = guidance.fit_all(pursuer, target, DT)
        shown.append(
            {
                "pursuer": pursuer.tolist(),
                "target": target.tolist(),
                "simulated": {law: f.simulated.tolist() for law, f in fits.items()},
                "winner": guidance.winner(fits),
            }
        )
    return shown


def analyse(
    condition: str,
    agents: dict[str, Actor],
    kind: str,
    episodes: int,
    seed: int,
    references: bool = True,
    task_options: Mapping[str, Any] | None = None,
    avoidance: bool = False,
) -> dict[str, Any]:
    """law.json's content for one set of agents: per predator of ``kind`` (and, with
    ``references``, per scripted reference predator in the predators' places, their lower
    layer avoiding obstacles as ``avoidance`` says) the fits; ``task_options``: obstacles."""
    predators = list(CONDITIONS[condition].agent_names[:-1])
    result: dict[str, Any] = {"condition": condition, "episodes": episodes, "seed": seed, "dt": DT, "kinds": {}}
    found = pursuits(condition, agents, episodes, seed, task_options=task_options)
    result["kinds"][kind] = {name: fit_pursuits(found[name]) for name in predators}
    result["examples"] = {kind: examples(found[predators[0]])}
    if references:
        for name, policy in REFERENCES.items():
            scripted = {**agents, **{p: ScriptedAgent(p, policy(avoidance=avoidance)) for p in predators}}
            found = pursuits(condition, scripted, episodes, seed, task_options=task_options)
            result["kinds"][name] = {p: fit_pursuits(found[p]) for p in predators}
    return result


def over_seeds(per_run: list[dict[str, Any]]) -> dict[str, Any]:
    """A sweep's law.json: per condition and predator kind, over seeds (runs), the mean of each
    run's median gains and its 95 % interval, and how often each law wins."""
    grouped: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for result in per_run:
        for kind, predators in result["kinds"].items():
            grouped.setdefault((result["condition"], kind), []).extend(predators.values())
    summary: dict[str, Any] = {}
    for (condition, kind), fits in sorted(grouped.items()):
        entry: dict[str, Any] = {"predator_runs": len(fits), "laws": {}}
        for law in guidance.LAWS:
            medians = [f["laws"][law]["median"] for f in fits if "median" in f["laws"][law]]
            law_entry: dict[str, Any] = {}
            for key in (*guidance.LAW_GAINS[law], "delay", "error"):
                values = np.array([m[key] for m in medians])
                law_entry[key] = {
                    "mean": float(values.mean()) if len(values) else None,
                    "ci": statistics.t_interval(values),
                }
            law_entry["wins"] = float(np.mean([f["wins"][law] for f in fits])) if fits else None
            entry["laws"][law] = law_entry
        entry["winner"] = max(guidance.LAWS, key=lambda law: entry["laws"][law]["wins"] or 0.0)
        summary.setdefault(condition, {})[kind] = entry
    return summary
