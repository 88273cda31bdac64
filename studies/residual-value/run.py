"""The residual study's driver (issue 48; docs/residual.md, "Protocol of the residual study";
PLAN.md beside this file): trains each setting's population members that the rule study does not
have and writes the population, then the judged runs, and evaluates each against its setting's
population at every budget (CRN), under the robustness ladders and, for the residual kind, its
corrections by distance and mode; each run's compact result goes under
``results/residual-study/runs/``. In the rule study's conditions its hierarchical and flat judged
runs are reused: their evaluations against the rule study's 9 members are taken from its compact
results and only the 4 residual members are played here.

    nohup nice -n 10 python studies/residual-value/run.py --workers 2 &   # start, or resume: the same command
    kill -TERM "$(cat sweeps/residual-study/driver.pid)"                  # stop cleanly (exits 143)
    tail -f sweeps/residual-study/progress.log                            # progress

It runs on one build of ``main`` (PLAN.md, "The build"), pinned at its first start in
``build.json`` beside this file (the commit, the fingerprint of the package's tracked .py files as
the rule study's driver computes it, and of the training code): it refuses any other package code
from then on. The build's training code (``design.TRAINING_CODE``: the package's files that
training reads, all but the evaluation) must be the rule study's, file for file, since the rule
study's hierarchical and flat runs, trained by its build (commit ec5779b), are reused. Every
evaluation made here is this build's, the ladders of the reused runs included; those taken from the
rule study's results are its build's, which the replay check shows this build reproduces to the
bit. The study's own logic is here and in design.py.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import gzip
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import design  # the study's fixed design, beside this file

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))  # the drivers' shared module alone
import driver

git, log, sweep = driver.git, driver.log, driver.sweep

ROOT = Path(__file__).resolve().parents[2]
WAITING = 3  # the exit status when only the rule study's runs are missing and --poll is 0
PIN = Path(__file__).resolve().parent / "build.json"  # the study's build, once it started


def record(marker: Path, seed_rule: dict[str, int] | None = None, floor: tuple[str, int] | None = None) -> None:
    """Write into the results' marker file (``residual-study.json``), which the report reads the
    seed rule from: the study's ``seed_rule``, or one plain setting's ``floor`` (the rule study's
    count there) into ``seed_floor``; the file is replaced whole, and only when that changes it
    (the driver says the floor again on every pass). SystemExit if it is not JSON."""
    from pursuit_bench.io.files import atomic_write_text

    try:
        about = json.loads(marker.read_text())
    except json.JSONDecodeError as error:
        raise SystemExit(f"{marker}: not JSON ({error}); restore it from git") from None
    updated = dict(about)
    if seed_rule is not None:
        updated["seed_rule"] = seed_rule
    if floor is not None:
        updated["seed_floor"] = {**about.get("seed_floor", {}), floor[0]: floor[1]}
    if updated != about:
        atomic_write_text(marker, json.dumps(updated, indent=2) + "\n")


def build() -> dict[str, str]:
    """This checkout's build (:func:`package_build`); refuses a package imported from another
    checkout than this one (PYTHONPATH)."""
    import pursuit_bench

    if ROOT not in Path(pursuit_bench.__file__).resolve().parents:
        raise SystemExit(
            f"pursuit_bench is imported from {pursuit_bench.__file__}, not {ROOT}: export PYTHONPATH={ROOT}"
        )
    return package_build(ROOT)


def package_build(root: Path) -> dict[str, str]:
    """The commit, the fingerprint of the package's tracked .py files (``code``, as the rule
    study's driver computes it) and that of its training code (``training_code``,
    :func:`design.training_code`) in the checkout ``root``. Refuses uncommitted package code and
    training code other than the rule study's, naming the files that differ from its build's."""
    commit, listed = driver.committed_package(root)
    code = driver.code_fingerprint(listed)
    files = design.training_files(git(root, "ls-tree", "-r", "HEAD", "--", "pursuit_bench"))
    training = design.training_code(files)
    if training != design.TRAINING_CODE:
        try:  # the rule study's build, from this project's history
            theirs = design.training_files(git(ROOT, "ls-tree", "-r", design.RULE_STUDY_COMMIT, "--", "pursuit_bench"))
            differ = ", ".join(sorted(p for p in files.keys() | theirs.keys() if files.get(p) != theirs.get(p)))
        except subprocess.CalledProcessError:
            differ = f"which files, unknown: commit {design.RULE_STUDY_COMMIT[:10]} is not in this clone"
        raise SystemExit(
            f"the package's training code ({training}, commit {commit[:10]}) is not the rule study's "
            f"({design.TRAINING_CODE}, commit {design.RULE_STUDY_COMMIT[:10]}), whose runs are reused: {differ}"
        )
    return {"commit": commit, "code": code, "training_code": training}


def pin(path: Path, current: dict[str, str], results: Path, write: bool = True) -> None:
    """The study's build, ``build.json``: written at the study's first start (commit it; not by a
    try-out, ``write=False``), then required: SystemExit if the package's code is another
    (``current``: :func:`build`), or if the file is gone while ``results`` holds the study's
    compact results (restore it from git)."""
    from pursuit_bench.io.files import atomic_write_text

    if path.exists():
        pinned = json.loads(path.read_text())
        if pinned["code"] != current["code"]:
            raise SystemExit(
                f"{path}: the study's build is commit {pinned['commit'][:10]} (package code {pinned['code']}); "
                f"this package is commit {current['commit'][:10]} ({current['code']}): not mixed; run from a "
                "checkout of the study's build (PLAN.md, How to drive it)"
            )
        return
    if not write:
        return
    if any((results / "runs").glob("*.json.gz")):
        raise SystemExit(f"{path}: missing, though {results / 'runs'} holds the study's results: restore it from git")
    stamp = f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M:%S} UTC"
    atomic_write_text(path, json.dumps({**current, "pinned": stamp}, indent=2) + "\n")


# --- training -----------------------------------------------------------------------------------


def plan_for(setting: str, kinds: tuple[str, ...], first: int, seeds: int, args: Any, keep: tuple[int, ...]) -> Any:
    """A sweep of ``kinds`` in ``setting``: the rule study's plan (``studies/rule-value/run.py``),
    with the setting's obstacles."""
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training.sweep import SweepPlan

    return SweepPlan(
        conditions=(design.condition_of(setting),),
        seeds=seeds,
        first_seed=first,
        predators=kinds,
        agent=PRESETS[args.preset].replace(episodes=args.episodes),
        episodes=args.episodes,
        eval_episodes=1,  # the sweep's own evaluation (each run against its own prey) is not read
        num_envs=args.num_envs,
        checkpoint_every=args.checkpoint_every,
        preset=args.preset,
        keep_checkpoints=keep,
        obstacles=design.obstacles_of(setting),
    )


