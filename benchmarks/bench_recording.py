"""Recording overhead: the paper's evaluation of the same agents with and without a Rerun
recording, in one process and one run; medians of ``--repeats``. Also the file size per episode.

    python benchmarks/bench_recording.py [--run runs/NAME] [--episodes 200] [--repeats 3]

Without ``--run`` it first trains a short run of ``--condition`` (quick preset, 300 episodes)
so that the episodes look like a real evaluation's.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import torch

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.training import runs
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.train import TrainConfig, Trainer
from pursuit_bench.trajectories.recording import Recorder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=Path, default=None, help="A trained run folder (else: train one).")
    parser.add_argument("--condition", default="2p-high-shared")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    torch.set_num_threads(1)
    if args.run is not None:
        config, _ = runs.read_config(args.run)
        trainer = Trainer(config)
        trainer.load_state_dict(runs.load_checkpoint(args.run))
    else:
        trainer = Trainer(TrainConfig(condition=args.condition, episodes=300))
        trainer.run()
    agents, condition = trainer.agents, trainer.config.condition
    names = list(CONDITIONS[condition].agent_names)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "eval.rrd"

        def evaluate(record: bool) -> float:
            start = time.perf_counter()
            recorder = Recorder(path, names, {"condition": condition}) if record else None
            evaluate_agents(condition, agents, episodes=args.episodes, seed=0, recorder=recorder)  # type: ignore[arg-type]
            if recorder is not None:
                recorder.close()
            return time.perf_counter() - start

        evaluate(False)  # warm up
        plain = statistics.median(evaluate(False) for _ in range(args.repeats))
        recorded = statistics.median(evaluate(True) for _ in range(args.repeats))
        size = path.stat().st_size
    print(f"eval of {condition}, {args.episodes} episodes per variant, {len(names) * 2 - 1} variants")
    print(f"without recording {plain:6.2f} s   with recording {recorded:6.2f} s   ratio {recorded / plain:.2f}x")
    per_episode = size / args.episodes / 1e3
    print(f"file {size / 1e6:.1f} MB for {args.episodes} recorded episodes: {per_episode:.1f} kB per episode")


if __name__ == "__main__":
    main()
