"""The budget study's driver (issue 63; PROTOCOL.md and PLAN.md beside this file): trains each
condition's population, then the judged runs, to 10^6 episodes, cheapest conditions first, and
writes each condition's population at every budget.

Every run has two parts. Its first 15,000 episodes are trained by the rule study's own plan
(``first/``: the same sweep plan, so the same run), and a population member's prey there must
equal the committed rule-study member's to the bit (else the driver stops). Then the run folder is
copied into ``on/`` (atomically: a run there is complete or absent) and trained on from that
checkpoint to 10^6 by a plan that differs only in its length and its kept checkpoints (exact:
a resumed run equals one trained in one go). Run it against the study's pinned build:

    cd /work/main && PYTHONPATH=/work/budget-build nohup nice -n 19 .venv/bin/python \\
        studies/budget/run.py --workers 2 --populations pursuit_bench/pretrained/populations \\
        --results results/budget-study/runs > /dev/null 2>&1 &        # start, or resume (PLAN.md)
    kill -TERM "$(cat /work/budget-study/driver.pid)"               # stop cleanly (checkpoints; exit 143)
    tail -f /work/budget-study/progress.log                         # progress

The driver holds its work folder's lock, refuses a package other than ``build.json``'s (and,
once started, other than the one it started with: ``study.json``), and on SIGTERM or SIGINT stops
its workers (each checkpoints its stack) and exits 143; the same command resumes exactly.
Before a judged run is carried on, its first part is replayed against the rule study's population
and must give the rule study's committed result (PROTOCOL.md); as it ends, ``evaluate.py`` judges
it in a process of its own with this checkout's package. Each run's outcome (a population
member's prey at every budget, a judged run's compact result) is kept as the run ends where a
later machine finds it (``--populations``, ``--results``: committed), and only runs without one
are trained.

``--paper-first`` (added after the protocol, descriptive: PLAN.md, "Fig. 2 at 15,000 episodes")
trains only the judged runs' first parts, in a work folder of its own, and plays each by the
paper's protocol at its end (``evaluate.py --first-part``, after the same replay check), so that
the report draws the same runs' Fig. 2 at 15,000 beside 10^6 by the same evaluation:

    cd /work/budget-paper-run && PYTHONPATH=/work/budget-build nohup nice -n 19 /work/main/.venv/bin/python \\
        studies/budget/run.py --paper-first --work /work/budget-paper \\
        --judged-results /work/main/results/budget-study/runs \\
        --results /work/main/results/budget-study/paper-15000 > /dev/null 2>&1 &
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any


def _own_design() -> Any:
    """The study's design beside this file, as a module of its own name (the residual study's
    driver has a ``design`` of its own: a test process may load both)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("budget_design", Path(__file__).resolve().parent / "design.py")
    assert spec is not None and spec.loader is not None
    module = sys.modules.setdefault("budget_design", importlib.util.module_from_spec(spec))
    if not hasattr(module, "CONDITIONS"):
        spec.loader.exec_module(module)
    return module


design = _own_design()
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))  # the drivers' shared module alone
import driver  # noqa: E402

log = driver.log

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
WORK = Path("/work/budget-study")
STAGES = ("population", "judged")
#: A progress line per run every this many episodes.
PROGRESS_EVERY = 25_000


def package_build() -> dict[str, str]:
    """The build of the package this process imports: its checkout's commit and fingerprints.
    SystemExit if the package has uncommitted .py changes (a run is never trained by code that
    no commit holds)."""
    import pursuit_bench

    commit, listed = driver.committed_package(Path(pursuit_bench.__file__).resolve().parents[1])
    return {"commit": commit, **design.fingerprints(listed)}


def check_build(work: Path, current: dict[str, str], pinned: dict[str, str]) -> None:
    """SystemExit unless the package is the pinned build (``build.json``) and the one the
    study's work folder started with (``study.json``, written at the first start)."""
    for key in ("code", "training_code"):
        if current[key] != pinned[key]:
            raise SystemExit(
                f"the package is not the study's build: {key} {current[key]} (commit {current['commit'][:10]}), "
                f"build.json pins {pinned[key]} (commit {pinned['commit'][:10]}); "
                f"run with PYTHONPATH set to a checkout of {pinned['commit'][:10]}"
            )
    driver.check_started(work, current)


