"""Training and evaluation against the code before the compiled update (issue 35), measured in one
run: the reference is a git worktree of commit ``--reference`` (default ``8ec03b5``, the last
commit before it), imported in its own processes beside ours, repeats interleaved.

    python benchmarks/bench_speed.py [--repeats 3] [--episodes 1000] [--reference 8ec03b5]
        [--sections train,parts,stacked,update,eval] [--clock cpu|wall]

Prints, each as a median of ``--repeats`` and as today / reference:

- transitions/s (arena-steps of one run, every agent learning) of one run at the ``reproduction``
  preset (32 arenas, one update per env step) in 1p-high and in 3p-high-shared;
- (``parts``) the milliseconds of one such env step in each of its parts (env step, acting,
  storing, the update with the replay's sampling and priorities, the rest of the loop), both
  builds, timed by wrapping the calls each part is made of, by name (a name a build lacks is
  skipped);
- 10 seeds of 1p-high stacked in one process, and the ratio to one run alone (one after another,
  10 runs take 10 times one): ours against ours, and ours stacked against the reference alone;
- one member-update (batch 64, the prey-sized network, replay filled) at 1 and 24 members, in ms
  and as a multiple of its floating-point bound (its matrix products' FLOPs over the rate of
  256×256 products measured in the same process);
- evaluation episodes/s of the paper's protocol (the shipped 1p-high agents, ``--episodes`` per
  variant), and whether the two evaluations' results are identical.

The training measurements (transitions/s, the parts, the stacks) are timed by the worker's CPU
time by default (``--clock cpu``): on a machine others share, the wall clock counts the time the
worker waits for a core, which moves with their load (two runs of the same command differed by
0.1–0.6 in the ratio, docs/benchmarks.md), while a one-threaded worker's CPU time is what its steps
cost. ``--clock wall`` times them by the wall clock, for a machine to itself.

One torch thread, as on a busy two-core machine. Needs git (the worktree is made under the
system's temporary folder and removed at the end).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_train import member_update_flops  # noqa: E402  (the same bound as the stacking benchmark's)

#: What a worker process measures: ``python bench_speed.py --worker KIND ARGS…`` prints one JSON line.
WORKER = r"""
import json, os, statistics, sys, time
import numpy as np
import torch
torch.set_num_threads(1)
import pursuit_bench
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.training.train import TrainConfig, Trainer

kind, args = sys.argv[1], sys.argv[2:]
AGENT = REPRODUCTION.replace(learning_starts=500)
# the training measurements' clock: the process's CPU time, or the wall clock
clock = time.process_time if os.environ.get("BENCH_CLOCK", "cpu") == "cpu" else time.perf_counter

def transitions_per_second(condition, runs, steps):
    configs = [TrainConfig(condition=condition, agent=AGENT, num_envs=32, seed=s, episodes=10**9) for s in range(runs)]
    trainer = Trainer(configs)
    while trainer.groups[0].learner.steps < AGENT.learning_starts + 32:
        trainer.step()  # the replays past learning_starts: we time learning, not warm-up
    start = clock()
    for _ in range(steps):
        trainer.step()
    return steps * 32 * runs / (clock() - start)

