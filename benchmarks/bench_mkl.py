"""Cost of pinning MKL's code path (MKL_CBWR=AVX2, what ``import pursuit_bench`` sets unless
given): training steps of the quick preset in 1p-high, in a fresh process each (MKL reads the
setting once), pinned and with MKL free to choose (``MKL_CBWR=AUTO``); medians of
``--repeats``, interleaved, and their ratio (target: within 1.1x).

    python benchmarks/bench_mkl.py [--episodes 300] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

STEP = """
import sys, time
import torch
from pursuit_bench.training.train import Trainer, TrainConfig
torch.set_num_threads(1)
trainer = Trainer(TrainConfig(condition="1p-high", episodes=int(sys.argv[1]), seed=0))
start = time.perf_counter()
trainer.run()
print(time.perf_counter() - start)
"""


def timed(cbwr: str, episodes: int) -> float:
    env = {**os.environ, "MKL_CBWR": cbwr}
    done = subprocess.run([sys.executable, "-c", STEP, str(episodes)], env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(done.stderr)
    return float(done.stdout.split()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    times: dict[str, list[float]] = {"AVX2": [], "AUTO": []}
    for _ in range(args.repeats):
        for cbwr in times:
            times[cbwr].append(timed(cbwr, args.episodes))
    pinned, free = statistics.median(times["AVX2"]), statistics.median(times["AUTO"])
    print(f"training {args.episodes} episodes of 1p-high: MKL_CBWR=AVX2 {pinned:.2f} s, AUTO {free:.2f} s")
    print(f"ratio pinned/free: {pinned / free:.3f} (median of {args.repeats})")


if __name__ == "__main__":
    main()