# --- the population -----------------------------------------------------------------------------


def population_folder(args: Any, setting: str) -> Path:
    return args.population / design.population_name(setting) / design.condition_of(setting)


def write_population(args: Any, setting: str, current: dict[str, str]) -> Path:
    """``population.json`` of a setting in the population format, each learned member's prey as
    ``<member>/prey_0.safetensors``: those trained here exported from their runs, the rule study's
    copied from its population (its files unchanged: git stores them once)."""
    from pursuit_bench import pretrained
    from pursuit_bench.io.files import atomic_write_text
    from pursuit_bench.training import runs

    folder = population_folder(args, setting)
    folder.mkdir(parents=True, exist_ok=True)
    rule: dict[str, Any] = {}
    if design.plain(setting):
        index = args.rule_population / design.condition_of(setting) / "population.json"
        rule = {m["name"]: m for m in json.loads(index.read_text())["members"]}
    entries = []
    for member in design.members(setting):
        name = member["name"]
        entry = {**member, "trained": None, "files": {}}
        if member["policy"] is None and name in rule:
            (folder / name).mkdir(parents=True, exist_ok=True)
            shutil.copyfile(index.parent / rule[name]["files"]["prey_0"], folder / name / "prey_0.safetensors")
            entry.update(trained=rule[name]["trained"], files={"prey_0": f"{name}/prey_0.safetensors"})
        elif member["policy"] is None:
            run = (
                args.work
                / f"population-{setting}-{member['kind']}"
                / "runs"
                / f"{setting}-{member['kind']}-seed{member['seed']}"
            )
            config, agents, about = runs.described(run)
            trained = {
                "preset": args.preset,
                "episodes": int(about.get("trained_episodes", config.episodes)),
                "predator_kind": member["kind"],
                "build": current["commit"],
            }
            with tempfile.TemporaryDirectory(dir=folder) as scratch:
                (written,) = pretrained.export(
                    {"prey_0": agents["prey_0"]},
                    config,
                    Path(scratch),
                    trained_episodes=trained["episodes"],
                    provenance={
                        "population": design.population_name(setting),
                        "member": name,
                        "build": current["commit"],
                    },
                )
                (folder / name).mkdir(parents=True, exist_ok=True)
                os.replace(written, folder / name / "prey_0.safetensors")
            entry.update(trained=trained, files={"prey_0": f"{name}/prey_0.safetensors"})
        entries.append(entry)
    document = {
        "population": design.population_name(setting),
        "condition": design.condition_of(setting),
        "obstacles": design.obstacles_of(setting),
        "role": "prey",
        "provisional": False,
        "members": entries,
    }
    atomic_write_text(folder / "population.json", json.dumps(document, indent=2) + "\n")
    return folder / "population.json"


