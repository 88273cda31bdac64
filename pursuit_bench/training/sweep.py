"""A sweep: conditions × seeds × predator kinds, every run a normal run folder, trained in
stacks spread over worker processes, then evaluated by the paper's protocol.

``sweeps/NAME/sweep.json`` holds the plan; ``sweeps/NAME/runs/<condition>-<predator>-seed<S>/``
each run. Runs whose networks have the same shapes (same predator kind and number of
predators) are grouped into stacks (:mod:`pursuit_bench.training.stack`); each stack is one task for a
worker. Rerunning the same command skips finished runs and resumes the others from their
checkpoints. Workers report progress through a queue; a worker stops (checkpointing its stack)
on SIGINT or SIGTERM, or when the process that started it is gone.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import multiprocessing
import os
import queue
import tempfile
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pursuit_bench.agents.config import QUICK, AgentConfig
from pursuit_bench.env.conditions import CHASE_COSTS, CONDITIONS, OBSTACLE_RADIUS, TaskConfig
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.training import runs
from pursuit_bench.training.train import TrainConfig

if TYPE_CHECKING:
    from pursuit_bench.training.evaluate import Figure

SWEEP_FORMAT = "pursuit-bench-sweep-1"
PLAN = "sweep.json"
#: The evaluation seed of every run of a sweep (the CLI's ``eval`` default).
EVAL_SEED = 12345


@dataclass(frozen=True)
class SweepPlan:
    """What a sweep trains: every condition × seed × predator kind, one run each."""

    conditions: tuple[str, ...]
    """Conditions, in order (``pursuit_bench.CONDITIONS``)."""
    seeds: int
    """How many seeds, from ``first_seed`` on, for every condition and predator kind."""
    predators: tuple[str, ...] = ("hierarchical",)
    """Predator kinds to train (``hierarchical``, ``flat``, or a fixed baseline)."""
    agent: AgentConfig = QUICK
    """Hyper-parameters of every learner (a preset with any overrides)."""
    episodes: int = 2000
    """Training episodes of every run."""
    eval_episodes: int = 1000
    """Episodes per variant of each run's evaluation (paper 3.4: 1000)."""
    num_envs: int = 8
    """Arenas per run."""
    backend: str = "pymunk"
    """Physics backend of every run."""
    record_every: int = 100
    """Every run records its first and every Nth training episode."""
    checkpoint_every: int = 100
    """Episodes between checkpoints (a stack's unfinished runs checkpoint together)."""
    preset: str = "quick"
    """Name of the preset ``agent`` started from (for the record)."""
    keep_checkpoints: tuple[int, ...] = ()
    """Episode counts at which every run keeps its checkpoint (``checkpoint-epN.pt``), each
    evaluated like the final one into ``eval-epN.json``: learning against budget."""
    obstacles: int = 0
    """Obstacles per arena in every run (0: the paper's empty arena)."""
    obstacle_radius: float = OBSTACLE_RADIUS
    """Radius of every obstacle."""
    avoidance: bool = True
    """With obstacles: the predators' lower layer avoids them (``TrainConfig.avoidance``)."""
    first_seed: int = 0
    """The first seed: the sweep trains seeds ``first_seed … first_seed + seeds - 1`` (the rule
    study's population trains from 1000, apart from the judged runs)."""

    def __post_init__(self) -> None:
        unknown = [c for c in self.conditions if c not in CONDITIONS]
        if unknown or not self.conditions:
            raise ValueError(f"conditions={list(self.conditions)!r}: expected some of {', '.join(CONDITIONS)}")
        if isinstance(self.seeds, bool) or not isinstance(self.seeds, int) or self.seeds < 1:
            raise ValueError(f"seeds={self.seeds!r}: expected an integer >= 1")
        kinds = ("hierarchical", "flat", "residual", "always_chase", "always_stalk")
        if not self.predators or any(p not in kinds for p in self.predators):
            raise ValueError(f"predators={list(self.predators)!r}: expected some of {', '.join(kinds)}")
        TaskConfig(obstacles=self.obstacles, obstacle_radius=self.obstacle_radius)  # refuses bad obstacle options
        if any(
            isinstance(n, bool) or not isinstance(n, int) or not 1 <= n < self.episodes for n in self.keep_checkpoints
        ):
            raise ValueError(
                f"keep_checkpoints={list(self.keep_checkpoints)!r}: expected episode counts in [1, {self.episodes})"
            )

    def runs(self) -> dict[str, TrainConfig]:
        """Every run by its folder name, ``<condition>-<predator>-seed<S>``; with obstacles
        ``<condition>-obstacles<K>-<predator>[-noavoid]-seed<S>``."""
        middle = f"-obstacles{self.obstacles}" if self.obstacles else ""
        after = "-noavoid" if self.obstacles and not self.avoidance else ""
        return {
            f"{condition}{middle}-{predator}{after}-seed{seed}": TrainConfig(
                condition=condition,
                agent=self.agent,
                episodes=self.episodes,
                num_envs=self.num_envs,
                seed=seed,
                predator=predator,  # type: ignore[arg-type]
                backend=self.backend,  # type: ignore[arg-type]
                obstacles=self.obstacles,
                obstacle_radius=self.obstacle_radius,
                avoidance=self.avoidance,
            )
            for predator in self.predators
            for condition in self.conditions
            for seed in range(self.first_seed, self.first_seed + self.seeds)
        }

    def to_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "agent": self.agent.to_dict()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SweepPlan:
        fields = {**data, "agent": AgentConfig().replace(**data["agent"])}
        fields.update(conditions=tuple(data["conditions"]), predators=tuple(data["predators"]))
        fields["keep_checkpoints"] = tuple(data.get("keep_checkpoints", ()))
        return cls(**fields)