def sweep(work: Path, folder: Path, plan: Any, workers: int, stop: list[bool], finished: Any = None) -> bool:
    """Train ``plan``'s runs in ``folder`` (resuming what is there); whether all are done.
    ``finished(name)`` is called as each run ends (the driver stores a population member then).
    The workers' CPU time goes into ``work/cpu.jsonl`` (PLAN.md's rates, from the study's own runs)."""
    start = driver.child_cpu()
    episodes: dict[str, int] = {}
    done = driver.sweep(
        work, folder, plan, workers, stop, finished=finished, progress_every=PROGRESS_EVERY, episodes=episodes
    )
    record = {
        "sweep": folder.name,
        "part": folder.parent.name,
        "done": done,
        "worker_cpu_s": driver.child_cpu() - start,
    }
    record["last_episode"] = {name: n for name, n in episodes.items() if n}
    with (work / "cpu.jsonl").open("a") as file:
        file.write(json.dumps(record) + "\n")
    log(work, f"{folder.parent.name}/{folder.name}: workers' CPU {record['worker_cpu_s']:.0f} s this time")
    return done


def trained(folder: Path, episodes: int) -> bool:
    """Whether a run folder holds a checkpoint of at least ``episodes`` episodes."""
    from pursuit_bench.training import runs

    try:
        return int(runs.load_checkpoint(folder)["episodes_done"]) >= episodes
    except (ValueError, FileNotFoundError):
        return False


def carry_on(first: Path, on: Path, plan: Any, name: str) -> None:
    """Make ``on/runs/<name>`` the run of ``first`` set to train on by ``plan``: its config (the
    longer length; every budget but the last kept), metrics and checkpoint, that checkpoint also
    as the first budget's. Written beside and renamed into place: the folder is whole or absent."""
    from pursuit_bench.training import runs

    config, settings = runs.read_config(first)
    if name not in plan.runs():
        raise SystemExit(f"{first}: its run is not the plan's: {name} is not among its runs")
    target = plan.runs()[name]
    if config.to_dict() | {"episodes": target.episodes, "agent": target.agent.to_dict()} != target.to_dict():
        raise SystemExit(f"{first}: its run is not the plan's {name} but for the length")
    state = runs.load_checkpoint(first)
    done = int(state["episodes_done"])
    if done != config.episodes:
        raise SystemExit(f"{first}: trained {done} of {config.episodes} episodes; expected its end")
    scratch = on / "runs" / f".{name}.tmp"
    if scratch.exists():
        shutil.rmtree(scratch)
    scratch.mkdir(parents=True)
    runs.write_config(scratch, target, {**settings, "keep_checkpoints": list(plan.keep_checkpoints)})
    shutil.copy2(first / runs.METRICS, scratch / runs.METRICS)
    shutil.copy2(first / runs.CHECKPOINT, scratch / runs.CHECKPOINT)
    shutil.copy2(first / runs.CHECKPOINT, scratch / runs.milestone_checkpoint(done))
    os.replace(scratch, on / "runs" / name)


def population_check(work: Path, condition: str, kind: str, run: Path, committed: Path | None) -> None:
    """SystemExit unless the run's prey at its first part's end equals the committed member's."""
    from pursuit_bench.training import runs

    member = member_name(run.name)
    equal, differs = design.prey_equals_committed(run, runs.CHECKPOINT, condition, member, committed)
    if not equal:
        log(work, f"{run.name}: prey at 15,000 episodes differs from the committed {member} ({differs[:3]}): stopped")
        raise SystemExit(f"{run.name}: not the rule study's run (prey tensors differ: {', '.join(differs[:3])})")
    log(work, f"{run.name}: prey at its first part's end equals the committed {condition}/{member} to the bit")


