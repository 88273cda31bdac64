"""Evaluation with common random numbers (issue 47) against the code before it: the speed of one
evaluation as the pool study plays it (a shipped condition's agents, predators greedy, the prey
ε-greedy, every predator replaced in turn by always-chase and always-stalk, no prey check), and
how much the paired difference trained − baseline moves between evaluation seeds.

    python benchmarks/bench_evaluate.py [--condition 2p-high-individual] [--episodes 60]
        [--repeats 3] [--seeds 8] [--out results/speed/evaluate.json]

The code before is ``pursuit_bench/training/evaluate.py`` as it stood at commit :data:`BEFORE`
(read with ``git show``), run in the same process on the same agents. Speed: the median of
``--repeats`` timed evaluations of each, alternated; the new one run twice must give the same
numbers (it says so). Noise: for ``--seeds`` evaluation seeds, each predator's mean paired
difference trained − always-chase and trained − always-stalk over the episodes; their standard
deviation over the seeds, before and after, and the standard deviation of the per-episode
differences (after only: before, the variants' episodes are not matched one to one). Also each
one's mean episode length as trained: the code before kept the first episodes to *finish*, so with
as many arenas as episodes it dropped the long ones and played fewer steps.
One torch thread.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
import types
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pursuit_bench import pretrained
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.training import evaluate

ROOT = Path(__file__).resolve().parents[1]
#: The last commit whose evaluation is the code before common random numbers.
BEFORE = "7a7c4df"


def old_module() -> types.ModuleType:
    """``training/evaluate.py`` as it stood at :data:`BEFORE`, as a module of its own."""
    source = subprocess.run(
        ["git", "show", f"{BEFORE}:pursuit_bench/training/evaluate.py"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    module = types.ModuleType("evaluate_before")
    sys.modules[module.__name__] = module  # dataclasses look their module up
    exec(compile(source, f"evaluate.py@{BEFORE}", "exec"), module.__dict__)
    return module


def one(module: Any, condition: str, episodes: int, seed: int) -> tuple[float, dict[str, Any]]:
    agents = pretrained.load(condition)  # read afresh: the code before draws from the learners' generators
    start = time.perf_counter()
    result = module.evaluate_agents(condition, agents, episodes=episodes, seed=seed, prey_check=False)
    return time.perf_counter() - start, result


def differences(result: dict[str, Any]) -> dict[str, float]:
    return {
        f"{p['predator']} − {base}": p["trained"] - p[base]
        for p in result["panels"]
        for base in ("always_chase", "always_stalk")
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--condition", default="2p-high-individual")
    parser.add_argument("--episodes", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    torch.set_num_threads(1)
    before = old_module()
    one(evaluate, args.condition, 4, 0)  # compile the kernels once for both
    times: dict[str, list[float]] = {"before": [], "after": []}
    repeated, lengths = [], {}
    for _ in range(args.repeats):
        took, result = one(before, args.condition, args.episodes, 12345)
        times["before"].append(took)
        lengths["before"] = result["episode_length"]
        took, result = one(evaluate, args.condition, args.episodes, 12345)
        times["after"].append(took)
        lengths["after"] = result["episode_length"]
        repeated.append(json.dumps(result["panels"]))
    speed = {k: statistics.median(v) for k, v in times.items()}
    same = len(set(repeated)) == 1
    print(
        f"{args.condition}, {args.episodes} episodes: before {speed['before']:.2f} s, after {speed['after']:.2f} s, "
        f"speed-up {speed['before'] / speed['after']:.2f}x (median of {args.repeats}); repeats exactly: {same}; "
        f"mean episode length as trained: before {lengths['before']:.1f}, after {lengths['after']:.1f} steps"
    )
    spread: dict[str, dict[str, Any]] = {}
    for name, module in (("before", before), ("after", evaluate)):
        rows = [differences(one(module, args.condition, args.episodes, 1000 + s)[1]) for s in range(args.seeds)]
        spread[name] = {k: float(np.std([r[k] for r in rows], ddof=1)) for k in rows[0]}
    episode_sd: dict[str, float] = {}
    result = one(evaluate, args.condition, args.episodes, 1000)[1]
    for p in result["panels"]:
        trained = np.array(p["episode_returns"]["trained"])
        for base in ("always_chase", "always_stalk"):
            episode_sd[f"{p['predator']} − {base}"] = float(
                np.std(trained - np.array(p["episode_returns"][base]), ddof=1)
            )
    for key in spread["before"]:
        print(
            f"  SD over {args.seeds} evaluation seeds of {key}: before {spread['before'][key]:.4f}, "
            f"after {spread['after'][key]:.4f}"
        )
    out = {
        "command": "python benchmarks/bench_evaluate.py " + " ".join(sys.argv[1:]),
        "condition": args.condition,
        "episodes": args.episodes,
        "before_commit": BEFORE,
        "seconds": times,
        "median_seconds": speed,
        "speedup": speed["before"] / speed["after"],
        "repeats_exactly": same,
        "mean_episode_length_trained": lengths,
        "difference_sd_over_seeds": spread,
        "evaluation_seeds": [1000 + s for s in range(args.seeds)],
        "episode_difference_sd_after": episode_sd,
    }
    if args.out is not None:
        atomic_write_text(args.out, json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
