"""Is the learning unchanged by the compiled training step (issue 46)? 10 seeds of 1p-high trained
to 15,000 episodes at the ``reproduction`` preset by this build and by the reference build (a git
worktree of commit ``--reference``, default ``7a7c4df``, the code before the issue), each run
evaluated by the paper's protocol, and the margins of the two builds tested for equivalence
within ±``--margin`` (0.05).

    python scripts/equivalence_check.py [--seeds 10] [--episodes 15000] [--eval-episodes 1000]
    python scripts/equivalence_check.py --time-only     # one run's training time, both builds
    python scripts/equivalence_check.py --bits 1500     # both builds' learners, bit for bit, after 1500 steps

Each unit of work (a build and a chunk of ``--stack`` seeds, trained stacked in one process:
stacked runs learn exactly as alone, ``tests/test_stacking.py``) writes its results to
``results/speed/equivalence/<build>-seeds<first>-<last>.json`` when it finishes; a rerun skips
the units already there (resumable). When every unit is there, the test goes to
``results/speed/equivalence.json``.

The evaluation (``evaluate_agents``): each run's trained predator against ``FleeingPrey`` (the
held-out prey), and against its own learned prey (ε = 0.1), each time beside always-chase and
always-stalk in its place on the same episodes (paired); the *margin* is the trained
predator's return minus the better fixed mode's. Seeds pair the builds (the same run seed and
evaluation seed in both): the per-seed differences (ours minus reference) get the paired TOST
(``study.statistics.paired_equivalence``); Welch's TOST (``equivalence``) is reported beside it
for runs that diverge as independent ones. Holm over the two margins.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "speed"
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_speed import reference_tree  # noqa: E402  (the benchmark's worktree of the code before)

#: ``python -c WORKER SEEDS EPISODES EVAL_EPISODES``: trains the seeds stacked, evaluates each run,
#: prints one JSON line. Uses only what both builds have.
WORKER = r"""
import json, sys, time
import torch
torch.set_num_threads(1)
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.rules.policies import FleeingPrey
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.train import TrainConfig, Trainer

