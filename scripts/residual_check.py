"""Issue 48's check of a new user: does a short residual run keep the rule where nothing shows a
correction pays?

For each seed: ``pursuit-bench train --condition 1p-high --predator residual --seed S --episodes 300
--preset reproduction --physics numpy --no-record``, then ``pursuit-bench analyze RUN --episodes 30``;
writes, per seed, the share of analysed states in which the greedy predator corrected the rule,
the corrections it used, and what its correction learner had to learn from (corrected transitions
stored, updates made, the largest C(s, m, k) over k ≠ 0 in the analysed states).

    python scripts/residual_check.py --out runs/residual-check --results results/residual/new-user-check.json
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from pursuit_bench.io.files import atomic_write_text

SEEDS = (1, 2, 3)
EPISODES, ANALYSED = 300, 30


def check(run: Path, seed: int) -> dict[str, object]:
    """Train and analyse one seed in ``run``; what the check reports of it."""
    cli = [sys.executable, "-m", "pursuit_bench.cli.main"]
    train = ["train", "--condition", "1p-high", "--predator", "residual", "--seed", str(seed)]
    train += ["--episodes", str(EPISODES), "--preset", "reproduction", "--physics", "numpy", "--no-record"]
    subprocess.run([*cli, *train, "--out", str(run), "--force"], check=True, capture_output=True)
    subprocess.run([*cli, "analyze", str(run), "--episodes", str(ANALYSED)], check=True, capture_output=True)
    predator = json.loads((run / "analysis.json").read_text())["predators"]["predator_0"]
    used = {int(k): n for k, n in predator["correction_by_distance"]["used"].items()}

    from pursuit_bench.agents.residual import ResidualLearner
    from pursuit_bench.training.runs import load_agents

    learner = load_agents(run)["predator_0"].learner
    assert isinstance(learner, ResidualLearner)
    return {
        "seed": seed,
        "states": sum(used.values()),
        "corrected_share": 1 - used.get(0, 0) / sum(used.values()),
        "used": used,
        "corrected_transitions": int(learner.correction_replay.size[0]),  # the replay holds them all
        "correction_updates": int(learner.correction_adam.steps[0]),
        "transitions": int(learner.steps),
    }


def largest_correction(run: Path) -> float:
    """The largest C(s, m, k), k ≠ 0, of the run's predator over the analysed episodes' states."""
    from pursuit_bench.agents.residual import ResidualLearner
    from pursuit_bench.training.evaluate import run_episodes
    from pursuit_bench.training.runs import load_agents

    agents = load_agents(run)
    learner = agents["predator_0"].learner
    assert isinstance(learner, ResidualLearner)
    seen: list[np.ndarray] = []
    run_episodes(
        "1p-high",
        agents,
        ANALYSED,
        seed=0,
        num_envs=32,
        epsilons={"prey_0": 0.1},
        on_step=lambda obs, actions, done, counted: seen.append(obs[counted, 0].copy()),
    )
    obs = np.concatenate(seen)[None]
    return float(learner.correction_values(obs)[..., 1:].max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="Folder for the runs.")
    parser.add_argument("--results", type=Path, required=True, help="JSON file written.")
    args = parser.parse_args()
    seeds = []
    for seed in SEEDS:
        run = args.out / f"residual-1p-high-seed{seed}"
        entry = check(run, seed)
        entry["largest_correction_value"] = largest_correction(run)
        seeds.append(entry)
        print(json.dumps(entry))
    command = "python scripts/residual_check.py --out RUNS --results " + str(args.results)
    atomic_write_text(args.results, json.dumps({"command": command, "seeds": seeds}, indent=1) + "\n")


if __name__ == "__main__":
    main()