#: Mean episode length (env steps) by number of predators and chase cost, with the predators
#: and the prey trained: the reproduction sweep's evaluations (REPRODUCTION.md, the prey table).
EPISODE_STEPS = {(1, "low"): 15, (1, "high"): 144, (2, "low"): 10, (2, "high"): 66, (3, "low"): 8, (3, "high"): 28}
#: How much longer the flat ablation's episodes run (REPRODUCTION.md: 1.5–3 times the transitions).
FLAT_FACTOR = 2.0


def expected_transitions(config: TrainConfig) -> float:
    """What a run is expected to cost: its arena-steps (transitions), from its condition and
    predator kind (``EPISODE_STEPS``). Every learner acts and learns on each transition, so a
    stack's time is about its runs' transitions times their learners."""
    condition = CONDITIONS[config.condition]
    cost = "high" if condition.chase_cost >= CHASE_COSTS["high"] else "low"
    steps = EPISODE_STEPS[(condition.n_predators, cost)] * (FLAT_FACTOR if config.predator == "flat" else 1.0)
    return config.episodes * steps


def expected_cost(config: TrainConfig) -> float:
    """Transitions times learning agents: the unit of work the sweep plans and counts by."""
    return expected_transitions(config) * (CONDITIONS[config.condition].n_predators + 1)


def stacks(plan: SweepPlan, names: list[str], workers: int, max_runs: int = 16) -> list[list[str]]:
    """Runs grouped into stacks, longest first: runs of one stack share network shapes
    (predator kind and number of predators); stacks hold at most ``max_runs``. Planned by
    expected cost (:func:`expected_cost`), not by count: a group of runs is cut into stacks
    of at most half a worker's share of the total each, its runs dealt longest first to the
    stack with the least cost so far, so that workers taking stacks longest first finish
    together."""
    all_runs = plan.runs()
    groups: dict[tuple[str, int], list[str]] = {}
    for name in names:
        config = all_runs[name]
        groups.setdefault((config.predator, CONDITIONS[config.condition].n_predators), []).append(name)
    cost = {name: expected_cost(all_runs[name]) for name in names}
    share = sum(cost.values()) / (2 * max(workers, 1))
    planned: list[list[str]] = []
    for members in groups.values():
        total = sum(cost[n] for n in members)
        count = max(math.ceil(total / share) if share > 0 else 1, math.ceil(len(members) / max_runs))
        count = min(count, len(members))
        bins: list[list[str]] = [[] for _ in range(count)]
        for name in sorted(members, key=lambda n: (-cost[n], n)):
            open_bins = [b for b in bins if len(b) < max_runs]
            min(open_bins, key=lambda b: sum(cost[n] for n in b)).append(name)
        planned += [sorted(b, key=members.index) for b in bins if b]
    return sorted(planned, key=lambda b: -sum(cost[n] for n in b))