seeds, episodes, eval_episodes = json.loads(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
configs = [TrainConfig(condition="1p-high", agent=REPRODUCTION, num_envs=32, seed=s, episodes=episodes) for s in seeds]
trainer = Trainer(configs)
start = time.perf_counter()
trainer.run()
train_seconds = time.perf_counter() - start

def margins(result):
    panel = result["panels"][0]
    return {k: panel[k] for k in ("trained", "always_chase", "always_stalk")} | {
        "margin": panel["trained"] - max(panel["always_chase"], panel["always_stalk"])
    }

runs = []
for seed, run in zip(seeds, trainer.runs):
    agents = run.agents
    fleeing = {"predator_0": agents["predator_0"], "prey_0": ScriptedAgent("prey_0", FleeingPrey())}
    evaluation_seed = 100_000 + seed
    options = {"episodes": eval_episodes, "seed": evaluation_seed}
    against_fleeing = evaluate_agents("1p-high", fleeing, prey_epsilon=None, **options)
    against_own = evaluate_agents("1p-high", agents, prey_check=False, **options)
    runs.append(
        {"seed": seed, "env_steps": run.env_steps, "fleeing": margins(against_fleeing), "own": margins(against_own)}
    )
print(json.dumps({"train_seconds": train_seconds, "runs": runs}))
"""

#: ``python -c TIMER EPISODES``: seconds (wall and this process's CPU) to train one run of 1p-high
#: alone to EPISODES.
TIMER = r"""
import json, sys, time
import torch
torch.set_num_threads(1)
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.training.train import TrainConfig, Trainer
episodes = int(sys.argv[1])
trainer = Trainer(TrainConfig(condition="1p-high", agent=REPRODUCTION, num_envs=32, seed=0, episodes=episodes))
start, cpu = time.perf_counter(), time.process_time()
trainer.run()
seconds, cpu_seconds = time.perf_counter() - start, time.process_time() - cpu
print(json.dumps({"seconds": seconds, "cpu_seconds": cpu_seconds, "env_steps": trainer.runs[0].env_steps}))
"""


#: ``python -c BITS CONDITION STEPS``: a SHA-256 of every learner's parameters and priorities after
#: STEPS env steps of one run (seed 3), with its episode count and last losses.
BITS = r"""
import hashlib, json, sys
import torch
torch.set_num_threads(1)
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.training.train import TrainConfig, Trainer
condition, steps = sys.argv[1], int(sys.argv[2])
trainer = Trainer(TrainConfig(condition=condition, agent=REPRODUCTION, num_envs=32, seed=3, episodes=10**9))
for _ in range(steps):
    trainer.step()
digest = hashlib.sha256()
for group in trainer.groups:
    digest.update(group.learner.optimizer.flat.numpy().tobytes())
    digest.update(group.learner.replay.priorities.tobytes())
run = trainer.runs[0]
print(json.dumps({"sha256": digest.hexdigest(), "episodes": run.episodes_done, "losses": run.last_losses}))
"""


def in_tree(tree: Path, code: str, *args: str) -> dict:
    """Run ``code`` with ``tree``'s pursuit_bench first on the path; its last line, as JSON."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    done = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True, cwd=tree)
    if done.returncode != 0:
        raise SystemExit(f"worker {args} in {tree} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def write_json(path: Path, value: object) -> None:
    """Atomically: a file is either absent or complete."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".partial")
    partial.write_text(json.dumps(value, indent=1) + "\n")
    partial.replace(path)


def analyse(units: list[dict], margin: float) -> dict:
    """Per margin (against FleeingPrey, against the own prey): both builds' per-seed values, the
    paired and Welch equivalence tests of ours minus reference, Holm over the two."""
    import numpy as np

    from pursuit_bench import stats

    by_build: dict[str, dict[int, dict]] = {}
    for unit in units:
        for run in unit["runs"]:
            by_build.setdefault(unit["build"], {})[run["seed"]] = run
    seeds = sorted(set(by_build["ours"]) & set(by_build["reference"]))
    tests = {}
    for opponent in ("fleeing", "own"):
        ours = np.array([by_build["ours"][s][opponent]["margin"] for s in seeds])
        theirs = np.array([by_build["reference"][s][opponent]["margin"] for s in seeds])
        tests[opponent] = {
            "ours": ours.tolist(),
            "reference": theirs.tolist(),
            "mean_difference": float((ours - theirs).mean()),
            "difference": stats.paired_difference(ours, theirs),
            "paired": stats.paired_equivalence(ours - theirs, margin),
            "welch_equivalence": stats.equivalence(ours, theirs, margin),
        }
    for key in ("paired", "welch_equivalence"):
        holm = stats.holm([tests[o][key]["p"] for o in tests])
        for opponent, p in zip(tests, holm, strict=True):
            tests[opponent][key]["p_holm"] = float(p)
            tests[opponent][key]["equivalent"] = bool(p <= stats.ALPHA)
    return {"seeds": seeds, "margin": margin, "tests": tests}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--episodes", type=int, default=15_000)
    parser.add_argument("--eval-episodes", type=int, default=1000, help="evaluation episodes per variant")
    parser.add_argument("--stack", type=int, default=5, help="seeds trained stacked in one process")
    parser.add_argument("--margin", type=float, default=0.05)
    parser.add_argument("--reference", default="7a7c4df", help="the commit measured against")
    parser.add_argument("--time-only", action="store_true", help="time one run of each build, nothing else")
    parser.add_argument(
        "--bits", type=int, metavar="STEPS", help="compare both builds' learners bit for bit after STEPS env steps"
    )
    args = parser.parse_args()
    with reference_tree(args.reference) as reference:
        trees = {"ours": ROOT, "reference": reference}
        if args.bits:
            compared = {
                condition: {name: in_tree(tree, BITS, condition, str(args.bits)) for name, tree in trees.items()}
                for condition in ("1p-high", "3p-high-shared")
            }
            builds = {"ours": _commit(ROOT), "reference": _commit(reference)}
            write_json(OUT / "equivalence-bits.json", {"steps": args.bits, "seed": 3, "commits": builds, **compared})
            print(json.dumps(compared))
            return
        if args.time_only:
            timed = {name: in_tree(tree, TIMER, str(args.episodes)) for name, tree in trees.items()}
            write_json(OUT / "equivalence-run-time.json", {"episodes": args.episodes, **timed})
            print(json.dumps(timed))
            return
        run_units(args, trees)


def _commit(tree: Path) -> str:
    """The commit ``tree`` has checked out, with ``+changes`` when its package (``pursuit_bench/``)
    differs from that commit's."""
    head = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run(
        ["git", "-C", str(tree), "status", "--porcelain", "--untracked-files=no", "--", "pursuit_bench"],
        capture_output=True,
        text=True,
    )
    return head.stdout.strip() + ("+changes" if dirty.stdout.strip() else "")


def run_units(args: argparse.Namespace, trees: dict[str, Path]) -> None:
    folder = OUT / "equivalence"
    chunks = [list(range(s, min(s + args.stack, args.seeds))) for s in range(0, args.seeds, args.stack)]
    units = []
    for chunk in chunks:
        for name, tree in trees.items():  # the builds interleaved: a partial result stays balanced
            path = folder / f"{name}-seeds{chunk[0]}-{chunk[-1]}.json"
            if not path.exists():
                start = time.time()
                answer = in_tree(tree, WORKER, json.dumps(chunk), str(args.episodes), str(args.eval_episodes))
                build = subprocess.run(
                    ["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
                ).stdout.strip()
                unit = {"build": name, "commit": build, "episodes": args.episodes, "eval_episodes": args.eval_episodes}
                write_json(path, {**unit, **answer, "wall_seconds": time.time() - start})
                print(f"{path.name}: trained in {answer['train_seconds']:.0f} s", flush=True)
            units.append(json.loads(path.read_text()))
    result = analyse(units, args.margin)
    result["command"] = "python scripts/equivalence_check.py " + " ".join(sys.argv[1:])
    write_json(OUT / "equivalence.json", result)
    for opponent, test in result["tests"].items():
        print(
            f"{opponent}: mean difference {test['mean_difference']:+.4f}, paired TOST p (Holm) "
            f"{test['paired']['p_holm']:.4f} → equivalent within ±{args.margin}: {test['paired']['equivalent']}"
        )


if __name__ == "__main__":
    main()
