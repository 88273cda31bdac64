"""The residual study's costs, measured and scaled (PLAN.md quotes what this writes).

    nice -n 10 python studies/residual-value/measure.py [--steps 40] [--out studies/residual-value/rates.json]
    python studies/residual-value/measure.py --estimate      # PLAN.md's table, from both rates files

What studies/rule-value/rates.json does not hold: the residual kind's training in the four plain
conditions, and all three kinds' training with 4 obstacles in 1p-high and 2p-high-individual
(the rule study trains no run with obstacles). As in studies/rule-value/measure.py: a run at the
``reproduction`` preset timed over ``--steps`` steps of its 32 arenas once its replay has filled
past ``learning_starts`` (one torch thread), as seconds per transition (arena-step), and a whole
run's time *scaled*: seconds per transition × the transitions of a 15,000-episode run.

The transitions: hierarchical and flat from the committed reproduction runs' training curves (as
the rule study's plan); the residual kind has no committed 15,000-episode run, so it is given the
hierarchical predator's (it moves in the rule's direction in about 95 % of its steps and starts
as the rule) and, as a bound, the flat one's. With obstacles, the plain run's transitions times
the ratio of episode lengths with 5 obstacles to without over the first 5000 episodes, from the
obstacle study's committed runs (results/obstacles/avoidance against results/obstacles/empty;
2p-high-individual, which that study did not train, takes 2p-high-shared's ratio). Rough figures:
the machine is loaded while this runs (PLAN.md says how loaded).
"""

from __future__ import annotations

import argparse
import gzip
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.training.train import TrainConfig, Trainer

ROOT = Path(__file__).resolve().parents[2]
PLAIN = ("1p-high", "2p-high-individual", "3p-low-individual", "3p-high-shared")
OBSTACLES = 4
WITH_OBSTACLES = ("1p-high", "2p-high-individual")
KINDS = ("residual", "hierarchical", "flat")
#: The obstacle study's condition whose ratio stands in for one it did not train.
OBSTACLE_PROXY = {"1p-high": "1p-high", "2p-high-individual": "2p-high-shared"}


def curve_transitions(path: Path, episodes: int | None = None) -> float:
    """Transitions of a committed run's training curve (mean length per window × its episodes), up
    to ``episodes`` if given."""
    curve = json.loads(gzip.decompress(path.read_bytes()))["curve"]
    ends = np.array(curve["episodes"])
    windows = np.diff([0, *ends])
    keep = ends <= (episodes or ends[-1])
    return float(np.sum(windows[keep] * np.array(curve["length"])[keep]))


def transitions(condition: str, kind: str) -> float:
    """Mean transitions of a 15,000-episode run of the reproduction's committed runs."""
    paths = sorted((ROOT / "results" / "reproduction" / "runs").glob(f"{condition}-{kind}-seed*.json.gz"))
    return float(np.mean([curve_transitions(p) for p in paths]))


def obstacle_ratio(condition: str, kind: str) -> float:
    """Transitions with 5 obstacles over those without, the first 5000 episodes, mean over seeds."""
    proxy = OBSTACLE_PROXY[condition]
    results = ROOT / "results" / "obstacles"
    walled = [
        curve_transitions(p, 5000)
        for p in sorted((results / "avoidance" / "runs").glob(f"{proxy}-obstacles5-{kind}-seed*.json.gz"))
    ]
    empty = [
        curve_transitions(p, 5000) for p in sorted((results / "empty" / "runs").glob(f"{proxy}-{kind}-seed*.json.gz"))
    ]
    return float(np.mean(walled) / np.mean(empty))


def seconds_per_transition(condition: str, kind: str, steps: int, obstacles: int) -> float:
    config = TrainConfig(
        condition=condition,
        agent=REPRODUCTION,
        episodes=15000,
        num_envs=32,
        predator=kind,  # type: ignore[arg-type]
        obstacles=obstacles,
    )
    trainer = Trainer([config])
    while trainer.groups[0].learner.steps < REPRODUCTION.learning_starts:
        trainer.step()
    start = time.perf_counter()
    for _ in range(steps):
        trainer.step()
    return (time.perf_counter() - start) / (steps * config.num_envs)