def plan_differences(saved: SweepPlan, plan: SweepPlan) -> list[str]:
    """What differs between two plans, one ``name: saved → given`` per field (hyper-parameters
    by their own names)."""
    before, after = saved.to_dict(), plan.to_dict()
    for agent in (before, after):
        agent.update({f"agent.{k}": v for k, v in agent.pop("agent").items()})
    return [f"{k}: {before.get(k)!r} → {after.get(k)!r}" for k in sorted(after) if before.get(k) != after.get(k)]


def open_sweep(out: Path, plan: SweepPlan) -> str | None:
    """Write the plan into ``out`` (a new sweep) or check that ``out`` holds this plan. A plan
    that differs only by more ``episodes`` extends the sweep (its runs train on from their
    checkpoints; returns a note saying so); any other difference is a ValueError naming it."""
    path = out / PLAN
    if path.exists():
        try:
            saved_payload = json.loads(path.read_text())
            if saved_payload.get("format") != SWEEP_FORMAT:
                raise ValueError(f"format {saved_payload.get('format')!r}")
            saved = SweepPlan.from_dict(saved_payload["plan"])
        except (ValueError, KeyError, TypeError) as error:
            raise ValueError(f"{path}: not a pursuit-bench sweep plan ({error})") from None
        if saved == plan:
            return None
        differences = plan_differences(saved, plan)
        if dataclasses.replace(saved, episodes=plan.episodes) == plan and plan.episodes > saved.episodes:
            _write_plan(path, plan)
            return f"extending the sweep from {saved.episodes} to {plan.episodes} episodes a run"
        raise ValueError(
            f"{out} holds a sweep with another plan ({'; '.join(differences)}); give the same options, "
            "a larger --episodes to extend it, or another --out"
        )
    if out.exists() and any(out.iterdir()):
        raise ValueError(f"{out}: the folder is not empty and holds no sweep; choose another --out")
    out.mkdir(parents=True, exist_ok=True)
    _write_plan(path, plan)
    return None


def _write_plan(path: Path, plan: SweepPlan) -> None:
    payload = {"format": SWEEP_FORMAT, "plan": plan.to_dict(), "runs": sorted(plan.runs())}
    atomic_write_text(path, json.dumps(payload, indent=2) + "\n")


def milestone_tag(episodes: int) -> str:
    """The evaluation tag of a kept checkpoint: ``eval-ep1500.json`` …"""
    return f"ep{episodes}"


def run_status(folder: Path, config: TrainConfig, keep: tuple[int, ...] = ()) -> tuple[int, bool]:
    """(episodes trained, evaluated) of a sweep's run folder, from its checkpoint, eval.json
    and the evaluations of its kept checkpoints (``keep``)."""
    try:
        done = int(runs.load_checkpoint(folder)["episodes_done"])
    except ValueError:
        return 0, False
    evaluations = ["eval.json", *(runs.eval_paths(folder, milestone_tag(n))["json"].name for n in keep)]
    return done, done >= config.episodes and all((folder / name).exists() for name in evaluations) and (
        _evaluated_at(folder) == done
    )


def _evaluated_at(folder: Path) -> int | None:
    """The episode count of the checkpoint ``eval.json`` evaluated (None without one)."""
    try:
        return int(json.loads((folder / "eval.json").read_text())["trained_episodes"])
    except (FileNotFoundError, ValueError, KeyError, TypeError):
        return None


def _prepare(folder: Path, name: str, config: TrainConfig, plan: SweepPlan) -> dict[str, Any] | None:
    """Make ``folder`` hold run ``name`` (its lock held); the checkpoint to resume from, or None."""
    folder.mkdir(parents=True, exist_ok=True)
    if runs.is_run(folder) and (folder / runs.CHECKPOINT).exists():
        saved, settings = runs.read_config(folder)
        if saved != config and dataclasses.replace(saved, episodes=config.episodes) == config:
            runs.write_config(folder, config, settings)  # the sweep was extended: train on to its target
        elif saved != config:
            raise ValueError(f"{folder} holds a run with another configuration than the sweep's {name}")
        return runs.load_checkpoint(folder)
    runs.clear(folder)
    settings = {
        "preset": plan.preset,
        "record_every": plan.record_every,
        "checkpoint_every": plan.checkpoint_every,
        "recording_id": uuid.uuid4().hex,
        "keep_checkpoints": list(plan.keep_checkpoints),
    }
    runs.write_config(folder, config, settings)
    return None


@dataclass(frozen=True)
class Work:
    """How each stack of a sweep is worked: what the local workers and Ray tasks are handed."""

    record: bool = True
    """Whether episodes are recorded (Rerun)."""
    threads: int = 1
    """torch threads per stack."""
    figure: Figure | None = None
    """Draws each evaluation's figure (:func:`~pursuit_bench.training.evaluate.evaluate_into`)."""