def population(args: Any, stop: list[bool], settings: list[str], current: dict[str, str]) -> list[str]:
    """Train every setting's members this study trains, then write each setting's population;
    returns what it waits for: nothing is trained before the rule study's population of every
    plain setting is there."""
    rules = [args.rule_population / design.condition_of(s) / "population.json" for s in settings if design.plain(s)]
    if missing := [str(path) for path in rules if not path.exists()]:
        return [f"the rule study's population ({', '.join(missing)})"]
    for setting in settings:
        if (population_folder(args, setting) / "population.json").exists():
            continue  # written (committed): not trained again, on any machine
        for kind in design.trained_here(setting, "population"):
            seeds = design.population_seeds(kind)
            folder = args.work / f"population-{setting}-{kind}"
            log(args.work, f"population of {setting}: {kind} prey, seeds {seeds.start}–{seeds.stop - 1}")
            plan = plan_for(setting, (kind,), seeds.start, len(seeds), args, ())
            if not sweep(args.work, folder, plan, args.workers, stop):
                return ["stop"]
    for setting in settings:
        if not (population_folder(args, setting) / "population.json").exists():
            log(args.work, f"population of {setting} written to {write_population(args, setting, current).parent}")
    return []


# --- evaluation ---------------------------------------------------------------------------------


def play(
    folder: Path, where: Path, opponents: list[dict[str, Any]], budgets: list[int], episodes: int
) -> dict[str, Any]:
    """A run's predators at each budget against each opponent (a member of the population in
    ``where``), by the CRN protocol: the same calls as the rule study's ``evaluate_run`` (whose
    population is fixed to the rule study's nine), so a member's evaluation is the same here and
    there. A member is loaded by ``rule_study.load_member``, with its range readings where it
    trained among obstacles (this driver loaded them itself while the package's did not)."""
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports.rule_study import load_member
    except ImportError:
        from pursuit_bench.study.rule_study import load_member

    from pursuit_bench.agents.kinds import ScriptedAgent
    from pursuit_bench.rules.policies import FleeingPrey
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import evaluate_agents

    out: dict[str, Any] = {}
    for budget in budgets:
        checkpoint = runs.CHECKPOINT if budget == budgets[-1] else runs.milestone_checkpoint(budget)
        config, agents, _ = runs.described(folder, checkpoint)
        evaluations = {}
        for member in opponents:
            protocol = dict(config.protocol)
            if member["policy"] == design.FLEEING:
                prey: Any = ScriptedAgent("prey_0", FleeingPrey(obstacles=bool(config.task_options.get("obstacles"))))
                protocol["prey_epsilon"] = None
            else:
                prey = load_member(where / member["files"]["prey_0"])
            result = evaluate_agents(
                config.condition,
                {**{k: v for k, v in agents.items() if k != "prey_0"}, "prey_0": prey},
                episodes=episodes,
                seed=design.EVAL_SEED,
                prey_check=False,
                **protocol,
            )
            evaluations[member["name"]] = {
                "panels": {
                    p["predator"]: [p["trained"], p["always_chase"], p["always_stalk"]] for p in result["panels"]
                },
                "stderr": {p["predator"]: p["stderr"]["trained"] for p in result["panels"]},
                "capture_rate": result["capture_rate"],
            }
        out[str(budget)] = evaluations
    return out