def estimate() -> str:
    """PLAN.md's cost table (markdown), from this study's rates and the rule study's
    (studies/rule-value/rates.json: the hierarchical and flat runs, one evaluation's seconds). A
    judged run trained here plays 13 members × 5 budgets; a reused one 4 × 5 and one check; a
    residual or hierarchical run 300 episodes on each ladder rung (5 evaluations' worth each: 10
    levels, 7 with obstacles); a residual run's corrections 200 episodes of one variant (about one
    evaluation). With obstacles an evaluation is taken as the plain one × the hierarchical obstacle
    ratio of episode lengths (not measured)."""
    mine = json.loads((ROOT / "studies" / "residual-value" / "rates.json").read_text())["settings"]
    rule = json.loads((ROOT / "studies" / "rule-value" / "rates.json").read_text())["conditions"]
    lines = [
        "| setting | residual run (h) | hierarchical run (h) | flat run (h) | one evaluation (s) | population (h) "
        "| judged, 10 a kind (h) | 20 a kind (h) | 30 a kind (h) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    totals = np.zeros(4)
    for setting in [*PLAIN, *(f"{c}-obstacles{OBSTACLES}" for c in WITH_OBSTACLES)]:
        condition = setting.removesuffix(f"-obstacles{OBSTACLES}")
        walled = setting != condition
        hours = {k: (mine[setting] if walled else rule[condition]).get(k, {}).get("run_hours") for k in KINDS}
        hours["residual"] = mine[setting]["residual"]["run_hours"]
        evaluation = rule[condition]["evaluation_seconds"] * (
            mine[setting]["hierarchical"]["obstacle_ratio"] if walled else 1.0
        )
        levels = 7 if walled else 10
        trained_here = KINDS if walled else ("residual",)
        population = sum(POPULATION_RUNS * hours[k] for k in trained_here)

        train = sum(hours[k] for k in trained_here)  # a seed's runs trained here
        plays = sum(65 if k in trained_here else 21 for k in KINDS) + 2 * levels * 5 + 1  # a seed's evaluations
        row = [population, *(n * (train + plays * evaluation / 3600) for n in (10, 20, 30))]
        totals += row
        shown = " | ".join("—" if hours[k] is None else f"{hours[k]:.3f}" for k in KINDS)
        lines.append(f"| {setting} | {shown} | {evaluation:.1f} | " + " | ".join(f"{v:.2f}" for v in row) + " |")
    lines.append("| **all** | | | | | " + " | ".join(f"**{v:.1f}**" for v in totals) + " |")
    return "\n".join(lines) + "\n"


POPULATION_RUNS = 4


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--estimate", action="store_true", help="Print PLAN.md's cost table and stop.")
    args = parser.parse_args()
    if args.estimate:
        print(estimate(), end="")
        return
    torch.set_num_threads(1)
    plan = [(c, "residual", 0) for c in PLAIN] + [(c, k, OBSTACLES) for c in WITH_OBSTACLES for k in KINDS]
    rows: dict[str, Any] = {}
    for condition, kind, obstacles in plan:
        setting = f"{condition}-obstacles{obstacles}" if obstacles else condition
        rate = seconds_per_transition(condition, kind, args.steps, obstacles)
        source = "hierarchical" if kind == "residual" else kind
        total = transitions(condition, source)
        row = {"seconds_per_transition": rate, "transitions": total, "transitions_from": source}
        if kind == "residual":
            row["transitions_if_flat"] = transitions(condition, "flat")
        if obstacles:
            ratio = obstacle_ratio(condition, source)
            row.update(obstacle_ratio=ratio, obstacle_ratio_from=OBSTACLE_PROXY[condition], transitions=total * ratio)
            if kind == "residual":
                row["transitions_if_flat"] *= obstacle_ratio(condition, "flat")
        row["run_hours"] = rate * row["transitions"] / 3600
        rows.setdefault(setting, {})[kind] = row
        print(
            f"{setting} {kind}: {rate * 1e6:.1f} µs a transition, {row['run_hours']:.3f} h a run (scaled)", flush=True
        )
    out = {
        "command": "nice -n 10 python studies/residual-value/measure.py " + " ".join(sys.argv[1:]),
        "steps": args.steps,
        "load_average": list(os.getloadavg()),
        "settings": rows,
    }
    if args.out is not None:
        atomic_write_text(args.out, json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
