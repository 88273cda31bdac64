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

    python benchmarks/bench_evaluate.py --workloads --before-root DIR [--repeats 3]
        [--out results/speed/evaluate-workloads.json]

Issue 62's three workloads, this checkout against another build (``--before-root``: a git
worktree of it, e.g. ``git worktree add /tmp/before 39cf492``), each in a fresh process of its
own with that build's package first on ``PYTHONPATH``, alternated, medians of ``--repeats``, CPU
time: (1) the paper's protocol on a shipped run (``evaluate_agents``, 5000 episodes, 3p-high-shared
and 1p-high); (2) a study job (``rule_study.evaluate_run`` at one budget: a 2p-high-shared run of
the reproduction preset, trained here for 3000 episodes, against the rule study's 9-member
population, 60 episodes a member); (3) ``pursuit-bench score pure-pursuit --role predator`` in all
ten conditions at its default episodes, the whole process (start-up counts). (1) and (2) time the
call alone. Then one profiled run of each in each build: CPU by part (cProfile's, its overhead
included).
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


# ------------------------------------------------------------------ issue 62's workloads

#: The workloads: name -> what the child process runs.
WORKLOADS = ("protocol:3p-high-shared", "protocol:1p-high", "study-job:2p-high-shared", "score:pure-pursuit")
STUDY_JOB_EPISODES = 3000

#: The parts of a profile: name -> the functions whose cumulative time it is (file, function).
PARTS: dict[str, list[tuple[str, str]]] = {
    "physics (world step)": [("env/world.py", "step")],
    "observations, rewards (finish_step)": [("env/task.py", "finish_step")],
    "resets": [("env/core.py", "reset")],
    "networks (decisive_q)": [("agents/dqn.py", "decisive_q")],
    "scripted agents and the rule": [("agents/kinds.py", "act_batch"), ("agents/kinds.py", "to_env")],
    "building the envs": [("env/vector.py", "__init__")],
    "the evaluation loop": [("training/evaluate.py", "play_variants")],
}


def _child(workload: str, work: Path, profile: Path | None) -> None:
    """Run one workload in this process (its package from ``PYTHONPATH``); print its CPU time."""
    import cProfile

    torch.set_num_threads(1)
    kind, what = workload.split(":")
    profiler = cProfile.Profile() if profile is not None else None
    if kind == "protocol":
        from pursuit_bench import pretrained as shipped

        agents = shipped.load(what)
        evaluate.evaluate_agents(what, agents, episodes=4, seed=1)  # the kernels compiled (cached) first
        start = time.process_time()
        if profiler:
            profiler.enable()
        evaluate.evaluate_agents(what, agents, episodes=5000, seed=12345)
    elif kind == "study-job":
        from pursuit_bench.reports import rule_study

        population = ROOT / "pursuit_bench/pretrained/populations/rule-study" / what
        folder = work / "runs" / f"{what}-hierarchical-seed0"
        from pursuit_bench import pretrained as shipped

        evaluate.evaluate_agents(what, shipped.load(what), episodes=4, seed=1)  # the kernels compiled (cached)
        start = time.process_time()
        if profiler:
            profiler.enable()
        rule_study.evaluate_run(folder, population, budgets=(STUDY_JOB_EPISODES,))
    else:
        raise ValueError(workload)
    took = time.process_time() - start
    if profiler and profile:
        profiler.disable()
        profiler.dump_stats(str(profile))
    print(json.dumps({"cpu": took}))


def _train_study_run(work: Path) -> None:
    """The study job's run (this checkout's package): trained once, kept in ``work``."""
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training.sweep import SweepPlan, open_sweep, run_sweep

    condition = WORKLOADS[2].split(":")[1]
    plan = SweepPlan(
        conditions=(condition,), seeds=1, predators=("hierarchical",),
        agent=PRESETS["reproduction"].replace(episodes=STUDY_JOB_EPISODES), episodes=STUDY_JOB_EPISODES,
        eval_episodes=1, num_envs=32, checkpoint_every=1000, preset="reproduction",
    )  # fmt: skip
    work.mkdir(parents=True, exist_ok=True)
    open_sweep(work, plan)
    run_sweep(work, plan, workers=1, record=False)


