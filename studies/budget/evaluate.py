"""The budget study's evaluation of one judged run (PROTOCOL.md, "Evaluation"), written before
any judged run was evaluated: the run's compact result, ``<out>/<run>.json.gz``, written whole or
not at all and committed as it lands, so that a later machine trains on only the runs without one.

Run by the driver (``run.py``) in a process of its own with this checkout's package (the driver
trains with the pinned build): the evaluation may run on a later build than the training only
where it gives the rule study's committed result bit for bit (PROTOCOL.md, "Build"), so before
anything else the run's 15,000-episode checkpoint is replayed against the rule study's population
by the rule study's evaluation and must equal ``results/rule-study/runs/<run>.json.gz`` there.

What it holds, by the protocol (60 episodes a variant and member, seed 12345, common random
numbers, predators greedy, a learned prey ε-greedy with ε 0.1):

- ``same_budget``: at each budget, against the population of that budget (primary at 10^6;
  secondaries 1, 3, 4), per member the panels (as trained, as always-chase, as always-stalk), the
  standard error as trained, the capture rate and the prey's outcomes in the trained variant's
  episodes (secondary 6);
- ``first_population``: at each budget after the first, against the 15,000-episode population
  (secondary 2; at 15,000 it is ``same_budget``'s);
- ``paper``: at 10^6, the predators with their own co-trained prey by the paper's protocol (1000
  episodes a variant; secondary 5): each panel's three means and standard errors, the capture
  rate, the co-trained prey's outcomes (secondary 6).

With ``--first-part`` the run is a first part alone (the driver's ``--paper-first``, added after
the protocol, descriptive: PLAN.md, "Fig. 2 at 15,000 episodes"): its checkpoint must be at the
first budget; after the same replay, and, where the judged run's result is committed, a check
that the first part played against the first budget's population gives that result's
``same_budget`` at 15,000 to the bit, only the paper's comparison at its end is written (format
``budget-study-paper-1``), so that the report draws Fig. 2 of the same runs at 15,000 episodes
beside 10^6.

    python studies/budget/evaluate.py RUN --condition 3p-low-shared --build d9886b9… \\
        --populations pursuit_bench/pretrained/populations --out results/budget-study/runs
"""

from __future__ import annotations

import argparse
import gzip
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
FORMAT = "budget-study-run-1"
#: A first part's compact result (``--first-part``): the paper's comparison at 15,000 episodes.
FIRST_PART_FORMAT = "budget-study-paper-1"
BUDGETS = (15_000, 50_000, 150_000, 500_000, 1_000_000)
EPISODES = 60
PAPER_EPISODES = 1000
EVAL_SEED = 12345


def population_name(budget: int) -> str:
    """The population of one budget (``design.population_name``'s)."""
    return f"budget-study-ep{budget}"


def checkpoint_of(budget: int, budgets: tuple[int, ...]) -> str:
    """The run folder's checkpoint at ``budget``: the last budget's is the final one."""
    from pursuit_bench.training import runs

    return runs.CHECKPOINT if budget == budgets[-1] else runs.milestone_checkpoint(budget)


def replay(run: Path, condition: str, committed: Path, first: int = BUDGETS[0], checkpoint: str | None = None) -> None:
    """SystemExit unless this build, playing the run's checkpoint at ``first`` episodes (the rule
    study's end of training; ``checkpoint``, by default the run's kept one of that budget) against
    the rule study's population, gives the rule study's committed result there bit for bit."""
    from pursuit_bench.benchmark import populations
    from pursuit_bench.reports import rule_study

    path = committed / f"{run.name}.json.gz"
    if not path.exists():
        raise SystemExit(f"{path}: no committed rule-study result to replay {run.name} against")
    expected = json.loads(gzip.decompress(path.read_bytes()))
    played = rule_study.evaluate_checkpoint(
        run, checkpoint or checkpoint_of(first, BUDGETS), populations.FOLDER / populations.RULE_STUDY / condition
    )
    if played != expected["pool"][str(first)]:
        raise SystemExit(f"{run.name}: this build's replay at {first} episodes differs from the rule study's result")