def ladders(folder: Path, setting: str, episodes: int) -> dict[str, Any]:
    """The run's margin against its own prey at the end of training, unperturbed and on each rung
    of the study's ladders (``pursuit-bench robust``'s evaluation)."""
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.analysis import robustness
    except ImportError:
        from pursuit_bench.study import robustness

    from pursuit_bench.env.perturbations import Perturbations

    levels = {robustness.NONE: Perturbations()}
    for name, rungs in design.LADDERS.items():
        if name == "obstacles" and not design.plain(setting):
            continue
        levels.update({f"{name}={value:g}": robustness.perturbation(name, value) for value in rungs})
    return {level: robustness._evaluate(folder, folder, p, episodes, design.EVAL_SEED) for level, p in levels.items()}


def corrections(folder: Path, episodes: int) -> dict[str, Any]:
    """``pursuit-bench analyze``'s corrections of a residual run at the end of training, without its
    t-SNE: per predator, the share of states corrected and the correction by distance and mode."""
    import numpy as np

    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.analysis import behaviour as analysis
    except ImportError:
        from pursuit_bench.study import analysis

    from pursuit_bench.training import runs

    config, agents, _ = runs.described(folder)
    states = analysis.collect(
        config.condition, agents, episodes=episodes, seed=design.ANALYSIS_SEED, task_options=config.task_options
    )
    return {
        name: {
            "states": len(s.mode),
            "corrected": float(np.mean(s.correction != 0)),
            "p_chase": float(s.mode.mean()),
            "correction_by_distance": analysis.correction_by_distance(s.distance, s.mode, s.correction),
        }
        for name, s in states.items()
        if s.correction is not None
    }


def judge(
    folder: str,
    where: str,
    out: str,
    name: str,
    setting: str,
    kind: str,
    seed: int,
    build: str,
    reused: str | None,
    trial: Any,
) -> dict[str, Any]:
    """One judged run's compact result, written whole (a worker's job). ``reused``: the rule study's
    compact result of this run, whose 9 members' evaluations are taken (after one of them is played
    again and found identical); else every member is played here."""
    import torch

    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    from pursuit_bench.training.evaluate import PROTOCOL

    torch.set_num_threads(1)
    episodes, budgets = (design.EPISODES, list(design.BUDGETS)) if trial is None else (trial[0], list(trial[1]))
    opponents = json.loads((Path(where) / "population.json").read_text())["members"]
    if [m["name"] for m in opponents] != [m["name"] for m in design.members(setting)]:
        raise ValueError(f"{where}: not the population of {setting}")
    sources = {m["name"]: "residual-study" for m in opponents}
    pool: dict[str, Any] = {}
    if reused is None:
        pool = play(Path(folder), Path(where), opponents, budgets, episodes)
    else:
        earlier = json.loads(gzip.decompress(Path(reused).read_bytes()))
        if sorted(earlier["pool"], key=int) != [str(b) for b in budgets] or earlier["episodes"] != episodes:
            raise ValueError(f"{reused}: evaluated at other budgets or episodes than this study")
        known = [m for m in opponents if m["name"] in earlier["pool"][str(budgets[-1])]]
        check = next(m for m in known if m["policy"] is None)
        again = play(Path(folder), Path(where), [check], budgets[-1:], episodes)[str(budgets[-1])][check["name"]]
        again = json.loads(json.dumps(again))  # as the rule study's file holds it
        if again != earlier["pool"][str(budgets[-1])][check["name"]]:
            raise ValueError(f"{name}: played again against {check['name']}, it does not give the rule study's result")
        fresh = play(Path(folder), Path(where), [m for m in opponents if m not in known], budgets, episodes)
        for budget in map(str, budgets):
            both = {**earlier["pool"][budget], **fresh[budget]}
            pool[budget] = {m["name"]: both[m["name"]] for m in opponents}
        sources.update({m["name"]: f"rule-study ({Path(reused).name})" for m in known})
    result: dict[str, Any] = {
        "protocol": PROTOCOL,
        "episodes": episodes,
        "eval_seed": design.EVAL_SEED,
        "pool": pool,
        "study": "residual-study",
        "setting": setting,
        "obstacles": design.obstacles_of(setting),
        "population": design.population_name(setting),
        "evaluated_by": sources,
    }
    if kind in design.LADDER_KINDS:
        result["ladders"] = ladders(Path(folder), setting, design.LADDER_EPISODES if trial is None else episodes)
    if kind == "residual":
        result["corrections"] = corrections(Path(folder), design.ANALYSIS_EPISODES if trial is None else episodes)
    rule_study.write_run(Path(out), name, design.condition_of(setting), kind, seed, build, result)
    return {"written": f"{name}.json.gz"}


