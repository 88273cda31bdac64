"""Train and ship each condition's agents into the package (``pursuit_bench/pretrained/``).

The rule, fixed before any of them is trained (issue 67, item 13): in each condition, of the
rule study's hierarchical runs of seeds 0–9, the one whose pool return at 15,000 episodes
(results/rule-study/runs/, the rule study's primary measure, averaged over the predators) is the
median — the lower of the two middle ones, ties by name; not the best of several. That run is
trained again, alone, by this checkout's build at the rule study's plan (the reproduction preset,
15,000 episodes, 32 arenas), and must replay the rule study's committed result at 15,000 episodes
bit for bit against the rule study's population (so the shipped agents are that run's); its
predators and the prey it trained with go into ``DEST/<condition>/<agent>.safetensors`` with a
header saying how they were trained and chosen.

    python scripts/ship_pretrained.py --work /tmp/ship            # all ten conditions
    python scripts/ship_pretrained.py --work /tmp/ship --conditions 1p-high --dry-run
"""

from __future__ import annotations

import argparse
import gzip
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from pursuit_bench import pretrained
from pursuit_bench.benchmark import populations
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.reports import rule_study
from pursuit_bench.training import runs

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "rule-study" / "runs"
SEEDS = range(10)
BUDGET = "15000"


def pool_return(run: dict[str, Any]) -> float:
    """A rule-study run's pool return at 15,000 episodes, averaged over its predators."""
    evaluations = run["pool"][BUDGET]
    predators = next(iter(evaluations.values()))["panels"]
    return sum(rule_study.pooled(evaluations, p)["return"] for p in predators) / len(predators)


def chosen_seed(condition: str) -> tuple[int, dict[int, float]]:
    """The rule's seed in ``condition`` and every candidate's pool return."""
    scores: dict[Path, float] = {}
    for seed in SEEDS:
        path = RESULTS / f"{condition}-hierarchical-seed{seed}.json.gz"
        scores[Path(f"seed{seed}")] = pool_return(json.loads(gzip.decompress(path.read_bytes())))
    chosen = pretrained.median_seed(scores)
    return int(chosen.name.removeprefix("seed")), {int(p.name.removeprefix("seed")): s for p, s in scores.items()}


def train(work: Path, condition: str, seed: int) -> Path:
    """The rule study's run ``<condition>-hierarchical-seed<seed>``, trained alone by its plan."""
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training.sweep import SweepPlan, open_sweep, run_sweep

    plan = SweepPlan(
        conditions=(condition,),
        seeds=1,
        first_seed=seed,
        predators=("hierarchical",),
        agent=PRESETS["reproduction"].replace(episodes=int(BUDGET)),
        episodes=int(BUDGET),
        eval_episodes=1,
        num_envs=32,
        checkpoint_every=1000,
        preset="reproduction",
        keep_checkpoints=(),
    )
    folder = work / condition
    open_sweep(folder, plan)
    if not run_sweep(folder, plan, workers=1, record=False):
        raise SystemExit(f"{folder}: the run did not finish")
    return folder / "runs" / f"{condition}-hierarchical-seed{seed}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--work", type=Path, required=True, help="Where the runs are trained (kept: resumable).")
    parser.add_argument("--conditions", default=",".join(CONDITIONS))
    parser.add_argument("--dest", type=Path, default=pretrained.FOLDER, help="Where to write [the package].")
    parser.add_argument("--dry-run", action="store_true", help="Say the chosen seeds; train nothing.")
    args = parser.parse_args()
    conditions = args.conditions.split(",")
    if unknown := [c for c in conditions if c not in CONDITIONS]:
        print(f"--conditions: unknown {unknown}; expected some of {', '.join(CONDITIONS)}", file=sys.stderr)
        return 2
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    population = populations.FOLDER / populations.RULE_STUDY
    for condition in conditions:
        seed, scores = chosen_seed(condition)
        ranked = ", ".join(f"seed {s}: {v:+.4f}" for s, v in sorted(scores.items()))
        print(f"{condition}: seed {seed} ({scores[seed]:+.4f}) of {ranked}", flush=True)
        if args.dry_run:
            continue
        run = train(args.work, condition, seed)
        committed = json.loads(gzip.decompress((RESULTS / f"{run.name}.json.gz").read_bytes()))
        played = rule_study.evaluate_run(run, population / condition, budgets=(int(BUDGET),))
        if played["pool"][BUDGET] != committed["pool"][BUDGET]:
            raise SystemExit(f"{run.name}: its replay at {BUDGET} episodes differs from the rule study's result")
        state = runs.load_checkpoint(run)
        config, _ = runs.read_config(run)
        provenance = {
            "preset": "reproduction",
            "build": commit,
            "selection": (
                f"the median of the rule study's hierarchical runs of seeds 0-9 by their pool return at {BUDGET} "
                f"episodes (results/rule-study/runs; {ranked})"
            ),
            "pool_return": f"{scores[seed]:+.6f}",
            "replay": f"the rule study's committed result at {BUDGET} episodes, bit for bit",
            "command": f"python scripts/ship_pretrained.py --work WORK --conditions {condition}",
        }
        written = pretrained.export(
            runs.load_agents(run, state),
            config,
            args.dest,
            trained_episodes=int(state["episodes_done"]),
            provenance=provenance,
        )
        size = sum(p.stat().st_size for p in written)
        print(f"{condition}: replayed to the bit; {len(written)} files, {size / 1024:.0f} KiB", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