def member_update_seconds(members):
    from pursuit_bench.agents.dqn import DQNLearner
    from pursuit_bench.env.task import obs_size
    n_obs = obs_size(2)
    learner = DQNLearner(n_obs, 12, AGENT, members=members, seed=0)
    rng = np.random.default_rng(0)
    for _ in range(20):
        obs = rng.normal(size=(members, 100, n_obs)).astype(np.float32)
        actions, rewards = rng.integers(0, 12, (members, 100)), rng.normal(size=(members, 100))
        learner.store(obs, actions, rewards, obs, np.zeros((members, 100)))
    learner.update()
    updates = max(10, 200 // members)
    start = time.perf_counter()
    for _ in range(updates):
        learner.update()
    return (time.perf_counter() - start) / (updates * members)

def matmul_rate():
    a = torch.randn(256, 256)
    torch.mm(a, a)
    start = time.perf_counter()
    for _ in range(200):
        torch.mm(a, a)
    return 200 * 2 * 256**3 / (time.perf_counter() - start)

PARTS = {  # part -> (module, owner, attribute) of the calls timed as that part, exclusive of nested ones
    "env step": [("pursuit_bench.env.vector", "VectorPursuitEnv", "step")],
    "acting": [
        ("pursuit_bench.agents.dqn", "DQNLearner", "act_values"),
        ("pursuit_bench.agents.dqn", "DQNLearner", "choose"),
        ("pursuit_bench.agents.dqn", "DQNLearner", "act_members"),
        ("pursuit_bench.training.train", None, "members_to_env"),
        ("pursuit_bench.training.train", None, "put_actions"),
        ("pursuit_bench.agents.kinds", "ScriptedAgent", "act_batch"),
    ],
    "storing": [("pursuit_bench.agents.dqn", "DQNLearner", "store")],
    # one part: today's build samples, steps and sets the priorities in one compiled call
    "update, with replay sampling and priorities": [
        ("pursuit_bench.agents.dqn", "DQNLearner", "update"),
        ("pursuit_bench.agents.replay", "ReplayStack", "sample"),
        ("pursuit_bench.agents.replay", "ReplayStack", "update_priorities"),
        ("pursuit_bench.agents.dqn", "DQNLearner", "learn"),
        ("pursuit_bench.agents.adam", "FlatAdam", "step"),
    ],
}

def step_parts(condition, steps):
    # milliseconds per env step of one run in each part (exclusive of the parts it calls), and the
    # rest of Trainer.step (the loop's own Python: gathering rows, counting episodes)
    import importlib
    spent = {part: 0.0 for part in PARTS}
    stack = []  # [part, start, time spent in nested timed calls]

    def timed(part, function):
        def wrapper(*a, **k):
            stack.append([part, clock(), 0.0])
            try:
                return function(*a, **k)
            finally:
                _, start, nested = stack.pop()
                elapsed = clock() - start
                spent[part] += elapsed - nested
                if stack:
                    stack[-1][2] += elapsed
        return wrapper

    for part, places in PARTS.items():
        for module, owner, name in places:
            holder = importlib.import_module(module)
            holder = getattr(holder, owner) if owner else holder
            if hasattr(holder, name):
                setattr(holder, name, timed(part, getattr(holder, name)))
    configs = [TrainConfig(condition=condition, agent=AGENT, num_envs=32, seed=0, episodes=10**9)]
    trainer = Trainer(configs)
    while trainer.groups[0].learner.steps < AGENT.learning_starts + 32:
        trainer.step()
    for part in spent:
        spent[part] = 0.0
    start = clock()
    for _ in range(steps):
        trainer.step()
    total = clock() - start
    out = {part: 1e3 * seconds / steps for part, seconds in spent.items()}
    out["rest of the loop"] = 1e3 * (total - sum(spent.values())) / steps
    out["total"] = 1e3 * total / steps
    return out

if kind == "train":
    print(json.dumps(transitions_per_second(args[0], int(args[1]), int(args[2]))))
elif kind == "parts":
    print(json.dumps(step_parts(args[0], int(args[1]))))
elif kind == "update":
    print(json.dumps({"seconds": member_update_seconds(int(args[0])), "matmul": matmul_rate()}))
elif kind == "eval":
    from pursuit_bench import pretrained
    from pursuit_bench.training.evaluate import evaluate_agents
    agents = pretrained.load(args[0])
    for agent in agents.values():  # compile (or load) the forward pass before the clock starts
        learner = getattr(agent, "learner", None)
        if learner is not None and hasattr(learner, "decisive_q"):
            learner.decisive_q(np.zeros((1, learner.n_obs), dtype=np.float32), agent.member)
    start = time.perf_counter()
    result = evaluate_agents(args[0], agents, episodes=int(args[1]), seed=12345)
    elapsed = time.perf_counter() - start
    plays = 1 + 2 * len(result["panels"]) + (2 if result["prey_check"] else 0)
    print(json.dumps({"episodes_per_s": plays * int(args[1]) / elapsed, "result": result}))
"""


#: Every BLAS and OpenMP pool of a worker at one thread, as in a study (a run a core): a pool's
#: spare threads wait by spinning, which the CPU-time clock would count as the run's work.
ONE_THREAD = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def measure(tree: Path, *args: str) -> object:
    """One worker's answer, with ``tree``'s pursuit_bench first on the path."""
    env = {**os.environ, "PYTHONPATH": str(tree), **ONE_THREAD}
    done = subprocess.run([sys.executable, "-c", WORKER, *args], env=env, capture_output=True, text=True, cwd=tree)
    if done.returncode != 0:
        raise SystemExit(f"worker {args} in {tree} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def medians(trees: dict[str, Path], repeats: int, *args: str) -> dict[str, list[object]]:
    """Every tree's answers to the same measurement, repeats interleaved."""
    answers: dict[str, list[object]] = {name: [] for name in trees}
    for _ in range(repeats):
        for name, tree in trees.items():
            answers[name].append(measure(tree, *args))
    return answers


#: What the benchmark can measure (``--sections``).
SECTIONS = ("train", "parts", "stacked", "update", "eval")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--episodes", type=int, default=1000, help="evaluation episodes per variant")
    parser.add_argument("--steps", type=int, default=150, help="env steps timed per training measurement")
    parser.add_argument("--reference", default="8ec03b5", help="the commit measured against")
    parser.add_argument(
        "--sections",
        default=",".join(SECTIONS),
        help=f"what to measure, comma-separated among {', '.join(SECTIONS)} (default: all)",
    )
    parser.add_argument(
        "--clock",
        choices=("cpu", "wall"),
        default="cpu",
        help="time training by the worker's CPU time (default: what a one-threaded run costs, whatever else "
        "the machine runs) or by the wall clock (what it takes on a machine to itself)",
    )
    args = parser.parse_args()
    os.environ["BENCH_CLOCK"] = args.clock  # the workers' clock: they inherit the environment
    args.sections = args.sections.split(",")
    unknown = set(args.sections) - set(SECTIONS)
    if unknown:
        parser.error(f"--sections: unknown {', '.join(sorted(unknown))}; expected some of {', '.join(SECTIONS)}")
    with reference_tree(args.reference) as reference:
        report(args, {"today": ROOT, "reference": reference})


@contextlib.contextmanager
def reference_tree(commit: str) -> Iterator[Path]:
    """A git worktree of ``commit`` in a temporary folder, removed whatever happens (SIGTERM too)."""
    with tempfile.TemporaryDirectory() as scratch:
        reference = Path(scratch) / "reference"
        add = ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(reference), commit]
        subprocess.run(add, check=True)
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # the worktree goes whatever happens
        try:
            yield reference
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(reference)], check=False)