def redesigned() -> bool:
    """Whether the ``pursuit_bench`` imported is 0.2's (rooms ``reports/``, ``benchmark/``) rather
    than the pinned build's. Asked of the package's own folder, not by trying an import: with the
    build first on the path, an editable install of a later checkout still answers for modules
    the build lacks, and mixed a later ``reports.rule_study`` with the build's training code."""
    import pursuit_bench

    return (Path(pursuit_bench.__file__).parent / "reports").is_dir()


def replay_check(args: Any, condition: str, run: Path) -> None:
    """SystemExit unless a judged run's first part, played at its end against the rule study's
    population by the rule study's evaluation, gives the rule study's committed result for that
    budget bit for bit (every member, every variant). What it played is kept in ``--work/replay/``."""
    import gzip

    if redesigned():  # this checkout's module paths; else the pinned build's (before 0.2's redesign)
        from pursuit_bench.reports import rule_study
    else:
        from pursuit_bench.study import rule_study

    from pursuit_bench.io.files import atomic_write_text

    committed_path = args.rule_results / f"{run.name}.json.gz"
    if not committed_path.exists():
        raise SystemExit(f"{committed_path}: no committed rule-study result to replay {run.name} against")
    committed = json.loads(gzip.decompress(committed_path.read_bytes()))
    budget = str(args.budgets[0])
    played = rule_study.evaluate_run(run, args.rule_population / condition, budgets=(args.budgets[0],))
    same = all(played[k] == committed[k] for k in ("protocol", "episodes", "eval_seed"))
    same = same and played["pool"][budget] == committed["pool"][budget]
    (args.work / "replay").mkdir(exist_ok=True)
    atomic_write_text(args.work / "replay" / f"{run.name}.json", json.dumps({"equal": same, **played}) + "\n")
    if not same:
        log(args.work, f"{run.name}: its {budget}-episode result differs from the rule study's committed one: stopped")
        raise SystemExit(f"{run.name}: not the rule study's run (its replay at {budget} episodes differs)")
    log(args.work, f"{run.name}: replayed at {budget} episodes, the rule study's committed result to the bit")


def member_folder(args: Any, condition: str, member: str, budget: int) -> Path:
    """Where a population member's prey at one budget is stored (the population's own folder)."""
    return args.populations / design.population_name(budget) / condition / member


def stored(args: Any, condition: str, member: str) -> bool:
    """Whether a member's prey is stored at every budget (by this machine or committed by an
    earlier one: a member is stored as its run ends, so a new machine trains on only the rest)."""
    return all((member_folder(args, condition, member, b) / "prey_0.safetensors").is_file() for b in args.budgets)


def member_name(run_name: str) -> str:
    """A population run's member: ``3p-low-shared-flat-seed1004`` -> ``flat-seed1004``."""
    kind = next(k for k in design.KINDS if f"-{k}-seed" in run_name)
    return f"{kind}-seed{run_name.rsplit('seed', 1)[1]}"


def gather(on: Path, tag: str, folder: Path, names: list[str]) -> None:
    """Move each of ``names``' run folders found in another continuation sweep of ``tag`` (an
    earlier subset, on this machine) into ``folder``'s: a run folder holds all it resumes from."""
    for name in names:
        if (folder / "runs" / name).exists():
            continue
        for other in sorted(on.glob(f"{tag}*/runs/{name}")):
            os.replace(other, folder / "runs" / name)
            break


def kept(args: Any, stage: str, condition: str, kind: str, seed: int) -> bool:
    """Whether a run's outcome is kept where a later machine finds it: a population member's prey
    at every budget, or a judged run's compact result (``--results/<run>.json.gz``)."""
    if stage == "population":
        return stored(args, condition, f"{kind}-seed{seed}")
    return (args.results / f"{design.run_name(condition, kind, seed)}.json.gz").is_file()


def keep(args: Any, stage: str, condition: str, run: Path) -> None:
    """Keep a finished run's outcome (:func:`kept`): store its prey, or evaluate it."""
    if stage == "population":
        store_member(args, condition, run)
    elif not (args.results / f"{run.name}.json.gz").is_file():
        evaluate_judged(args, condition, run)