def evaluate(
    run: Path,
    condition: str,
    populations: Path,
    *,
    budgets: tuple[int, ...] = BUDGETS,
    episodes: int = EPISODES,
    paper_episodes: int = PAPER_EPISODES,
    seed: int = EVAL_SEED,
) -> dict[str, Any]:
    """The run's evaluations by the protocol (the module's docstring says what each holds)."""
    from pursuit_bench.reports import rule_study
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import PROTOCOL

    def against(budget: int, population: int) -> dict[str, Any]:
        folder = populations / population_name(population) / condition
        if not (folder / "population.json").is_file():
            raise SystemExit(f"{folder}: no population written there")
        checkpoint = checkpoint_of(budget, budgets)
        return rule_study.evaluate_checkpoint(run, checkpoint, folder, episodes=episodes, seed=seed, outcomes=True)

    same = {str(b): against(b, b) for b in budgets}
    first = {str(b): against(b, budgets[0]) for b in budgets[1:]}
    return {
        "protocol": PROTOCOL,
        "episodes": episodes,
        "eval_seed": seed,
        "budgets": list(budgets),
        "same_budget": same,
        "first_population": first,
        "paper": paper_comparison(run, condition, runs.CHECKPOINT, paper_episodes, seed),
    }


def paper_comparison(run: Path, condition: str, checkpoint: str, episodes: int, seed: int) -> dict[str, Any]:
    """The run's predators at ``checkpoint`` with their own co-trained prey by the paper's
    protocol: each panel's three means and standard errors, the capture rate, the prey's outcomes."""
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import Actor, evaluate_agents

    config, learned, _ = runs.described(run, checkpoint)
    protocol = dict(config.protocol)
    agents: dict[str, Actor] = dict(learned)
    paper = evaluate_agents(
        condition, agents, episodes=episodes, seed=seed, prey_check=False, outcomes=True, **protocol
    )
    kept = ("trained", "always_chase", "always_stalk", "stderr")
    return {
        "episodes": episodes,
        "panels": {p["predator"]: {k: p[k] for k in kept} for p in paper["panels"]},
        "capture_rate": paper["capture_rate"],
        "prey": paper["prey_outcomes"],
    }


def first_part_episodes(run: Path, first: int) -> None:
    """SystemExit unless the run folder's last checkpoint is a first part's end, ``first`` episodes."""
    from pursuit_bench.training import runs

    done = int(runs.load_checkpoint(run)["episodes_done"])
    if done != first:
        raise SystemExit(f"{run}: its checkpoint holds {done} episodes, not the first part's {first}")


def same_as_judged(run: Path, condition: str, populations: Path, judged: Path, first: int, episodes: int) -> bool:
    """Whether the budget study's committed result of this run (``judged/<run>.json.gz``) is there
    to check against; SystemExit if it is and this first part's end, played against the first
    budget's population by the protocol, differs from its ``same_budget`` at that budget in any bit
    (the first part is the judged run's own 15,000 episodes, evaluated as its result was)."""
    from pursuit_bench.reports import rule_study
    from pursuit_bench.training import runs

    path = judged / f"{run.name}.json.gz"
    if not path.exists():
        return False
    committed = json.loads(gzip.decompress(path.read_bytes()))
    folder = populations / population_name(first) / condition
    played = rule_study.evaluate_checkpoint(
        run, runs.CHECKPOINT, folder, episodes=episodes, seed=EVAL_SEED, outcomes=True
    )
    if json.loads(json.dumps(played)) != committed["same_budget"][str(first)]:
        raise SystemExit(f"{run.name}: its first part differs from the budget study's judged run at {first} episodes")
    return True