# --- the judged runs ----------------------------------------------------------------------------


def own_runs(out: Path, setting: str) -> list[dict[str, Any]]:
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    return [r for r in rule_study.read_runs(out) if r.get("setting") == setting]


def rule_count(args: Any, condition: str) -> int | None:
    """How many judged runs a kind the rule study has in ``condition`` once it is done there (its
    seed rule satisfied by its evaluated runs), else None."""
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    except ImportError:
        from pursuit_bench.study import rule_study

    runs = [r for r in rule_study.read_runs(args.rule_results / "runs") if r["condition"] == condition]
    runs = [r for r in runs if r.get("study") is None]  # the rule study's own files only
    wanted = rule_study.seeds_wanted(runs) if args.rule_first is None else args.rule_first
    have = {k: {r["seed"] for r in runs if r["kind"] == k} for k in rule_study.KINDS}
    return wanted if all(set(range(wanted)) <= seeds for seeds in have.values()) else None


def rule_folder(args: Any, setting: str, kind: str, seed: int) -> Path | None:
    """The rule study's run folder of a judged run, if it is still on this machine."""
    name = f"{design.condition_of(setting)}-{kind}-seed{seed}"
    found = sorted(args.rule_work.glob(f"judged-{design.condition_of(setting)}-from*/runs/{name}"))
    return found[0] if found else None


