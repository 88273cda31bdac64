"""Env speed side by side with the peers, in one process and one run.

Every env is driven the same way: actions sampled from its own action spaces each step, a reset
whenever its episode ends (both count). Each figure is the median of ``--repeats`` timed runs.

    python benchmarks/bench_env.py            # needs the mpe2 extra for the MPE2 peer
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from collections.abc import Callable
from typing import Any

import pursuit_bench


def steps_per_second(env: Any, steps: int, repeats: int) -> float:
    """Median over ``repeats`` of env steps per second through the PettingZoo parallel API."""

    def run() -> None:
        env.reset(seed=0)
        for _ in range(steps):
            if not env.agents:
                env.reset()
            env.step({a: env.action_space(a).sample() for a in env.agents})

    run()  # warm up
    rates = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        rates.append(steps / (time.perf_counter() - start))
    return statistics.median(rates)


def mpe2_simple_tag() -> Any | None:
    """MPE2's simple_tag with 3 predators, 1 prey and no obstacles, or None if not installed."""
    try:
        from mpe2 import simple_tag_v3
    except ImportError:
        return None
    return simple_tag_v3.parallel_env(num_good=1, num_adversaries=3, num_obstacles=0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    envs: dict[str, Callable[[], Any | None]] = {
        "pursuit-bench single env (pymunk)": lambda: pursuit_bench.parallel_env("3p-high-shared"),
        "pursuit-bench single env (numpy)": lambda: pursuit_bench.parallel_env("3p-high-shared", backend="numpy"),
        "MPE2 simple_tag (3 adversaries, 1 good, 0 obstacles)": mpe2_simple_tag,
    }
    rates: dict[str, float] = {}
    for name, make in envs.items():
        env = make()
        if env is None:
            print(f"{name:55s} not installed (pip install -e '.[mpe2]')")
            continue
        rates[name] = steps_per_second(env, args.steps, args.repeats)
        print(f"{name:55s} {rates[name]:10,.0f} env-steps/s")
    peer = rates.get("MPE2 simple_tag (3 adversaries, 1 good, 0 obstacles)")
    if peer:
        for name, rate in rates.items():
            if name.startswith("pursuit-bench"):
                print(f"ratio {name} / MPE2: {rate / peer:.1f}x")


if __name__ == "__main__":
    main()
