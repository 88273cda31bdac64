"""Does this build give a committed study job's result bit for bit? Trains one judged run of
the rule study again (its preset, budget, seed and checkpoints), evaluates it against the
committed population as the study did (``rule_study.evaluate_run``) and compares every number
with the run's committed compact result (issue 62: evaluation changed, results must not).

    python benchmarks/replay_job.py --name 3p-low-shared-hierarchical-seed0 [--work DIR]

Prints ``identical`` (exit 0) or the first differing entries (exit 1).
"""

from __future__ import annotations

import argparse
import gzip
import json
import re
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def differences(a: Any, b: Any, where: str = "") -> list[str]:
    """Every path at which two JSON values differ (floats compared exactly)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{where}/{k}: only in one" for k in sorted(set(a) ^ set(b))]
        return out + [d for k in sorted(set(a) & set(b)) for d in differences(a[k], b[k], f"{where}/{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True)) for d in differences(x, y, f"{where}[{i}]")]
    return [] if a == b else [f"{where}: {a!r} != {b!r}"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--name", default="3p-low-shared-hierarchical-seed0")
    parser.add_argument("--work", type=Path, default=Path("/tmp/pursuit-bench-replay"))
    args = parser.parse_args()
    import torch

    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.reports import rule_study
    from pursuit_bench.training.sweep import SweepPlan, open_sweep, run_sweep

    torch.set_num_threads(1)
    committed = json.loads(gzip.decompress((ROOT / "results/rule-study/runs" / f"{args.name}.json.gz").read_bytes()))
    match = re.fullmatch(r"(.+)-(hierarchical|flat)-seed(\d+)", args.name)
    if match is None:
        print(f"--name {args.name}: expected CONDITION-KIND-seedN", file=sys.stderr)
        return 2
    condition, kind, seed = match[1], match[2], int(match[3])
    episodes = rule_study.BUDGETS[-1]
    plan = SweepPlan(  # as studies/rule-value/run.py plans a judged run
        conditions=(condition,), seeds=1, first_seed=seed, predators=(kind,),
        agent=PRESETS["reproduction"].replace(episodes=episodes), episodes=episodes, eval_episodes=1,
        num_envs=32, checkpoint_every=1000, preset="reproduction", keep_checkpoints=rule_study.BUDGETS[:-1],
    )  # fmt: skip
    args.work.mkdir(parents=True, exist_ok=True)
    open_sweep(args.work, plan)
    start = time.process_time()
    run_sweep(args.work, plan, workers=1, record=False)
    trained = time.process_time() - start
    folder = args.work / "runs" / args.name
    start = time.process_time()
    result = rule_study.evaluate_run(folder, ROOT / "pursuit_bench/pretrained/populations/rule-study" / condition)
    evaluated = time.process_time() - start
    found = differences({k: committed[k] for k in result}, json.loads(json.dumps(result)))
    print(f"{args.name}: trained in {trained:.1f} s, evaluated in {evaluated:.1f} s of CPU (this process)")
    print("identical" if not found else "\n".join(["DIFFERENT:", *found[:20]]))
    return 0 if not found else 1


if __name__ == "__main__":
    sys.exit(main())