def consecutive(seeds: list[int], most: int) -> list[list[int]]:
    """``seeds`` (increasing) cut into runs of consecutive seeds, each at most ``most`` long."""
    chunks: list[list[int]] = []
    for seed in seeds:
        if chunks and seed == chunks[-1][-1] + 1 and len(chunks[-1]) < most:
            chunks[-1].append(seed)
        else:
            chunks.append([seed])
    return chunks


def unit(args: Any, stage: str, condition: str, kind: str, stop: list[bool]) -> bool:
    """One kind's runs of a condition through both parts; whether they are done. A run whose
    outcome is kept (:func:`kept`) is not trained on again. The population's runs go through
    together (the smallest run of seeds holding the rest). The judged runs go in chunks of at most
    ``--workers`` consecutive seeds, each chunk through both parts before the next starts, so that
    a session's first run is carried on minutes after the session starts, not after every first
    part (a run finishes only within one session: PLAN.md); each run's config is its own whichever
    plan holds it, and the replay check proves each first part to the bit."""
    import dataclasses

    on_plan = design.continuation_plan(stage, condition, kind, args.budgets, args.judged_seeds, **args.trial)
    seeds = range(on_plan.first_seed, on_plan.first_seed + on_plan.seeds)
    rest = [s for s in seeds if not kept(args, stage, condition, kind, s)]
    tag = f"{stage}-{kind}-{condition}"
    if not rest:
        log(args.work, f"{tag}: every run's outcome is kept: not trained again")
        return True
    if len(rest) < on_plan.seeds:
        log(args.work, f"{tag}: seeds {', '.join(map(str, rest))} to train; the others' outcomes are kept")
    chunks = consecutive(rest, args.workers) if stage == "judged" else [list(range(rest[0], rest[-1] + 1))]
    whole = chunks == [list(seeds)]
    for chunk in chunks:
        span = dataclasses.replace(on_plan, predators=(kind,), first_seed=chunk[0], seeds=len(chunk))
        on = args.work / "on" / (tag if whole else f"{tag}-seeds{chunk[0]}-{chunk[-1]}")
        if stop[0] or not part(args, stage, condition, kind, span, on, stop):
            return False
    return True


def part(args: Any, stage: str, condition: str, kind: str, on_plan: Any, on: Path, stop: list[bool]) -> bool:
    """``on_plan``'s runs (one kind's, some seeds) through both parts in ``on``; whether done. The
    judged runs' first part on a new machine is the rule study's plan restricted to these runs (in
    a work folder that holds the whole plan's first part, both kinds', that one)."""
    import dataclasses

    trial = args.trial
    tag = f"{stage}-{kind}-{condition}"
    first_tag = tag if stage == "population" else f"judged-{condition}"

    def finished(name: str) -> None:
        keep(args, stage, condition, on / "runs" / name)

    names = sorted(on_plan.runs())
    if all(trained(on / "runs" / n, on_plan.episodes) for n in names):
        for name in names:
            finished(name)
        return True
    first_plan = design.first_part(stage, condition, kind, args.budgets, args.rule_keep, **trial)
    first = args.work / "first" / first_tag
    if stage == "judged" and not first.exists():
        # Only this kind's runs still to do: the same runs (a run's config is its own, whichever
        # plan holds it; the replay check proves each to the bit), not both kinds' twenty again.
        first_plan = dataclasses.replace(
            first_plan, predators=(kind,), first_seed=on_plan.first_seed, seeds=on_plan.seeds
        )
        first = args.work / "first" / on.name
    from pursuit_bench.training.sweep import open_sweep

    if on.exists():
        (on / "runs").mkdir(exist_ok=True)
        gather(args.work / "on", tag, on, names)
    waiting = [n for n in names if not trained(on / "runs" / n, args.budgets[0])]
    if waiting:
        log(args.work, f"{tag}: first {args.budgets[0]} episodes by the rule study's plan ({len(waiting)} runs)")
        if not sweep(args.work, first, first_plan, args.workers, stop):
            return False
        open_sweep(on, on_plan)  # the plan first: a sweep's folder holds its plan before its runs
        (on / "runs").mkdir(parents=True, exist_ok=True)
        gather(args.work / "on", tag, on, names)
        for name in [n for n in names if not trained(on / "runs" / n, args.budgets[0])]:
            if stop[0]:
                return False
            if stage == "population" and not args.no_population_check:
                population_check(args.work, condition, kind, first / "runs" / name, args.committed)
            if stage == "judged" and not args.no_replay_check:
                replay_check(args, condition, first / "runs" / name)
            carry_on(first / "runs" / name, on, on_plan, name)
    log(args.work, f"{tag}: on to {on_plan.episodes} episodes, checkpoints kept at {list(on_plan.keep_checkpoints)}")
    done = sweep(args.work, on, on_plan, args.workers, stop, finished)
    for name in names:
        if trained(on / "runs" / name, on_plan.episodes):
            finished(name)  # heard of before a stop, or trained earlier
    return done