def judged(args: Any, stop: list[bool], setting: str, current: dict[str, str]) -> str:
    """Train, reuse and evaluate a setting's judged runs, seed step by seed step as the seed rule
    asks; returns "done", "stop" or what it waits for."""
    try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
        from pursuit_bench.training.jobs import run_jobs
    except ImportError:
        from pursuit_bench.study.jobs import run_jobs

    out = args.results / "runs"
    out.mkdir(parents=True, exist_ok=True)
    budgets = list(design.BUDGETS) if args.budgets is None else [int(b) for b in args.budgets.split(",")]
    keep = tuple(budgets[:-1])
    condition = design.condition_of(setting)
    floor = 0
    if design.plain(setting):
        counted = rule_count(args, condition)
        if counted is None:
            return f"{setting}: the rule study's judged runs of {condition} (not all evaluated yet)"
        floor = counted
        record(args.results / "residual-study.json", floor=(setting, floor))  # the report's: at least the rule study's
    first = 0
    while True:
        wanted = max(design.seeds_wanted(own_runs(out, setting), args.first, args.step, args.most), floor)
        if first >= wanted:
            log(args.work, f"{setting}: {wanted} judged runs a kind, done")
            return "done"
        step = min(args.step if first else args.first, wanted - first)
        design.check_design({k: list(range(wanted)) for k in design.KINDS}, design.members(setting))
        folder = args.work / f"judged-{setting}-from{first}"
        mine = design.trained_here(setting, "judged")
        if all(
            (out / f"{setting}-{k}-seed{s}.json.gz").exists() for k in design.KINDS for s in range(first, first + step)
        ):
            first += step  # judged already (its results committed): not trained again, on any machine
            continue
        log(args.work, f"{setting}: judged seeds {first}–{first + step - 1}, {', '.join(mine)} trained here")
        if not sweep(args.work, folder, plan_for(setting, mine, first, step, args, keep), args.workers, stop):
            return "stop"
        where = population_folder(args, setting)
        if not (where / "population.json").exists():
            return f"{setting}: its population"
        sources: dict[tuple[str, int], tuple[Path, str | None]] = {}
        for seed in range(first, first + step):
            for kind in mine:
                sources[(kind, seed)] = (folder / "runs" / f"{setting}-{kind}-seed{seed}", None)
        if design.plain(setting):  # the rule study's hierarchical and flat runs, reused or trained again
            retrain = args.work / f"retrained-{setting}-from{first}"
            reference = plan_for(setting, ("hierarchical", "flat"), first, step, args, keep)
            found = {
                (kind, seed): rule_folder(args, setting, kind, seed) if seed < floor else None
                for kind in ("hierarchical", "flat")
                for seed in range(first, first + step)
            }
            if None in found.values():  # gone with the machine, or seeds the rule study has not: trained here
                log(args.work, f"{setting}: training hierarchical and flat runs the rule study's folders lack")
                if not sweep(args.work, retrain, reference, args.workers, stop):
                    return "stop"
            for (kind, seed), run in found.items():
                name = f"{setting}-{kind}-seed{seed}"
                earlier = args.rule_results / "runs" / f"{name}.json.gz" if seed < floor else None
                if earlier is not None and not earlier.exists():  # the rule study's count says it is there
                    raise SystemExit(f"{earlier}: missing, though the rule study's seed rule counts it")
                run = run or retrain / "runs" / name
                check_same_configuration(run, reference.runs()[name])
                sources[(kind, seed)] = (run, None if earlier is None else str(earlier))
        jobs = []
        for (kind, seed), (run, earlier_path) in sorted(sources.items(), key=lambda x: (x[0][1], x[0][0])):
            name = f"{setting}-{kind}-seed{seed}"
            if (out / f"{name}.json.gz").exists():
                continue
            trial = None if args.budgets is None else (args.eval_episodes, budgets)
            job = (str(run), str(where), str(out), name, setting, kind, seed, current["commit"], earlier_path, trial)
            jobs.append((name, job))
        if jobs:
            log(args.work, f"{setting}: evaluating {len(jobs)} runs against the population")
            try:
                run_jobs(
                    jobs,
                    judge,
                    args.work / "evaluation-parts",
                    {"build": current["code"]},
                    workers=args.workers,
                    progress=lambda n, total, s=setting: log(args.work, f"{s}: {n} of {total} evaluations"),
                )
            except ValueError as error:  # a reused run that does not replay as the rule study's, say
                log(args.work, f"stopped: {error}")
                raise SystemExit(str(error)) from None
        if stop[0]:
            return "stop"
        first += step


def check_same_configuration(run: Path, expected: Any) -> None:
    """SystemExit unless a reused run was trained with the configuration this study's plan gives it."""
    from pursuit_bench.training import runs

    saved, _ = runs.read_config(run)
    if saved != expected:
        differ = [f.name for f in dataclasses.fields(saved) if getattr(saved, f.name) != getattr(expected, f.name)]
        raise SystemExit(f"{run}: trained with another configuration than this study's ({', '.join(differ)})")