def evaluate_first_part(run: Path, condition: str, first: int, paper_episodes: int, checked: bool) -> dict[str, Any]:
    """A first part's compact result (PLAN.md, "Fig. 2 at 15,000 episodes", descriptive): the
    paper's comparison at its end; ``checked``: whether :func:`same_as_judged` compared it."""
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import PROTOCOL

    paper = paper_comparison(run, condition, runs.CHECKPOINT, paper_episodes, EVAL_SEED)
    return {"protocol": PROTOCOL, "eval_seed": EVAL_SEED, "budget": first, "same_as_judged": checked, "paper": paper}


def write(out: Path, run: Path, condition: str, build: str, result: dict[str, Any], form: str = FORMAT) -> Path:
    """The compact result ``out/<run>.json.gz`` of format ``form``, the run's identity first."""
    from pursuit_bench.io.files import atomic_write_bytes

    kind = next(k for k in ("hierarchical", "flat") if f"-{k}-seed" in run.name)
    evaluated_by = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    identity = {
        "format": form,
        "name": run.name,
        "condition": condition,
        "kind": kind,
        "seed": int(run.name.rsplit("seed", 1)[1]),
        "build": build,
        "evaluated_by": evaluated_by.strip(),
    }
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{run.name}.json.gz"
    atomic_write_bytes(path, gzip.compress(json.dumps({**identity, **result}).encode(), mtime=0))
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="A judged run folder trained to its last budget.")
    parser.add_argument("--condition", required=True)
    parser.add_argument("--build", required=True, help="The commit that trained the run.")
    parser.add_argument("--populations", type=Path, required=True, help="Where budget-study-ep<B>/ lie.")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--budgets", default=",".join(str(b) for b in BUDGETS))
    parser.add_argument("--episodes", type=int, default=EPISODES, help="(trying the driver only)")
    parser.add_argument("--paper-episodes", type=int, default=PAPER_EPISODES, help="(trying the driver only)")
    parser.add_argument("--rule-results", type=Path, default=ROOT / "results" / "rule-study" / "runs")
    parser.add_argument(
        "--judged-results",
        type=Path,
        default=ROOT / "results" / "budget-study" / "runs",
        help="With --first-part: the judged runs' committed results, which a first part must match at its budget.",
    )
    parser.add_argument("--no-replay-check", action="store_true", help="(trying the driver only)")
    parser.add_argument(
        "--first-part",
        action="store_true",
        help="The run is a first part (trained to the first budget only): replayed at its end, then only "
        'the paper\'s comparison there is written (PLAN.md, "Fig. 2 at 15,000 episodes").',
    )
    args = parser.parse_args()
    budgets = tuple(int(b) for b in args.budgets.split(","))
    if args.first_part:
        first_part_episodes(args.run, budgets[0])
    if not args.no_replay_check:
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "pursuit_bench", "studies/budget"],
            cwd=ROOT, capture_output=True, text=True,
        ).stdout.split("\n")  # fmt: skip
        if any(line.endswith(".py") for line in dirty):
            raise SystemExit(f"{ROOT}: uncommitted code changes: a study's evaluation is made by committed code only")
        from pursuit_bench.training import runs

        # a first part's end is its last checkpoint: it keeps none of its own length
        replay(args.run, args.condition, args.rule_results, checkpoint=runs.CHECKPOINT if args.first_part else None)
    if args.first_part:
        checked = not args.no_replay_check and same_as_judged(
            args.run, args.condition, args.populations, args.judged_results, budgets[0], args.episodes
        )
        result = evaluate_first_part(args.run, args.condition, budgets[0], args.paper_episodes, checked)
        print(write(args.out, args.run, args.condition, args.build, result, FIRST_PART_FORMAT))
        return 0
    result = evaluate(
        args.run,
        args.condition,
        args.populations,
        budgets=budgets,
        episodes=args.episodes,
        paper_episodes=args.paper_episodes,
    )
    print(write(args.out, args.run, args.condition, args.build, result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