def evaluate_judged(args: Any, condition: str, run: Path, first_part: bool = False) -> None:
    """A finished judged run evaluated by ``evaluate.py`` in a process of its own with this
    checkout's package (which first replays the rule study's result), its compact result written
    to ``--results``; SystemExit if that fails. ``first_part``: the run is a first part alone,
    played by the paper's protocol at its end only (:func:`paper_first`)."""
    command = [
        sys.executable, str(HERE / "evaluate.py"), str(run), "--condition", condition, "--build", args.build["commit"],
        "--populations", str(args.populations), "--out", str(args.results),
        "--budgets", ",".join(str(b) for b in args.budgets),
    ]  # fmt: skip
    if args.eval_episodes is not None:
        command += ["--episodes", str(args.eval_episodes), "--paper-episodes", str(args.eval_episodes)]
    if args.no_replay_check:
        command.append("--no-replay-check")
    if first_part:
        command += ["--first-part", "--judged-results", str(args.judged_results)]
        log(args.work, f"{run.name}: evaluating its first part (the paper's protocol at its end)")
    else:
        log(args.work, f"{run.name}: evaluating (populations of every budget, the paper's protocol at the last)")
    done = subprocess.run(command, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True)
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        log(args.work, f"{run.name}: its evaluation failed ({last}): stopped")
        raise SystemExit(f"{run.name}: its evaluation failed: {last}")
    log(args.work, f"{run.name}: evaluated, {done.stdout.strip()}")


def paper_first(args: Any, condition: str, kind: str, stop: list[bool]) -> bool:
    """``--paper-first`` (PLAN.md, "Fig. 2 at 15,000 episodes": added after the protocol,
    descriptive): a kind's judged runs' first part trained again by the rule study's plan and, as
    each ends, evaluated by ``evaluate.py --first-part`` (replayed to the bit against the rule
    study's committed result and, where it is committed, against the budget study's own judged
    run; then the paper's comparison at its end), its compact result kept in ``--results``; a run
    with one is not trained again, and a chunk's runs trained in part by an earlier chunk (a stop)
    go on from where they were. Whether all are done."""
    import dataclasses
    import gzip

    from pursuit_bench.training.sweep import open_sweep

    tag = f"paper-{kind}-{condition}"
    seeds = design.JUDGED_SEEDS[: args.judged_seeds]
    for seed in seeds:
        path = args.results / f"{design.run_name(condition, kind, seed)}.json.gz"
        if path.is_file() and json.loads(gzip.decompress(path.read_bytes())).get("format") != "budget-study-paper-1":
            raise SystemExit(f"{path}: not a first part's result: give --paper-first a --results of its own")
    rest = [s for s in seeds if not kept(args, "judged", condition, kind, s)]
    if not rest:
        log(args.work, f"{tag}: every run's first part is evaluated: not trained again")
        return True
    rule_plan = design.first_part("judged", condition, kind, args.budgets, args.rule_keep, **args.trial)
    for chunk in consecutive(rest, len(rest)):
        plan = dataclasses.replace(rule_plan, predators=(kind,), first_seed=chunk[0], seeds=len(chunk))
        first = args.work / "first" / f"{tag}-seeds{chunk[0]}-{chunk[-1]}"
        names = sorted(plan.runs())
        if not first.exists():
            open_sweep(first, plan)  # the plan first: a sweep's folder holds its plan before its runs
        (first / "runs").mkdir(parents=True, exist_ok=True)
        gather(args.work / "first", tag, first, names)  # a run begun in an earlier chunk's folder

        def finished(name: str, first: Path = first) -> None:
            if not (args.results / f"{name}.json.gz").is_file():
                evaluate_judged(args, condition, first / "runs" / name, first_part=True)

        log(args.work, f"{tag}: seeds {chunk[0]}-{chunk[-1]}, {args.budgets[0]} episodes by the rule study's plan")
        if stop[0] or not sweep(args.work, first, plan, args.workers, stop, finished):
            return False
        for name in names:
            finished(name)  # trained earlier, or heard of before a stop
    return True


