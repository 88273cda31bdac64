"""What the OpenBLAS pin costs on this CPU: one run's training at the ``reproduction`` preset with
OpenBLAS's Haswell kernels (the package's pin, ``OPENBLAS_CORETYPE=Haswell``: the same bits on
every x86 CPU since 2013) against another of its kernel sets (``--other``; the default, SkylakeX, is
what OpenBLAS picks by itself on a CPU with AVX-512), in one run of the benchmark, repeats
interleaved.

    python benchmarks/bench_blas_kernels.py [--repeats 5] [--steps 1500] [--other SkylakeX]

Prints, for 1p-high and 3p-high-shared, each setting's transitions/s (medians of ``--repeats``,
one worker process each, timed by its CPU time, every thread pool at one thread) and the ratio,
and the kernels each loaded OpenBLAS reported (threadpoolctl), so that a setting the CPU cannot
run (OpenBLAS then falls back) shows. The pin stays whatever this prints: it keeps a run's bits the
same across machines (docs/departures.md, "Reproducibility across machines").
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: ``python -c WORKER CONDITION STEPS``: one run's transitions/s by the CPU time, and the kernels.
WORKER = r"""
import json, sys, time
import torch
torch.set_num_threads(1)
from threadpoolctl import threadpool_info
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.training.train import TrainConfig, Trainer

condition, steps = sys.argv[1], int(sys.argv[2])
agent = REPRODUCTION.replace(learning_starts=500)
trainer = Trainer(TrainConfig(condition=condition, agent=agent, num_envs=32, seed=0, episodes=10**9))
while trainer.groups[0].learner.steps < agent.learning_starts + 32:
    trainer.step()  # the replays past learning_starts: we time learning, not warm-up
start = time.process_time()
for _ in range(steps):
    trainer.step()
rate = steps * 32 / (time.process_time() - start)
kernels = sorted({i["architecture"] for i in threadpool_info() if i["internal_api"] == "openblas"})
print(json.dumps({"rate": rate, "kernels": kernels}))
"""

ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def measure(coretype: str, condition: str, steps: int) -> dict:
    env = {**os.environ, **ONE_THREAD, "OPENBLAS_CORETYPE": coretype}
    command = [sys.executable, "-c", WORKER, condition, str(steps)]
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"worker {coretype} {condition} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1500, help="env steps timed per measurement")
    parser.add_argument("--other", default="SkylakeX", help="the OpenBLAS kernels measured beside Haswell")
    args = parser.parse_args()
    settings = ("Haswell", args.other)
    print(f"one run alone, reproduction preset, 32 arenas; medians of {args.repeats}, CPU time, one thread")
    print(f"\n| condition | {settings[0]} (transitions/s) | {settings[1]} | {settings[1]} / {settings[0]} |")
    print("|---|---:|---:|---:|")
    reported = {}
    for condition in ("1p-high", "3p-high-shared"):
        rates: dict[str, list[float]] = {s: [] for s in settings}
        for _ in range(args.repeats):
            for setting in settings:
                answer = measure(setting, condition, args.steps)
                rates[setting].append(answer["rate"])
                reported[setting] = answer["kernels"]
        pinned, other = (statistics.median(rates[s]) for s in settings)
        print(f"| {condition} | {pinned:,.0f} | {other:,.0f} | {other / pinned:.2f}x |")
    print()
    for setting in settings:
        print(f"OPENBLAS_CORETYPE={setting}: the loaded OpenBLAS libraries report {', '.join(reported[setting])}")


if __name__ == "__main__":
    main()