def run_stack(out: Path, names: list[str], messages: Any, work: Work = Work()) -> None:
    """A worker's task: train the runs ``names`` of the sweep in ``out`` as one stack, then
    evaluate each. Sends ``("episode", name, n)`` as episodes finish and ``("done", name,
    None)`` when a run is trained and evaluated into ``messages``. Stops, checkpointing, on
    SIGINT, SIGTERM or when its parent process is gone."""
    import torch

    from pursuit_bench.io.signals import SignalCatcher
    from pursuit_bench.training.evaluate import evaluate_folder
    from pursuit_bench.training.stack import FolderRun, train_stack

    torch.set_num_threads(work.threads)
    plan = SweepPlan.from_dict(json.loads((out / PLAN).read_text())["plan"])
    configs = plan.runs()
    parent = os.getppid()
    with SignalCatcher(raise_at_once=False).active() as signals, contextlib.ExitStack() as locks:

        def should_stop() -> bool:
            return signals.signum is not None or os.getppid() != parent

        folders = {name: out / "runs" / name for name in names}
        for folder in folders.values():
            folder.mkdir(parents=True, exist_ok=True)
            locks.enter_context(runs.locked(folder))
        pending = []
        for name in names:
            state = _prepare(folders[name], name, configs[name], plan)
            settings = runs.read_config(folders[name])[1]
            pending.append((name, FolderRun(folders[name], configs[name], settings, state)))
        by_step: dict[int, list[tuple[str, FolderRun]]] = {}
        for name, run in pending:  # runs stacked together must resume from the same step
            by_step.setdefault(run.env_steps, []).append((name, run))
        for group in by_step.values():
            group_names = [name for name, _ in group]

            def report(k: int, episode: Any, group_names: list[str] = group_names) -> None:
                messages.put(("episode", group_names[k], episode.episode))

            train_stack([run for _, run in group], record=work.record, should_stop=should_stop, on_episode=report)
            if should_stop():
                break
        for name in names:
            if should_stop():
                break
            done, evaluated = run_status(folders[name], configs[name], plan.keep_checkpoints)
            if done >= configs[name].episodes and not evaluated:
                if _evaluated_at(folders[name]) != done:
                    evaluate_folder(
                        folders[name], episodes=plan.eval_episodes, seed=EVAL_SEED, record=False, figure=work.figure
                    )
                for n in plan.keep_checkpoints:
                    tag = milestone_tag(n)
                    if not runs.eval_paths(folders[name], tag)["json"].exists():
                        checkpoint = runs.milestone_checkpoint(n)
                        evaluate_folder(
                            folders[name],
                            episodes=plan.eval_episodes,
                            seed=EVAL_SEED,
                            record=False,
                            tag=tag,
                            checkpoint=checkpoint,
                            figure=work.figure,
                        )
            messages.put(("done", name, None))


def run_sweep(
    out: Path,
    plan: SweepPlan,
    *,
    workers: int,
    record: bool = True,
    threads: int = 1,
    executor: str = "local",
    address: str | None = None,
    on_message: Callable[[str, str, Any], None] = lambda kind, name, value: None,
    should_stop: Callable[[], bool] = lambda: False,
    figure: Figure | None = None,
) -> bool:
    """Run the sweep in ``out`` (written or checked by :func:`open_sweep`): its unfinished runs,
    in stacks, on ``workers`` local processes (``executor="local"``) or as Ray tasks
    (``"ray"``, on the cluster at ``address`` or a local instance of ``workers`` CPUs).
    Each stack trains on ``threads`` torch threads. ``on_message`` hears the workers'
    messages; when ``should_stop()`` turns true the workers are stopped (local ones checkpoint
    first); ``figure`` draws each evaluation's figure (:func:`~pursuit_bench.training.evaluate.evaluate_into`).
    Returns whether every run is done."""
    configs = plan.runs()
    todo = [
        name
        for name, config in configs.items()
        if not run_status(out / "runs" / name, config, plan.keep_checkpoints)[1]
    ]
    tasks = stacks(plan, todo, workers)
    work = Work(record, threads, figure)
    if executor == "ray":
        _run_on_ray(out, tasks, workers, address, on_message, should_stop, work)
    elif executor == "local":
        _run_locally(out, tasks, workers, on_message, should_stop, work)
    else:
        raise ValueError(f"executor={executor!r}: expected 'local' or 'ray'")
    return all(run_status(out / "runs" / name, config, plan.keep_checkpoints)[1] for name, config in configs.items())