def populations_written(args: Any, condition: str) -> bool:
    """Whether every budget's population of ``condition`` is written (the judged runs' judges)."""
    return all(
        (args.populations / design.population_name(b) / condition / "population.json").is_file() for b in args.budgets
    )


def store_member(args: Any, condition: str, run: Path) -> None:
    """Write a finished population run's prey at every budget into its populations' folders
    (``<populations>/<name>/<condition>/<member>/prey_0.safetensors``, weights only), each
    written beside and renamed into place; a member already stored is left as it is."""
    from pursuit_bench import pretrained
    from pursuit_bench.training import runs

    member = member_name(run.name)
    if stored(args, condition, member):
        return
    for budget in args.budgets:
        folder = member_folder(args, condition, member, budget)
        if (folder / "prey_0.safetensors").is_file():
            continue
        checkpoint = runs.CHECKPOINT if budget == args.budgets[-1] else runs.milestone_checkpoint(budget)
        config, agents, about = runs.described(run, checkpoint)
        if about["trained_episodes"] != budget:
            raise SystemExit(f"{run}/{checkpoint}: {about['trained_episodes']} episodes, expected {budget}")
        name = design.population_name(budget)
        provenance = {"population": name, "member": member, "build": args.build["commit"]}
        scratch = folder.parent / f".{member}.tmp"
        shutil.rmtree(scratch, ignore_errors=True)
        written = pretrained.export(
            {"prey_0": agents["prey_0"]}, config, scratch / ".export", trained_episodes=budget, provenance=provenance
        )[0]
        os.replace(written, scratch / "prey_0.safetensors")
        shutil.rmtree(scratch / ".export")
        if folder.exists():
            shutil.rmtree(folder)  # a member folder without its weights: an older, partial one
        os.replace(scratch, folder)
    log(args.work, f"{condition}/{member}: stored at every budget in {args.populations}")


def write_populations(args: Any, condition: str) -> None:
    """Each budget's ``population.json`` of ``condition`` (FleeingPrey and the 8 learned prey,
    stored as their runs ended), in the population format, once every member is stored."""
    from pursuit_bench.io.files import atomic_write_text

    for budget in args.budgets:
        name = design.population_name(budget)
        folder = args.populations / name / condition
        if (folder / "population.json").exists():
            continue
        entries = []
        for member in design.members(condition):
            files: dict[str, str] = {}
            trained_as = None
            if member["policy"] is None:
                if not (member_folder(args, condition, member["name"], budget) / "prey_0.safetensors").is_file():
                    raise SystemExit(f"{folder}: member {member['name']} is not stored")
                trained_as = {
                    "preset": args.trial.get("preset", design.PRESET),
                    "episodes": budget,
                    "predator_kind": member["kind"],
                    "build": args.build["commit"],
                }
                files = {"prey_0": f"{member['name']}/prey_0.safetensors"}
            entries.append({**member, "trained": trained_as, "files": files})
        document = {
            "population": name,
            "condition": condition,
            "role": "prey",
            "provisional": False,
            "members": entries,
        }
        atomic_write_text(folder / "population.json", json.dumps(document, indent=2) + "\n")
        log(args.work, f"population {name} of {condition} written to {folder}")


