"""The rule study's driver (issue 47; REPRODUCTION.md, "Protocol of the rule study"; PLAN.md beside
this file): trains each condition's population, writes it in the population format, then the
judged runs of both kinds, cheapest conditions first, and evaluates each against its condition's
population at every budget, writing its compact result under ``results/rule-study/runs/``; the
seed rule adds judged seeds where a condition's runs split.

    nohup python studies/rule-value/run.py --workers 2 &      # start, or resume: the same command
    kill -TERM "$(cat sweeps/rule-study/driver.pid)"          # stop cleanly (checkpoints, then exits 143)
    tail -f sweeps/rule-study/progress.log                    # progress

Every run is a sweep's run folder under ``--work`` (training resumes exactly from its last
checkpoint); a judged run's evaluation is written whole when it ends, and a rerun skips what is
written. The study refuses to go on with package code other than that it started with (a run
trained by another build is never mixed in): ``--work``/study.json holds the code's fingerprint.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))  # the drivers' shared module alone
import driver  # noqa: E402

log, sweep = driver.log, driver.sweep


def build() -> dict[str, str]:
    """The code that trains and evaluates: the commit, and a fingerprint of the package's tracked
    Python files (unchanged by committing results or the population's weights). Refuses
    uncommitted changes to the package's code."""
    commit, listed = driver.committed_package(ROOT)
    return {"commit": commit, "code": driver.code_fingerprint(listed)}


def plan_for(kind: str, conditions: list[str], first: int, seeds: int, args: Any, keep: tuple[int, ...]) -> Any:
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training.sweep import SweepPlan

    return SweepPlan(
        conditions=tuple(conditions),
        seeds=seeds,
        first_seed=first,
        predators=(kind,) if kind != "both" else ("hierarchical", "flat"),
        agent=PRESETS[args.preset].replace(episodes=args.episodes),
        episodes=args.episodes,
        eval_episodes=1,  # the sweep's own evaluation (each run against its own prey) is not read
        num_envs=args.num_envs,
        checkpoint_every=args.checkpoint_every,
        preset=args.preset,
        keep_checkpoints=keep,
    )


def population(args: Any, stop: list[bool], conditions: list[str], current: dict[str, str]) -> bool:
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    from pursuit_bench.training import runs

    # every condition's population written (committed): nothing to train; if only some are, the
    # sweeps train all of them, as they were planned (a sweep's plan cannot change once opened)
    written = all((args.population / c / "population.json").exists() for c in conditions)
    for kind in () if written else rule_study.KINDS:
        seeds = rule_study.population_seeds(kind)
        folder = args.work / f"population-{kind}"
        log(args.work, f"population: {kind} prey, seeds {seeds.start}–{seeds.stop - 1}, {len(conditions)} conditions")
        if not sweep(
            args.work, folder, plan_for(kind, conditions, seeds.start, len(seeds), args, ()), args.workers, stop
        ):
            return False
    for condition in conditions:
        if (args.population / condition / "population.json").exists():
            continue
        prey, trained = {}, {}
        for member in rule_study.members(condition):
            if member["policy"] is not None:
                continue
            name = f"{condition}-{member['kind']}-seed{member['seed']}"
            config, agents, about = runs.described(args.work / f"population-{member['kind']}" / "runs" / name)
            prey[member["name"]] = (agents["prey_0"], config)
            trained[member["name"]] = {
                "preset": args.preset,
                "episodes": int(about.get("trained_episodes", config.episodes)),
                "predator_kind": member["kind"],
                "build": current["commit"],
            }
        rule_study.write_population(args.population, condition, prey, trained)
        log(args.work, f"population of {condition} written to {args.population / condition}")
    return True


def evaluate(
    folder: str, population: str, out: str, name: str, condition: str, kind: str, seed: int, build: str, trial: Any
) -> dict[str, Any]:
    """One judged run against its population, its compact result written (a worker's job)."""
    import torch

    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    torch.set_num_threads(1)
    options = {} if trial is None else {"episodes": trial[0], "budgets": tuple(trial[1])}
    result = rule_study.evaluate_run(Path(folder), Path(population), **options)
    rule_study.write_run(Path(out), name, condition, kind, seed, build, result)
    return {"written": f"{name}.json.gz"}


def judged(args: Any, stop: list[bool], conditions: list[str], current: dict[str, str]) -> bool:
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.training.jobs import run_jobs
    except ImportError:
        from pursuit_bench.study.jobs import run_jobs

    from pursuit_bench.io.files import atomic_write_text

    out = args.results / "runs"
    out.mkdir(parents=True, exist_ok=True)
    marker = args.results / "rule-study.json"  # what `pursuit-bench report` knows the folder by
    if not marker.exists():
        about = {
            "format": rule_study.FORMAT,
            "protocol": "REPRODUCTION.md, Protocol of the rule study",
            "population": rule_study.POPULATION,
            "command": "python studies/rule-value/run.py " + " ".join(sys.argv[1:]),
            "seed_rule": {"first": rule_study.FIRST_RUNS, "step": rule_study.STEP_RUNS, "most": rule_study.MOST_RUNS},
        }
        atomic_write_text(marker, json.dumps(about, indent=2) + "\n")
    budgets = list(rule_study.BUDGETS) if args.budgets is None else [int(b) for b in args.budgets.split(",")]
    keep = tuple(budgets[:-1])
    for condition in conditions:
        first = 0
        while True:
            done = [r for r in rule_study.read_runs(out) if r["condition"] == condition]
            wanted = rule_study.seeds_wanted(done)
            if first >= wanted:
                log(args.work, f"{condition}: {wanted} judged runs a kind, done")
                break
            step = min(rule_study.STEP_RUNS if first else rule_study.FIRST_RUNS, wanted - first)
            rule_study.check_design({k: list(range(wanted)) for k in rule_study.KINDS}, rule_study.members(condition))
            folder = args.work / f"judged-{condition}-from{first}"
            names = [
                f"{condition}-{kind}-seed{seed}" for kind in rule_study.KINDS for seed in range(first, first + step)
            ]
            if all((out / f"{name}.json.gz").exists() for name in names):
                first += step  # judged already (its results committed): not trained again, on any machine
                continue
            log(args.work, f"{condition}: judged seeds {first}–{first + step - 1}, both kinds")
            if not sweep(args.work, folder, plan_for("both", [condition], first, step, args, keep), args.workers, stop):
                return False
            jobs = []
            for kind in rule_study.KINDS:
                for seed in range(first, first + step):
                    name = f"{condition}-{kind}-seed{seed}"
                    if (out / f"{name}.json.gz").exists():
                        continue
                    where = str(folder / "runs" / name)
                    pop = str(args.population / condition)
                    trial = None if args.budgets is None else (args.eval_episodes, budgets)
                    jobs.append((name, (where, pop, str(out), name, condition, kind, seed, current["commit"], trial)))
            if jobs:
                log(args.work, f"{condition}: evaluating {len(jobs)} runs against the population")
                run_jobs(
                    jobs,
                    evaluate,
                    args.work / "evaluation-parts",
                    {"build": current["code"]},
                    workers=args.workers,
                    progress=lambda n, total, c=condition: log(args.work, f"{c}: {n} of {total} evaluations"),
                )
            if stop[0]:
                return False
            first += step
    return True


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--work", type=Path, default=ROOT / "sweeps" / "rule-study", help="Run folders, logs.")
    parser.add_argument("--results", type=Path, default=ROOT / "results" / "rule-study")
    parser.add_argument(
        "--population", type=Path, default=ROOT / "pursuit_bench" / "pretrained" / "populations" / "rule-study"
    )
    parser.add_argument("--conditions", default="all", help="'all' or a comma-separated list.")
    parser.add_argument("--preset", default="reproduction", help="(only for trying the driver: quick)")
    parser.add_argument("--episodes", type=int, default=15000, help="(only for trying the driver)")
    parser.add_argument("--num-envs", type=int, default=32)
    parser.add_argument("--checkpoint-every", type=int, default=1000)
    parser.add_argument("--skip-build-check", action="store_true", help="(tests only)")
    parser.add_argument("--budgets", default=None, help="(tests only) e.g. 4,8; the last is --episodes")
    parser.add_argument("--eval-episodes", type=int, default=None, help="(tests only, with --budgets)")
    args = parser.parse_args()
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    from pursuit_bench.env.conditions import CONDITIONS

    chosen = list(CONDITIONS) if args.conditions == "all" else args.conditions.split(",")
    if unknown := [c for c in chosen if c not in CONDITIONS]:
        print(f"--conditions: unknown {unknown}; expected some of {', '.join(CONDITIONS)}", file=sys.stderr)
        return 2
    conditions = rule_study.order(chosen)
    last = rule_study.BUDGETS[-1] if args.budgets is None else int(args.budgets.split(",")[-1])
    if args.episodes != last:
        print(f"--episodes {args.episodes}: the study's last budget is {last}", file=sys.stderr)
        return 2
    args.work.mkdir(parents=True, exist_ok=True)
    from pursuit_bench.io.files import RunBusy, locked

    try:
        with locked(args.work):  # one driver a study: a second one refuses before it writes anything
            return drive(args, conditions)
    except RunBusy as error:
        print(f"{error}: stop it first (kill -TERM its pid), or wait for it to finish", file=sys.stderr)
        return 2


def drive(args: Any, conditions: list[str]) -> int:
    """The study from where it stands: 0 once finished, 143 when stopped by a signal."""
    current = {"commit": "test", "code": "test"} if args.skip_build_check else build()
    driver.check_started(
        args.work, current, "its runs are not mixed: check out that commit's package to go on, or start the study "
        "again in a new --work"
    )  # fmt: skip
    (args.work / "driver.pid").write_text(f"{os.getpid()}\n")
    stop = driver.stop_flag(args.work)
    log(args.work, f"rule study: {', '.join(conditions)}; commit {current['commit'][:10]}, code {current['code']}")
    finished = population(args, stop, conditions, current) and judged(args, stop, conditions, current)
    log(args.work, "finished" if finished else "stopped: rerun the same command to resume")
    return 0 if finished else 143


if __name__ == "__main__":
    sys.exit(main())
