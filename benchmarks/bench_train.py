"""Training throughput: transitions per second with the learners of a condition updated together
(stacked, one batched computation) versus one by one, in one process and one run.

    python benchmarks/bench_train.py [--condition 3p-high-shared] [--steps 150] [--repeats 3]

One thread for torch, as on a busy 2-core machine; medians of ``--repeats`` timed runs.
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch

from pursuit_bench.agents.config import QUICK
from pursuit_bench.train import TrainConfig, Trainer


def transitions_per_second(config: TrainConfig, steps: int, repeats: int) -> float:
    """Median transitions/s (arena-steps, every agent learning) once learning has started."""
    rates = []
    for _ in range(repeats):
        trainer = Trainer(config)
        while trainer.groups[0].learner.steps < config.agent.learning_starts:
            trainer.step()  # fill the replays first: we time learning, not warm-up
        start = time.perf_counter()
        for _ in range(steps):
            trainer.step()
        rates.append(steps * config.num_envs / (time.perf_counter() - start))
    return statistics.median(rates)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--condition", default="3p-high-shared")
    parser.add_argument("--num-envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=150)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    torch.set_num_threads(1)
    agent = QUICK.replace(learning_starts=500)
    rates = {}
    for batched in (True, False):
        config = TrainConfig(
            condition=args.condition, agent=agent, num_envs=args.num_envs, batched_learners=batched, episodes=10**9
        )
        rates[batched] = transitions_per_second(config, args.steps, args.repeats)
        label = "learners updated together" if batched else "learners updated one by one"
        print(f"{args.condition} {label:28s} {rates[batched]:8,.0f} transitions/s")
    print(f"ratio together / one by one: {rates[True] / rates[False]:.2f}x")


if __name__ == "__main__":
    main()