def _measure(workload: str, root: Path, work: Path, profile: Path | None = None) -> float:
    """CPU seconds of one workload in a fresh process running the package at ``root``."""
    import os
    import resource

    env = {**os.environ, "PYTHONPATH": str(root)}
    if workload.startswith("score:"):
        out = work / f"score-{root.name}"
        command = [sys.executable, *(["-m", "cProfile", "-o", str(profile)] if profile else [])]
        command += [str(Path(sys.executable).with_name("pursuit-bench")), "score", workload.split(":")[1]]
        command += ["--role", "predator", "--out", str(out)]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(command, env=env, cwd=root, check=True, capture_output=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    command = [sys.executable, str(Path(__file__).resolve()), "--child", workload, "--work", str(work)]
    command += ["--profile", str(profile)] if profile else []
    done = subprocess.run(command, env=env, cwd=root, check=True, capture_output=True, text=True)
    return float(json.loads(done.stdout.strip().splitlines()[-1])["cpu"])


def _parts(profile: Path) -> dict[str, float]:
    """CPU seconds by part (:data:`PARTS`) of a cProfile dump, and its total."""
    import pstats

    stats = pstats.Stats(str(profile)).stats  # type: ignore[attr-defined]
    cumulative: dict[str, float] = {}
    total = 0.0
    for (file, _, function), (_, _, own, cum, _) in stats.items():
        total += own
        for part, places in PARTS.items():
            if any(file.endswith(where) and function == name for where, name in places):
                cumulative[part] = cumulative.get(part, 0.0) + cum
    loop = cumulative.pop("the evaluation loop", 0.0)
    inside = sum(v for k, v in cumulative.items() if k != "building the envs")
    return {**cumulative, "the evaluation loop's own bookkeeping": loop - inside, "all (profiled)": total}


def workloads(args: argparse.Namespace) -> None:
    before_root = args.before_root.resolve()
    work = args.work.resolve()
    _train_study_run(work)
    builds = {"before": before_root, "after": ROOT}
    seconds: dict[str, dict[str, list[float]]] = {w: {"before": [], "after": []} for w in WORKLOADS}
    for workload in WORKLOADS:
        for _ in range(args.repeats):  # alternated: the load of the machine falls on both alike
            for name, root in builds.items():
                seconds[workload][name].append(_measure(workload, root, work))
        med = {k: statistics.median(v) for k, v in seconds[workload].items()}
        print(f"{workload}: before {med['before']:.1f} s, after {med['after']:.1f} s of CPU, "
              f"{med['before'] / med['after']:.2f}x (median of {args.repeats})", flush=True)  # fmt: skip
    parts = {}
    for workload in WORKLOADS:
        parts[workload] = {}
        for name, root in builds.items():
            profile = work / f"{workload.replace(':', '-')}-{name}.prof"
            _measure(workload, root, work, profile)
            parts[workload][name] = _parts(profile)
    out = {
        "command": "python benchmarks/bench_evaluate.py " + " ".join(sys.argv[1:]),
        "before_commit": subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=before_root, capture_output=True, text=True, check=True
        ).stdout.strip(),
        "after_commit": subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, check=True
        ).stdout.strip(),
        "cpu": subprocess.run(["lscpu"], capture_output=True, text=True).stdout.split("Model name:")[-1]
        .splitlines()[0].strip(),
        "cpu_seconds": seconds,
        "median_cpu_seconds": {w: {k: statistics.median(v) for k, v in t.items()} for w, t in seconds.items()},
        "speedup": {w: statistics.median(t["before"]) / statistics.median(t["after"]) for w, t in seconds.items()},
        "parts_cpu_seconds_profiled": parts,
    }  # fmt: skip
    text = json.dumps(out, indent=2) + "\n"
    print(text)
    if args.out is not None:
        atomic_write_text(args.out, text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workloads", action="store_true", help="issue 62's three workloads (see above)")
    parser.add_argument("--before-root", type=Path, default=None, help="with --workloads: the other build")
    parser.add_argument("--work", type=Path, default=Path("/tmp/pursuit-bench-bench-evaluate"))
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--profile", type=Path, default=None, help=argparse.SUPPRESS)
    parser.add_argument("--condition", default="2p-high-individual")
    parser.add_argument("--episodes", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=8)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if args.child:
        return _child(args.child, args.work, args.profile)
    if args.workloads:
        if args.before_root is None:
            parser.error("--workloads needs --before-root (a worktree of the build to compare with)")
        return workloads(args)
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
