"""The leaderboard's BenchMARL rows (issue 65, PLAN.md): IPPO, MAPPO and IQL as predators in
1p-high, 2p-low-shared and 3p-high-individual, seeds 0–2, each trained for FRAMES[condition] env
steps by ``pursuit-bench marl train`` (the library's defaults, its in-training evaluation off) and
scored as every row is (``score --episodes 20 --seed 12345`` against the rule-study population);
first, the rows they are compared with: our flat DQN and hierarchical predator in the same
conditions and seeds, 15,000 episodes of the reproduction preset (``pursuit-bench train``).

    nohup python studies/marl/run.py --work /work/marl-study --results results/marl > marl.out 2>&1 &

One run at a time, in the order of ``RUNS``; a run's folder is ``WORK/runs/NAME`` (BenchMARL's
checkpoints: rerunning resumes there), its score ``RESULTS/NAME.score.json`` (committed). A run
with a score is done and skipped; ``--only`` names the runs to do. SIGTERM or SIGINT stops the
run in progress (it resumes from its last checkpoint, up to ten batches back) and the driver.
Progress in ``WORK/progress.log``.
"""

from __future__ import annotations

import argparse
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ALGORITHMS = ("ippo", "mappo", "iql")
#: The budget in env steps: what the flat DQN's 15,000 episodes took in the condition at the
#: reproduction preset (seed 0; PLAN.md), rounded up to whole BenchMARL batches of 6000.
FRAMES = {"2p-low-shared": 258_000, "3p-high-individual": 972_000, "1p-high": 3_804_000}
SEEDS = (0, 1, 2)
#: Our learners, the comparison (PLAN.md): ``pursuit-bench train --predator KIND``.
OURS = ("flat", "hierarchical")
EPISODES = 15_000
#: Ours first (about half a core-hour in all), then BenchMARL's; cheapest condition first, so that
#: every algorithm has rows early.
RUNS = [(c, k, s) for c in FRAMES for s in SEEDS for k in OURS] + [
    (c, a, s) for c in FRAMES for s in SEEDS for a in ALGORITHMS
]
SCORE = ("--episodes", "20", "--seed", "12345")

stopping: list[int] = []
child: list[subprocess.Popen[Any]] = []


def log(work: Path, text: str) -> None:
    line = f"{time.strftime('%Y-%m-%d %H:%M:%S')} {text}"
    with (work / "progress.log").open("a") as f:
        f.write(line + "\n")
    print(line, flush=True)


def stop(signum: int, frame: Any) -> None:
    stopping.append(signum)
    for process in child:
        process.send_signal(signal.SIGTERM)


def run(command: list[str]) -> int:
    process = subprocess.Popen(command)
    child[:] = [process]
    try:
        return process.wait()
    finally:
        child.clear()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--work", type=Path, required=True, help="Run folders, scores in progress, the log.")
    parser.add_argument("--results", type=Path, required=True, help="Where each run's score.json lands.")
    parser.add_argument(
        "--only",
        default=None,
        help="Comma-separated run names (e.g. 3p-high-individual-iql-seed2): only these, in RUNS' order "
        "(a session's last hour fits a short row, not the next in order).",
    )
    args = parser.parse_args()
    names = [f"{c}-{a}-seed{s}" for c, a, s in RUNS]
    only = set(names) if args.only is None else set(args.only.split(","))
    if unknown := sorted(only - set(names)):
        print(f"--only: unknown run {', '.join(unknown)}; expected names such as {names[-1]}", file=sys.stderr)
        sys.exit(2)
    args.work.mkdir(parents=True, exist_ok=True)
    args.results.mkdir(parents=True, exist_ok=True)
    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    cli = [sys.executable, "-m", "pursuit_bench.cli.main"]
    for condition, algorithm, seed in RUNS:
        if stopping:
            log(args.work, "stopped; rerun to resume")
            return
        name = f"{condition}-{algorithm}-seed{seed}"
        result = args.results / f"{name}.score.json"
        if result.exists() or name not in only:
            continue
        folder = args.work / "runs" / name
        if algorithm in OURS:
            log(args.work, f"{name}: training to {EPISODES} episodes")
            train = ["train", "--resume", "--no-record"] if (folder / "checkpoint.pt").is_file() else [
                *("train", "--condition", condition, "--predator", algorithm, "--preset", "reproduction"),
                *("--episodes", str(EPISODES), "--seed", str(seed), "--no-record", "--force"),
            ]  # fmt: skip
            team = str(folder)
        else:
            log(args.work, f"{name}: training to {FRAMES[condition]} frames")
            train = ["marl", "train", "--algorithm", algorithm, "--condition", condition, "--set", "evaluation=false"]
            train += ["--frames", str(FRAMES[condition]), "--seed", str(seed)]
            team = str(folder / "predator.safetensors")
        code = run([*cli, *train, "--out", str(folder)])
        if stopping or code != 0:
            log(args.work, f"{name}: {'stopped' if stopping else f'failed ({code})'}; rerun to resume")
            sys.exit(0 if stopping else 1)
        scored = args.work / "scores" / name
        shutil.rmtree(scored, ignore_errors=True)
        code = run([*cli, "score", team, "--role", "predator", "--conditions", condition, *SCORE, "--out", str(scored)])
        if stopping or code != 0:
            log(args.work, f"{name}: scoring {'stopped' if stopping else f'failed ({code})'}; rerun to resume")
            sys.exit(0 if stopping else 1)
        partial = result.with_suffix(".partial")
        shutil.copyfile(scored / "score.json", partial)
        partial.replace(result)
        log(args.work, f"{name}: scored, {result}")
    log(args.work, "every run scored" if args.only is None else "every run named by --only scored")


if __name__ == "__main__":
    main()