def drive(args: Any) -> int:
    """The study from where it stands: 0 once every run is trained, 143 when stopped."""
    if args.skip_build_check:
        args.build = {"commit": "test", "code": "test", "training_code": "test"}
    else:
        args.build = package_build()
        check_build(args.work, args.build, json.loads((HERE / "build.json").read_text()))
    (args.work / "driver.pid").write_text(f"{os.getpid()}\n")
    stop = driver.stop_flag(args.work)
    what = "first parts by the paper's protocol" if args.paper_first else f"stages {', '.join(args.stages)}"
    log(
        args.work,
        f"budget study: {', '.join(args.conditions)}; {what}; budgets {list(args.budgets)}; "
        f"commit {args.build['commit'][:10]}, code {args.build['code']}, pid {os.getpid()}",
    )
    if args.paper_first:
        for condition in args.conditions:
            for kind in args.kinds:
                if stop[0] or not paper_first(args, condition, kind, stop):
                    log(args.work, "stopped: rerun the same command to resume")
                    return 143
        log(args.work, "finished: every judged run's first part played by the paper's protocol")
        return 0
    waiting = []
    for stage in args.stages:
        for condition in args.conditions:
            if stage == "judged" and not populations_written(args, condition):
                log(args.work, f"judged-{condition}: not every budget's population is written yet: left for later")
                waiting.append(condition)
                continue
            for kind in args.kinds:
                if stop[0] or not unit(args, stage, condition, kind, stop):
                    log(args.work, "stopped: rerun the same command to resume")
                    return 143
            if stage == "population" and all(
                stored(args, condition, m["name"]) for m in design.members(condition) if m["policy"] is None
            ):
                write_populations(args, condition)
    if waiting:
        log(
            args.work, f"finished what could be trained; judged runs of {', '.join(waiting)} wait for their populations"
        )
        return 0
    log(args.work, "finished: every run trained")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--work", type=Path, default=WORK, help="Run folders, progress.log, the lock.")
    parser.add_argument(
        "--populations",
        type=Path,
        default=None,
        help="Where members are stored and populations written (the study's: the package's populations "
        "folder of this checkout, to be committed). Default: --work/populations.",
    )
    parser.add_argument("--conditions", default=",".join(design.CONDITIONS))
    parser.add_argument("--stages", default=",".join(STAGES), help="population, judged or both, in that order.")
    parser.add_argument(
        "--kinds",
        default=",".join(design.KINDS),
        help="The kinds to train, in the order given (a session too short for one kind's long run "
        "does the cheaper kind first: every run's outcome is kept as it ends, whatever the order).",
    )
    parser.add_argument("--budgets", default=None, help="(trying the driver only) e.g. 4,8,12")
    parser.add_argument("--preset", default=None, help="(trying the driver only) e.g. quick")
    parser.add_argument("--num-envs", type=int, default=None, help="(trying the driver only)")
    parser.add_argument("--checkpoint-every", type=int, default=None, help="(trying the driver only)")
    parser.add_argument("--committed", type=Path, default=None, help="(tests only) the rule-study populations' root")
    parser.add_argument(
        "--judged-seeds", type=int, default=len(design.JUDGED_SEEDS), help="Only by PROTOCOL.md's cut: 6 to 10."
    )
    parser.add_argument("--rule-results", type=Path, default=ROOT / "results" / "rule-study" / "runs")
    parser.add_argument(
        "--judged-results",
        type=Path,
        default=ROOT / "results" / "budget-study" / "runs",
        help="With --paper-first: the judged runs' results, which a first part must match where committed.",
    )
    parser.add_argument("--rule-population", type=Path, default=None, help="Default: the package's rule-study.")
    parser.add_argument("--no-replay-check", action="store_true", help="(trying the driver only)")
    parser.add_argument(
        "--results",
        type=Path,
        default=None,
        help="Where judged runs' compact results go (the study's: results/budget-study/runs). Default: --work/results.",
    )
    parser.add_argument("--eval-episodes", type=int, default=None, help="(trying the driver only)")
    parser.add_argument("--no-population-check", action="store_true", help="(trying the driver only)")
    parser.add_argument("--skip-build-check", action="store_true", help="(tests only)")
    parser.add_argument(
        "--paper-first",
        action="store_true",
        help="Only the judged runs' first parts, each played by the paper's protocol at its end into --results "
        '(PLAN.md, "Fig. 2 at 15,000 episodes"); give another --work than the study\'s.',
    )
    args = parser.parse_args()
    args.conditions = args.conditions.split(",")
    if unknown := [c for c in args.conditions if c not in design.CONDITIONS]:
        print(f"--conditions: unknown {unknown}; expected some of {', '.join(design.CONDITIONS)}", file=sys.stderr)
        return 2
    args.conditions = [c for c in design.CONDITIONS if c in args.conditions]
    args.kinds = args.kinds.split(",")
    if not set(args.kinds) <= set(design.KINDS) or len(set(args.kinds)) < len(args.kinds):
        print(f"--kinds: {args.kinds} is not some of {', '.join(design.KINDS)}, each once", file=sys.stderr)
        return 2
    args.stages = args.stages.split(",")
    if unknown := [s for s in args.stages if s not in STAGES]:
        print(f"--stages: unknown {unknown}; expected some of {', '.join(STAGES)}", file=sys.stderr)
        return 2
    args.stages = [s for s in STAGES if s in args.stages]
    if not design.MIN_CUT_SEEDS <= args.judged_seeds <= len(design.JUDGED_SEEDS):
        print(f"--judged-seeds {args.judged_seeds}: expected {design.MIN_CUT_SEEDS} to 10", file=sys.stderr)
        return 2
    if args.rule_population is None:
        if redesigned():  # this checkout's module paths; else the pinned build's (before 0.2's redesign)
            from pursuit_bench.benchmark import populations
        else:
            from pursuit_bench.pretrained import populations

        args.rule_population = populations.FOLDER / design.RULE_POPULATION
    if args.workers < 1:
        print(f"--workers {args.workers}: expected at least 1", file=sys.stderr)
        return 2
    args.trial = {
        k: v
        for k, v in (("preset", args.preset), ("num_envs", args.num_envs), ("checkpoint_every", args.checkpoint_every))
        if v is not None
    }
    args.rule_keep = design.RULE_KEEP
    if args.budgets is None:
        args.budgets = design.BUDGETS
    else:
        try:
            args.budgets = tuple(int(b) for b in args.budgets.split(","))
        except ValueError:
            print(f"--budgets {args.budgets!r}: expected increasing integers, e.g. 4,8,12", file=sys.stderr)
            return 2
        if len(args.budgets) < 2 or any(b < 1 for b in args.budgets) or list(args.budgets) != sorted(set(args.budgets)):
            print(f"--budgets {args.budgets}: expected at least two increasing integers >= 1", file=sys.stderr)
            return 2
        args.rule_keep = ()
    trying = args.trial or args.budgets != design.BUDGETS or args.no_population_check or args.no_replay_check
    if args.paper_first and args.work == WORK:
        print("--paper-first: give another --work than the study's (its driver's folder)", file=sys.stderr)
        return 2
    if trying and args.work == WORK:
        print("trying the driver (--budgets, --preset …): give another --work than the study's", file=sys.stderr)
        return 2
    if args.paper_first and args.populations is None:  # the committed populations a first part is checked on
        args.populations = ROOT / "pursuit_bench" / "pretrained" / "populations"
    args.populations = args.populations or args.work / "populations"
    args.results = args.results or args.work / "results"
    args.work.mkdir(parents=True, exist_ok=True)
    from pursuit_bench.io.files import RunBusy, locked

    try:
        with locked(args.work):  # one driver a study: a second refuses before it writes anything
            return drive(args)
    except RunBusy as error:
        print(f"{error}: stop it first (kill -TERM its pid), or wait for it to finish", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