def _run_locally(
    out: Path,
    tasks: list[list[str]],
    workers: int,
    on_message: Callable[[str, str, Any], None],
    should_stop: Callable[[], bool],
    work: Work,
) -> None:
    context = multiprocessing.get_context("spawn")
    messages = context.Queue()
    running: list[Any] = []
    stopping = False
    while tasks or running:
        if should_stop() and not stopping:
            stopping = True
            tasks.clear()
            for process in running:
                process.terminate()  # SIGTERM: the worker checkpoints its stack and ends
        while tasks and len(running) < workers:
            process = context.Process(target=run_stack, args=(out, tasks.pop(0), messages, work), daemon=False)
            process.start()
            running.append(process)
        try:
            on_message(*messages.get(timeout=0.2))
        except queue.Empty:
            pass
        for process in [p for p in running if not p.is_alive()]:
            process.join()
            running.remove(process)
            if process.exitcode not in (0, None) and not stopping:
                raise RuntimeError(f"a sweep worker failed (exit status {process.exitcode}); rerun to resume")
    while True:  # what the last workers said before they ended
        try:
            on_message(*messages.get_nowait())
        except queue.Empty:
            break


class _Messages(list):
    """A worker's messages kept in a list (a Ray task returns them with its result)."""

    def put(self, message: tuple[str, str, Any]) -> None:
        self.append(message)


def stack_task(
    plan_json: str,
    names: list[str],
    files: dict[str, dict[str, bytes]],
    work: Work = Work(),
) -> dict[str, Any]:
    """One stack as a self-contained task, for a machine that does not share our file system:
    the sweep's plan and the runs' current files come in, the runs' files and the messages go
    out. (Ray runs it; it needs nothing of Ray.)"""
    with tempfile.TemporaryDirectory(prefix="pursuit-bench-stack-") as tmp:
        out = Path(tmp)
        (out / PLAN).write_text(plan_json)
        for name, contents in files.items():
            for file_name, data in contents.items():
                (out / "runs" / name).mkdir(parents=True, exist_ok=True)
                (out / "runs" / name / file_name).write_bytes(data)
        messages = _Messages()
        run_stack(out, names, messages, work)
        return {"files": {name: _files(out / "runs" / name) for name in names}, "messages": list(messages)}


def _files(folder: Path) -> dict[str, bytes]:
    """A run folder's own files (no lock, no temporary file)."""
    if not folder.is_dir():
        return {}
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file() and not p.name.startswith(".")}


def _run_on_ray(
    out: Path,
    tasks: list[list[str]],
    workers: int,
    address: str | None,
    on_message: Callable[[str, str, Any], None],
    should_stop: Callable[[], bool],
    work: Work,
) -> None:
    """Every stack a Ray task (``threads`` CPUs: a stack trains on that many torch threads), retried if its node is
    lost; the driver writes what each returns into ``out``, run folder by run folder."""
    try:
        import ray
    except ImportError:
        raise ValueError("--backend ray needs Ray: pip install 'pursuit-bench[ray]'") from None
    if address is None:
        ray.init(num_cpus=workers, include_dashboard=False, object_store_memory=200 * 2**20, log_to_driver=False)
    else:
        ray.init(address=address, log_to_driver=False)
    try:
        remote = ray.remote(num_cpus=work.threads, max_retries=3, retry_exceptions=False)(stack_task)
        plan_json = (out / PLAN).read_text()
        pending = {
            remote.remote(plan_json, names, {n: _files(out / "runs" / n) for n in names}, work): names
            for names in tasks
        }
        while pending:
            if should_stop():
                for ref in pending:
                    ray.cancel(ref, force=True)
                return
            done, _ = ray.wait(list(pending), num_returns=1, timeout=0.5)
            for ref in done:
                pending.pop(ref)
                result = ray.get(ref)
                for name, contents in result["files"].items():
                    folder = out / "runs" / name
                    folder.mkdir(parents=True, exist_ok=True)
                    with runs.locked(folder):
                        for file_name, data in contents.items():
                            atomic_write_bytes(folder / file_name, data)
                for message in result["messages"]:
                    on_message(*message)
    finally:
        ray.shutdown()
