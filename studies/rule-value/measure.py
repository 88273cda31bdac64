"""The rule study's costs, measured and scaled (PLAN.md quotes what this writes).

    python studies/rule-value/measure.py [--steps 40] [--out studies/rule-value/rates.json]

Training: per condition and kind, a run at the ``reproduction`` preset timed over ``--steps``
steps of its 32 arenas once its replay has filled past ``learning_starts`` (one torch thread; the
update schedule is one update per step, so a step costs the same early and late), as seconds per
transition (arena-step). A whole run's transitions come from the committed reproduction runs'
training curves (results/reproduction/runs: mean episode length per 150 episodes, 15,000
episodes, mean over that kind's seeds), so a run's time is *scaled*: seconds per transition ×
transitions. Evaluation: one evaluation of the shipped agents of the condition (60 episodes per
variant, no prey check, CRN), timed once; a judged run plays 5 budgets × 9 members of them.
"""

from __future__ import annotations

import argparse
import gzip
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
    from pursuit_bench.reports import rule_study
except ImportError:
    from pursuit_bench.study import rule_study

from pursuit_bench import pretrained
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.train import TrainConfig, Trainer

ROOT = Path(__file__).resolve().parents[2]


def transitions(condition: str, kind: str) -> float:
    """Mean transitions (arena-steps) of a 15,000-episode run of the reproduction's committed runs."""
    totals = []
    for path in sorted((ROOT / "results" / "reproduction" / "runs").glob(f"{condition}-{kind}-seed*.json.gz")):
        curve = json.loads(gzip.decompress(path.read_bytes()))["curve"]
        windows = np.diff([0, *curve["episodes"]])
        totals.append(float(np.sum(windows * np.array(curve["length"]))))
    return float(np.mean(totals))


def seconds_per_transition(condition: str, kind: str, steps: int) -> float:
    config = TrainConfig(condition=condition, agent=REPRODUCTION, episodes=15000, num_envs=32, predator=kind)  # type: ignore[arg-type]
    trainer = Trainer([config])
    while trainer.groups[0].learner.steps < REPRODUCTION.learning_starts:
        trainer.step()
    start = time.perf_counter()
    for _ in range(steps):
        trainer.step()
    return (time.perf_counter() - start) / (steps * config.num_envs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    torch.set_num_threads(1)
    rows = {}
    for condition in rule_study.order():
        agents = pretrained.load(condition)
        evaluate_agents(condition, agents, episodes=2, seed=0, prey_check=False)  # compile once
        start = time.perf_counter()
        evaluate_agents(condition, agents, episodes=rule_study.EPISODES, seed=rule_study.EVAL_SEED, prey_check=False)
        evaluation = time.perf_counter() - start
        row: dict[str, Any] = {"evaluation_seconds": evaluation}
        for kind in rule_study.KINDS:
            rate = seconds_per_transition(condition, kind, args.steps)
            total = transitions(condition, kind)
            row[kind] = {"seconds_per_transition": rate, "transitions": total, "run_hours": rate * total / 3600}
        rows[condition] = row
        hours = {kind: row[kind]["run_hours"] for kind in rule_study.KINDS}
        print(
            f"{condition}: hierarchical {hours['hierarchical']:.2f} h, flat {hours['flat']:.2f} h a run (scaled); "
            f"one evaluation {evaluation:.1f} s",
            flush=True,
        )
    out = {
        "command": "python studies/rule-value/measure.py " + " ".join(sys.argv[1:]),
        "steps": args.steps,
        "conditions": rows,
    }
    if args.out is not None:
        atomic_write_text(args.out, json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