# --- main ---------------------------------------------------------------------------------------


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--work", type=Path, default=ROOT / "sweeps" / "residual-study", help="Run folders, logs.")
    parser.add_argument("--results", type=Path, default=ROOT / "results" / "residual-study")
    parser.add_argument(
        "--population",
        type=Path,
        default=ROOT / "pursuit_bench" / "pretrained" / "populations",
        help="Where the populations are written (<population>/<condition>/).",
    )
    parser.add_argument(
        "--rule-work", type=Path, default=ROOT / "sweeps" / "rule-study", help="The rule study's --work."
    )
    parser.add_argument("--rule-results", type=Path, default=ROOT / "results" / "rule-study")
    parser.add_argument(
        "--rule-population", type=Path, default=ROOT / "pursuit_bench" / "pretrained" / "populations" / "rule-study"
    )
    parser.add_argument("--settings", default="all", help="'all' or a comma-separated list.")
    parser.add_argument("--poll", type=int, default=600, help="Seconds between looks while waiting (0: exit 3).")
    parser.add_argument("--preset", default="reproduction", help="(only for trying the driver: quick)")
    parser.add_argument("--episodes", type=int, default=15000, help="(only for trying the driver)")
    parser.add_argument("--num-envs", type=int, default=32)
    parser.add_argument("--checkpoint-every", type=int, default=1000)
    parser.add_argument("--skip-build-check", action="store_true", help="(tests only)")
    parser.add_argument("--budgets", default=None, help="(tests only) e.g. 4,8; the last is --episodes")
    parser.add_argument("--eval-episodes", type=int, default=None, help="(tests only, with --budgets)")
    parser.add_argument("--first", type=int, default=design.FIRST_RUNS, help="(tests only) the seed rule's counts")
    parser.add_argument("--step", type=int, default=design.STEP_RUNS, help="(tests only)")
    parser.add_argument("--most", type=int, default=design.MOST_RUNS, help="(tests only)")
    parser.add_argument("--rule-first", type=int, default=None, help="(tests only) the rule study's count")
    args = parser.parse_args()
    settings = list(design.SETTINGS) if args.settings == "all" else args.settings.split(",")
    if unknown := [s for s in settings if s not in design.SETTINGS]:
        print(f"--settings: unknown {unknown}; expected some of {', '.join(design.SETTINGS)}", file=sys.stderr)
        return 2
    settings = [s for s in design.SETTINGS if s in settings]
    last = design.BUDGETS[-1] if args.budgets is None else int(args.budgets.split(",")[-1])
    if args.episodes != last:
        print(f"--episodes {args.episodes}: the study's last budget is {last}", file=sys.stderr)
        return 2
    args.work.mkdir(parents=True, exist_ok=True)
    from pursuit_bench.io.files import RunBusy, locked

    try:
        with locked(args.work):  # one driver a study: a second one refuses before it writes anything
            return drive(args, settings)
    except RunBusy as error:
        print(f"{error}: stop it first (kill -TERM its pid), or wait for it to finish", file=sys.stderr)
        return 2


def drive(args: Any, settings: list[str]) -> int:
    """The study from where it stands: 0 once finished, 143 when stopped by a signal, WAITING when
    it waits for the rule study and ``--poll`` is 0."""
    from pursuit_bench.io.files import atomic_write_text

    if args.skip_build_check:
        current = {"commit": "test", "code": "test", "training_code": "test"}
    else:
        current = build()
        pin(PIN, current, args.results, write=args.preset == "reproduction" and args.budgets is None)
    driver.check_started(args.work, current)
    (args.work / "driver.pid").write_text(f"{os.getpid()}\n")
    stop = driver.stop_flag(args.work)
    args.results.mkdir(parents=True, exist_ok=True)
    marker = args.results / "residual-study.json"  # what `pursuit-bench report` knows the folder by
    if not marker.exists():
        try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
            from pursuit_bench.reports import rule_study
        except ImportError:
            from pursuit_bench.study import rule_study

        about = {
            "format": rule_study.FORMAT,
            "protocol": "docs/residual.md, Protocol of the residual study",
            "kinds": list(design.KINDS),
            "comparisons": [list(c) for c in design.COMPARISONS],
            "settings": {s: {"condition": c, "obstacles": n} for s, (c, n) in design.SETTINGS.items()},
            "differs": design.DIFFERS,
            "command": "python studies/residual-value/run.py " + " ".join(sys.argv[1:]),
        }
        atomic_write_text(marker, json.dumps(about, indent=2) + "\n")
    record(marker, seed_rule={"first": args.first, "step": args.step, "most": args.most})
    log(
        args.work,
        f"residual study: {', '.join(settings)}; commit {current['commit'][:10]}, code {current['code']}, "
        f"training code {current['training_code']}",
    )
    while True:
        waiting = population(args, stop, settings, current)
        states: list[str] = ["stop"] if waiting == ["stop"] else []
        if not waiting:
            for setting in settings:
                states.append(judged(args, stop, setting, current))
                if states[-1] == "stop":  # a stop ends the round: no next setting is begun
                    break
        if stop[0] or "stop" in states:
            log(args.work, "stopped: rerun the same command to resume")
            return 143
        waiting += [s for s in states if s != "done"]
        if not waiting:
            log(args.work, "finished")
            return 0
        log(args.work, "waiting for " + "; ".join(waiting))
        if args.poll <= 0:
            return WAITING
        until = time.monotonic() + args.poll
        while time.monotonic() < until and not stop[0]:
            time.sleep(1)
        if stop[0]:
            log(args.work, "stopped: rerun the same command to resume")
            return 143


if __name__ == "__main__":
    sys.exit(main())
