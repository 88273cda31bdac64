"""Cost of a perturbed evaluation: the shipped agents of a condition playing episodes,
unperturbed and under each perturbation at its strongest rung (pursuit_bench.analysis.robustness.LADDERS)
and all sense perturbations together, in one process; medians of ``--repeats``, reported per
step (perturbations change how long episodes last, so time per evaluation mixes that in) and
as a ratio to the unperturbed play measured in the same run (target: within 1.5x).

    python benchmarks/bench_perturb.py [--condition 2p-high-shared] [--episodes 300] [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch

from pursuit_bench import pretrained
from pursuit_bench.analysis.robustness import LADDERS, perturbation
from pursuit_bench.env.perturbations import Perturbations
from pursuit_bench.training.evaluate import run_episodes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--condition", default="2p-high-shared")
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    torch.set_num_threads(1)
    config, agents, _ = pretrained.described(args.condition)
    cases = {"none": Perturbations()}
    cases |= {f"{name}={levels[-1]:g}": perturbation(name, levels[-1]) for name, levels in LADDERS.items()}
    cases["obs-noise=0.1, delay=6, act-noise=0.6"] = Perturbations(obs_noise=0.1, delay=6, act_noise=0.6)
    times: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(args.repeats):  # interleaved, so that a noisy machine slows every case alike
        for name, changes in cases.items():
            start = time.perf_counter()
            played = run_episodes(
                config.condition,
                agents,  # type: ignore[arg-type]
                args.episodes,
                seed=12345,
                num_envs=64,
                epsilons={"prey_0": 0.1},
                perturbations=changes,
            )
            times[name].append((time.perf_counter() - start) / played.lengths.sum() * 1e6)
    base = statistics.median(times["none"])
    print(f"{args.condition}, {args.episodes} episodes, 64 arenas, median of {args.repeats}")
    print(f"{'perturbation':<40} {'µs per arena-step':>18} {'ratio':>6}")
    for name, measured in times.items():
        median = statistics.median(measured)
        print(f"{name:<40} {median:18.1f} {median / base:6.2f}")


if __name__ == "__main__":
    main()
