"""BenchMARL's env side by side: the batched TorchRL env (``marl/torchrl_env.py``, what the
BenchMARL task builds) against what it replaced, TorchRL's ``SerialEnv`` over one
``PettingZooWrapper`` env per arena (``benchmarl_task.make_env``), in one process and one run.
Both are stepped as BenchMARL's collector steps them (``step_and_maybe_reset``, random actions
from one seeded generator, ten arenas as BenchMARL's default ``n_envs_per_worker``); CPU time per
1000 env steps (BenchMARL's frames), medians of ``--repeats``, the two alternated. The two play
the same episodes bit for bit (``tests/test_marl_torchrl_env.py``).

    python benchmarks/bench_marl_env.py [--conditions 1p-high 2p-low-shared 3p-high-individual] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import torch
from torchrl.envs import EnvBase, SerialEnv

from pursuit_bench.marl.benchmarl_task import first_seeds, make_env
from pursuit_bench.marl.torchrl_env import PursuitTorchRLEnv

ARENAS = 10


def cpu_per_thousand(env: EnvBase, steps: int) -> float:
    """CPU seconds per 1000 frames of ``steps`` collector steps of ``env`` (random actions)."""
    generator = torch.Generator().manual_seed(0)
    td = env.reset()
    started = time.process_time()
    for _ in range(steps):
        td["predator", "action"] = torch.randint(0, 24, td["predator", "observation"].shape[:-1], generator=generator)
        td["prey", "action"] = torch.randint(0, 12, td["prey", "observation"].shape[:-1], generator=generator)
        _, td = env.step_and_maybe_reset(td)  # the next root fed back, as the collectors do
    return (time.process_time() - started) * 1000 / (steps * ARENAS)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--conditions", nargs="+", default=["1p-high", "2p-low-shared", "3p-high-individual"])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--steps", type=int, default=100, help="collector steps of the ten arenas a repeat")
    args = parser.parse_args()
    torch.set_num_threads(1)
    table = {}
    for condition in args.conditions:
        seeds = first_seeds(0, ARENAS)
        envs: dict[str, EnvBase] = {
            "serial_pettingzoo": SerialEnv(ARENAS, [lambda s=s, c=condition: make_env(c, s, "cpu") for s in seeds]),
            "batched": PursuitTorchRLEnv(condition, seeds, "cpu"),
        }
        times: dict[str, list[float]] = {name: [] for name in envs}
        for _ in range(args.repeats):
            for name, env in envs.items():
                times[name].append(cpu_per_thousand(env, args.steps))
        row = {name: statistics.median(values) for name, values in times.items()}
        row["ratio"] = row["serial_pettingzoo"] / row["batched"]
        table[condition] = row
        print(
            f"{condition}: SerialEnv of PettingZooWrapper {row['serial_pettingzoo']:.3f} s, "
            f"batched {row['batched']:.3f} s of CPU per 1000 frames: {row['ratio']:.1f}x"
        )
        envs["serial_pettingzoo"].close()
    print(json.dumps(table, indent=1))


if __name__ == "__main__":
    main()