def report(args: argparse.Namespace, trees: dict[str, Path]) -> None:
    print(
        f"today: {ROOT}; reference: commit {args.reference}; medians of {args.repeats}, one torch thread; "
        f"training timed by the {'CPU time' if args.clock == 'cpu' else 'wall clock'}"
    )
    med = statistics.median
    alone = {}
    for condition in ("1p-high", "3p-high-shared") if "train" in args.sections else ():
        alone[condition] = rates = medians(trees, args.repeats, "train", condition, "1", str(args.steps))
        today, before = med(rates["today"]), med(rates["reference"])  # type: ignore[type-var]
        print(
            f"one run, {condition}, reproduction preset: {today:,.0f} transitions/s "
            f"against {before:,.0f}: {today / before:.2f}x"
        )
    for condition in ("1p-high", "3p-high-shared") if "parts" in args.sections else ():
        parts_table(condition, medians(trees, args.repeats, "parts", condition, str(args.steps)))
    if "stacked" in args.sections:
        stacked_runs(args, trees, alone)
    if "update" in args.sections:
        member_updates(args, trees)
    if "eval" in args.sections:
        evaluation(args, trees)


def parts_table(condition: str, answers: dict[str, list[object]]) -> None:
    """Milliseconds per env step of one run in each part of the step, medians of the repeats."""
    print(f"\nper part of one env step, {condition}, one run, reproduction preset (ms, median):\n")
    print("| part | reference | today | reference / today |\n|---|---:|---:|---:|")
    for part in answers["today"][0]:  # type: ignore[attr-defined]
        before = statistics.median(a[part] for a in answers["reference"])  # type: ignore[index]
        today = statistics.median(a[part] for a in answers["today"])  # type: ignore[index]
        print(f"| {part} | {before:.3f} | {today:.3f} | {before / today:.2f}x |")
    print()


def stacked_runs(args: argparse.Namespace, trees: dict[str, Path], alone: dict[str, dict[str, list[object]]]) -> None:
    """10 seeds of 1p-high stacked, against one run alone."""
    med = statistics.median
    if "1p-high" not in alone:
        alone["1p-high"] = medians(trees, args.repeats, "train", "1p-high", "1", str(args.steps))
    stacked = medians(trees, args.repeats, "train", "1p-high", "10", str(max(10, args.steps // 5)))
    for name in trees:
        s, a = med(stacked[name]), med(alone["1p-high"][name])  # type: ignore[type-var]
        print(f"10 seeds of 1p-high stacked, {name}: {s:,.0f} transitions/s, {s / a:.2f}x one after another ({a:,.0f})")
    ratio = med(stacked["today"]) / med(alone["1p-high"]["reference"])  # type: ignore[type-var, operator]
    print(f"  today's stack against the reference's runs one after another: {ratio:.2f}x")


def member_updates(args: argparse.Namespace, trees: dict[str, Path]) -> None:
    """One member-update at 1 and 24 members, against its floating-point bound."""
    med = statistics.median
    from pursuit_bench.env.task import obs_size

    bound_flops = member_update_flops(obs_size(2) + 2, 12, 64)  # the worker's learner: 1p, wall features
    for members in (1, 24):
        answers = medians(trees, args.repeats, "update", str(members))
        for name in trees:
            seconds = med(a["seconds"] for a in answers[name])  # type: ignore[index]
            bound = bound_flops / med(a["matmul"] for a in answers[name])  # type: ignore[index]
            print(
                f"member-update at {members:2d} members, {name}: "
                f"{seconds * 1e3:.3f} ms = {seconds / bound:.1f}x its bound"
            )


def evaluation(args: argparse.Namespace, trees: dict[str, Path]) -> None:
    """Evaluation episodes/s of the paper's protocol, and whether the two builds' results agree."""
    med = statistics.median
    evaluations = medians(trees, args.repeats, "eval", "1p-high", str(args.episodes))
    rates = {name: med(a["episodes_per_s"] for a in evaluations[name]) for name in trees}  # type: ignore[index]
    same = all(a["result"] == evaluations["reference"][0]["result"] for a in evaluations["today"])  # type: ignore[index]
    print(
        f"evaluation, 1p-high shipped agents, {args.episodes} episodes per variant: {rates['today']:,.0f} episodes/s "
        f"against {rates['reference']:,.0f}: {rates['today'] / rates['reference']:.2f}x; results identical: {same}"
    )


if __name__ == "__main__":
    main()
