"""``pursuit-bench``: train, evaluate and look at agents from the command line.

The commands parse options into configurations and call the library (``train.Trainer``,
``evaluate.evaluate_agents``, ``recording.Recorder``); they hold no logic of their own beyond
run folders, progress and errors. Bad input is a one-line error and exit status 2; SIGINT and
SIGTERM stop a command cleanly with status 130 and 143. torch and Rerun are imported inside the
commands that use them, so that ``--help`` and errors come at once.
"""

from __future__ import annotations

import ast
import contextlib
import dataclasses
import inspect
import itertools
import json
import os
import shutil
import subprocess
import sys
import textwrap
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from click.core import ParameterSource

from pursuit_bench.agents.config import PRESETS, AgentConfig
from pursuit_bench.cli.progress import Progress
from pursuit_bench.conditions import CONDITIONS
from pursuit_bench.signals import SignalCatcher, Stopped

if TYPE_CHECKING:
    from pursuit_bench.train import EpisodeRecord, TrainConfig

PREDATOR_KINDS = ("hierarchical", "flat", "always_chase", "always_stalk")
#: Options that only say how this process runs: free to differ when a run is resumed.
RUNTIME_OPTIONS = {"out", "resume", "force", "no_record", "threads", "log_every", "episodes"}


class BadInput(click.ClickException):
    """Bad input: one line on stderr, exit status 2 (like click's usage errors)."""

    exit_code = 2


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of a dataclass (they are the CLI's help texts)."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    docs = {}
    for node, after in itertools.pairwise(body):
        if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            if isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant):
                docs[node.target.id] = " ".join(str(after.value.value).split())
    return docs


def hyperparameter_options(command: Any) -> Any:
    """Add ``--learning-rate``, ``--gamma``, … : one option per AgentConfig field (but
    ``episodes``, which ``train --episodes`` sets)."""
    docs = field_docs(AgentConfig)
    for f in reversed(dataclasses.fields(AgentConfig)):
        if f.name == "episodes":
            continue
        kind = {"int": int, "float": float, "bool": bool}[str(f.type)]
        flag = "--" + f.name.replace("_", "-")
        if kind is bool:
            flag = f"{flag}/--no-{f.name.replace('_', '-')}"
        values = ", ".join(f"{name}: {getattr(preset, f.name)}" for name, preset in PRESETS.items())
        help_text = f"{docs.get(f.name, '')} [{values}]"
        command = click.option(flag, f.name, type=kind, default=None, help=help_text)(command)
    return command


def training_options(command: Any) -> Any:
    """The options ``train`` and ``sweep`` share: preset, budget, arenas, physics, recording,
    checkpoints, log lines."""
    options = [
        click.option(
            "--preset", type=click.Choice(list(PRESETS)), default="quick", show_default=True, help="Hyper-parameters."
        ),
        click.option(
            "--episodes",
            type=click.IntRange(min=1),
            default=None,
            help="Episodes to train [preset's: "
            + ", ".join(f"{name} {preset.episodes}" for name, preset in PRESETS.items())
            + "]. With train --resume: the run's saved target unless given, which extends or shortens the run.",
        ),
        click.option(
            "--num-envs", type=click.IntRange(min=1), default=8, show_default=True, help="Arenas stepped together."
        ),
        click.option(
            "--physics",
            "physics",
            type=click.Choice(["pymunk", "numpy"]),
            default="pymunk",
            show_default=True,
            help="Physics backend of the arenas: pymunk (the reference) or the numpy twin.",
        ),
        click.option(
            "--record-every",
            type=click.IntRange(min=1),
            default=100,
            show_default=True,
            help="Record every Nth episode.",
        ),
        click.option("--no-record", is_flag=True, help="Write no Rerun recording of training."),
        click.option(
            "--checkpoint-every",
            type=click.IntRange(min=1),
            default=100,
            show_default=True,
            help="Episodes between checkpoints.",
        ),
        click.option(
            "--log-every",
            type=click.IntRange(min=1),
            default=100,
            show_default=True,
            help="When stderr is not a terminal: a progress line every N episodes (and at least every minute).",
        ),
    ]
    command = hyperparameter_options(command)
    for option in reversed(options):
        command = option(command)
    return command


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="pursuit-bench")
def main() -> None:
    """pursuit-bench: predators hunt a prey; deep RL picks how hard, parallel navigation where."""


@main.command()
def conditions() -> None:
    """The paper's ten conditions and their options."""
    click.echo(f"{'condition':22s} {'predators':>9s} {'chase cost':>10s}  reward sharing")
    for name, c in CONDITIONS.items():
        click.echo(f"{name:22s} {c.n_predators:>9d} {c.chase_cost:>10g}  {c.reward_sharing}")


def _options_given(ctx: click.Context) -> set[str]:
    """The options the user typed (or set through the environment), not left at their defaults."""
    sources = (ParameterSource.COMMANDLINE, ParameterSource.ENVIRONMENT)
    return {name for name in ctx.params if ctx.get_parameter_source(name) in sources}


def _flag(ctx: click.Context, name: str) -> str:
    param = next(p for p in ctx.command.params if p.name == name)
    return param.opts[0]


def _resumed_config(
    ctx: click.Context, out: Path, episodes: int | None
) -> tuple[TrainConfig, dict[str, Any], str | None]:
    """The configuration saved in ``out`` with the options given beside ``--resume`` checked
    against it; ``--episodes`` moves the target. Returns (config, settings, what changed)."""
    from pursuit_bench import runs

    try:
        saved, settings = runs.read_config(out)
    except ValueError as error:
        raise BadInput(f"cannot resume: {error}") from None
    saved_values: dict[str, Any] = {f.name: getattr(saved, f.name) for f in dataclasses.fields(saved)}
    saved_values.update(saved.agent.to_dict())
    saved_values.update(settings)
    saved_values["physics"] = saved.backend  # the option's name for TrainConfig.backend
    for name in sorted(_options_given(ctx) - RUNTIME_OPTIONS):
        given, was = ctx.params[name], saved_values.get(name)
        if given != was:
            raise BadInput(
                f"--resume: {_flag(ctx, name)} {given} disagrees with the run's {was} ({out / runs.CONFIG}); "
                "leave it out to keep the run's, or start over with --force"
            )
    note = None
    if episodes is not None and episodes != saved.episodes:
        verb = "extending" if episodes > saved.episodes else "shortening"
        note = f"{verb} the run from {saved.episodes} to {episodes} episodes"
        saved = dataclasses.replace(saved, episodes=episodes)
    return saved, settings, note


def _prepare_folder(out: Path, config: TrainConfig, settings: dict[str, Any], resume: bool, force: bool) -> dict | None:
    """Make ``out`` hold this run (its lock held); returns the checkpoint to resume from, or None."""
    from pursuit_bench import runs

    if resume:
        state = None
        if (out / runs.CHECKPOINT).exists():
            try:
                state = runs.load_checkpoint(out)
            except ValueError as error:
                raise BadInput(f"cannot resume: {error}") from None
        else:
            click.echo(f"{out}: no checkpoint yet; starting the run from its beginning", err=True)
        runs.write_config(out, config, settings)
        return state
    if not runs.holds_only_unstarted_or_nothing(out):
        if not runs.is_run(out):
            raise BadInput(f"--out {out}: the folder is not empty and holds no pursuit-bench run; choose another")
        if not force:
            try:
                saved, _ = runs.read_config(out)
                same = saved == config
            except ValueError:
                same = False
            what = "this run" if same else "a different run"
            raise BadInput(f"--out {out} already holds {what}: pass --resume to continue it or --force to start over")
    runs.clear(out)
    runs.write_config(out, config, settings)
    return None


def _describe(returns: dict[str, list[float]], captures: list[bool], epsilon: float) -> str:
    """The last 100 episodes: every agent's mean return, the capture rate, ε."""
    if not captures:
        return "no episode finished yet"
    parts = [f"{name} {sum(r[-100:]) / len(r[-100:]):+.2f}" for name, r in returns.items()]
    recent = captures[-100:]
    return f"return {' '.join(parts)} | capture {sum(recent) / len(recent):.0%} | ε {epsilon:.2f}"


@main.command()
@click.option(
    "--condition", type=click.Choice(list(CONDITIONS)), default="1p-high", show_default=True, help="Which task."
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seeds the arenas, the networks and every learner's sampling.",
)
@click.option("--out", type=click.Path(path_type=Path), default=None, help="Run folder [runs/CONDITION-seedS].")
@click.option(
    "--resume",
    is_flag=True,
    help="Continue the run in --out from its last checkpoint, with its saved configuration "
    "(options given beside it must agree).",
)
@click.option("--force", is_flag=True, help="Start over in --out, replacing the run there.")
@click.option(
    "--predator",
    type=click.Choice(PREDATOR_KINDS),
    default="hierarchical",
    show_default=True,
    help="The predators: the paper's hierarchical agent, the flat ablation (24 actions, no rule), "
    "or a fixed baseline that does not learn.",
)
@click.option(
    "--prey",
    type=click.Choice(["learning", "scripted"]),
    default="learning",
    show_default=True,
    help="A learning prey (the paper's) or the scripted FleeingPrey.",
)
@click.option(
    "--batched-learners/--separate-learners",
    default=True,
    show_default=True,
    help="Update the predators' networks in one stacked pass (same result, faster) or one by one.",
)
@click.option(
    "--threads", type=click.IntRange(min=1), default=1, show_default=True, help="torch threads (1: repeatable)."
)
@training_options
@click.pass_context
def train(
    ctx: click.Context,
    condition: str,
    preset: str,
    episodes: int | None,
    seed: int,
    out: Path | None,
    resume: bool,
    force: bool,
    num_envs: int,
    predator: str,
    prey: str,
    batched_learners: bool,
    physics: str,
    record_every: int,
    no_record: bool,
    checkpoint_every: int,
    threads: int,
    log_every: int,
    **hyperparameters: Any,
) -> None:
    """Train every agent of a condition together (independent learners) into a run folder.

    Ctrl-C or SIGTERM saves a checkpoint and stops (exit 130 or 143); `--resume` continues."""
    import torch

    from pursuit_bench import runs
    from pursuit_bench.train import TrainConfig

    torch.set_num_threads(threads)
    if resume and force:
        raise BadInput("--resume and --force contradict each other: pick one")
    out = out or Path("runs") / f"{condition}-seed{seed}"
    if out.exists() and not out.is_dir():
        raise BadInput(f"--out {out}: exists and is not a folder")
    note = None
    if resume:
        config, settings, note = _resumed_config(ctx, out, episodes)
    else:
        overrides = {k: v for k, v in hyperparameters.items() if v is not None}
        try:
            agent = PRESETS[preset].replace(**overrides)
            config = TrainConfig(
                condition=condition,
                agent=agent,
                episodes=episodes or agent.episodes,
                num_envs=num_envs,
                seed=seed,
                predator=predator,  # type: ignore[arg-type]
                prey=prey,  # type: ignore[arg-type]
                batched_learners=batched_learners,
                backend=physics,  # type: ignore[arg-type]
            )
        except ValueError as error:
            raise BadInput(str(error)) from None
        settings = {
            "preset": preset,
            "record_every": record_every,
            "checkpoint_every": checkpoint_every,
            "recording_id": uuid.uuid4().hex,
        }
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        with SignalCatcher(raise_at_once=False).active() as signals, runs.locked(out):
            state = _prepare_folder(out, config, settings, resume, force)
            if note:
                click.echo(f"{out}: {note}", err=True)
            _train_run(out, config, settings, state, signals, record=not no_record, log_every=log_every)
    except runs.RunBusy as error:
        raise BadInput(str(error)) from None
    except BaseException:
        if created and not (out / runs.CHECKPOINT).exists():  # failed before its first checkpoint
            shutil.rmtree(out, ignore_errors=True)
        raise


def _train_run(
    out: Path,
    config: TrainConfig,
    settings: dict[str, Any],
    state: dict | None,
    signals: SignalCatcher,
    *,
    record: bool,
    log_every: int,
) -> None:
    """Train (the folder ready and locked) until done or a signal, showing progress."""
    from pursuit_bench.stack import FolderRun, train_stack

    run = FolderRun(out, config, settings, state)
    if run.episodes_done >= config.episodes:
        click.echo(f"{out}: already trained {run.episodes_done} of {config.episodes} episodes; nothing to do")
        return
    if state is not None:
        click.echo(f"resuming {out} at episode {run.episodes_done} of {config.episodes}", err=True)
    names = list(CONDITIONS[config.condition].agent_names)
    returns: dict[str, list[float]] = {name: [] for name in names}
    captures: list[bool] = []
    last: dict[str, Any] = {"done": run.episodes_done, "epsilon": 0.0}

    def on_episode(_: int, episode: EpisodeRecord) -> None:
        for name in names:
            returns[name].append(episode.returns[name])
        captures.append(episode.captured)
        last.update(done=episode.episode, epsilon=episode.extra.get("epsilon", 0.0))
        progress.update(episode.episode)

    progress = Progress(
        f"training {config.condition}",
        config.episodes,
        run.episodes_done,
        lambda: _describe(returns, captures, last["epsilon"]),
        every_episodes=log_every,
    )
    train_stack([run], record=record, should_stop=lambda: signals.signum is not None, on_episode=on_episode)
    progress.close()
    if signals.signum is not None:
        stopped = Stopped(signals.signum)
        click.echo(
            f"\n{stopped}: stopped at episode {last['done']}; checkpoint saved; "
            f"continue with: pursuit-bench train --out {out} --resume",
            err=True,
        )
        sys.exit(stopped.exit_code)
    click.echo(f"trained {last['done']} episodes of {config.condition} into {out}/")
    click.echo(f"  metrics: {out / 'metrics.jsonl'}   checkpoint: {out / 'checkpoint.pt'}")
    if record:
        click.echo(f"  recordings: pursuit-bench view {out}")


def pretrained_options(command: Any) -> Any:
    """``--pretrained CONDITION`` and ``--out DIR``: the shipped agents instead of a RUN."""
    command = click.option(
        "--out",
        type=click.Path(path_type=Path),
        default=None,
        help="With --pretrained: the folder for the results [runs/pretrained-CONDITION].",
    )(command)
    return click.option(
        "--pretrained",
        type=click.Choice(list(CONDITIONS)),
        default=None,
        help="Use the trained agents shipped with the package for this condition (REPRODUCTION.md) instead of a RUN.",
    )(command)


@main.command(name="eval")
@click.argument("run", type=click.Path(path_type=Path), required=False)
@pretrained_options
@click.option("--episodes", type=click.IntRange(min=1), default=1000, show_default=True, help="Episodes per variant.")
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=12345,
    show_default=True,
    help="Seeds the evaluation arenas (every variant plays the same ones).",
)
@click.option("--num-envs", type=click.IntRange(min=1), default=64, show_default=True, help="Arenas stepped together.")
@click.option("--no-record", is_flag=True, help="Write no Rerun recording of the evaluated episodes.")
@click.option(
    "--threads", type=click.IntRange(min=1), default=1, show_default=True, help="torch threads (1: repeatable)."
)
@click.option(
    "--tag",
    default=None,
    help="Write eval-TAG.json, .png and .rrd instead of eval.*, so that evaluations with other seeds "
    "or episode counts sit side by side.",
)
def evaluate(
    run: Path | None,
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    num_envs: int,
    no_record: bool,
    threads: int,
    tag: str | None,
) -> None:
    """Evaluate a trained RUN (or, with --pretrained, a shipped agent) by the paper's protocol;
    writes eval.json, eval.png and eval.rrd.

    The three files appear together when the evaluation is complete: Ctrl-C or SIGTERM leaves
    the previous ones as they were (exit 130 or 143)."""
    import torch

    from pursuit_bench import runs

    torch.set_num_threads(threads)
    folder = _run_or_pretrained(run, pretrained, out)
    settings: dict[str, Any] = {"episodes": episodes, "seed": seed, "num_envs": num_envs, "record": not no_record}
    try:
        paths = runs.eval_paths(folder, tag)
        with _locked(folder, pretrained):
            _evaluate_run(folder, paths, pretrained, tag, settings)
    except ValueError as error:  # RunBusy too
        raise BadInput(str(error)) from None


def _run_or_pretrained(run: Path | None, pretrained: str | None, out: Path | None) -> Path:
    """The folder a command works in: RUN, or --out (default runs/pretrained-CONDITION) with --pretrained."""
    if (run is None) == (pretrained is None):
        raise click.UsageError("give a RUN folder or --pretrained CONDITION (one of the two)")
    if out is not None and pretrained is None:
        raise click.UsageError("--out goes with --pretrained; a RUN's results go into the RUN")
    if pretrained is not None:
        folder = out if out is not None else Path("runs") / f"pretrained-{pretrained}"
        if (folder / "config.json").exists():
            raise click.UsageError(f"--out {folder} holds a training run, whose results are its own: choose another")
        return folder
    assert run is not None
    return run


@contextlib.contextmanager
def _locked(folder: Path, pretrained: str | None) -> Iterator[None]:
    """Hold ``folder``'s lock: a trained RUN (checked before a lock file is made in it), or the
    results folder of --pretrained (made if missing)."""
    from pursuit_bench import runs

    if pretrained is None:
        runs.read_config(folder)
    else:
        folder.mkdir(parents=True, exist_ok=True)
    with runs.locked(folder):
        yield


def _pretrained_agents(condition: str) -> tuple[TrainConfig, dict[str, Any], dict[str, Any]]:
    """The shipped agents of ``condition``: (training config, agents, what eval.json says of them)."""
    from pursuit_bench import pretrained
    from pursuit_bench.train import TrainConfig

    header = next(iter(pretrained.info(condition).values()))
    shown = {k: v for k, v in header.items() if k not in ("training", "agent", "kind", "format")}
    about = {"pretrained": shown, "trained_episodes": int(header["trained_episodes"])}
    return TrainConfig.from_dict(header["training"]), pretrained.load(condition), about


def _evaluate_run(
    run: Path, paths: dict[str, Path], pretrained: str | None, tag: str | None, settings: dict[str, Any]
) -> None:
    from pursuit_bench.stack import evaluate_folder, evaluate_into

    try:
        with SignalCatcher(raise_at_once=True).active():
            if pretrained is None:
                result = evaluate_folder(run, tag=tag, **settings)
            else:
                config, agents, about = _pretrained_agents(pretrained)
                result = evaluate_into(paths, config, agents, {**about, "tag": tag}, **settings)
    except Stopped as stopped:
        click.echo(f"\n{stopped}: evaluation stopped; {run} keeps its previous results", err=True)
        sys.exit(stopped.exit_code)
    kind = result["predator_kind"]
    for panel in result["panels"]:
        click.echo(
            f"{panel['predator']}: {kind} {panel['trained']:+.3f}  "
            f"always-chase {panel['always_chase']:+.3f}  always-stalk {panel['always_stalk']:+.3f}"
        )
    click.echo(f"capture rate {result['capture_rate']:.1%}; results in {paths['json']} and {paths['png']}")
    if settings["record"]:
        click.echo(f"recording: {paths['rrd']}   (pursuit-bench view {paths['rrd']})")


def _names(value: str, known: list[str] | tuple[str, ...], what: str) -> tuple[str, ...]:
    """``all`` or a comma-separated list of known names."""
    if value == "all":
        return tuple(known)
    names = tuple(v.strip() for v in value.split(",") if v.strip())
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise BadInput(f"--{what} {value!r}: expected 'all' or a comma-separated list of {', '.join(known)}")
    return names


def _episode_counts(value: str) -> tuple[int, ...]:
    """A comma-separated list of episode counts (possibly empty)."""
    try:
        return tuple(sorted({int(v) for v in value.split(",") if v.strip()}))
    except ValueError:
        raise BadInput(
            f"--keep-checkpoints {value!r}: expected comma-separated episode counts, e.g. 1500,5000"
        ) from None


@main.command()
@click.option(
    "--conditions",
    default="all",
    show_default=True,
    help="'all' (the paper's ten) or a comma-separated list, e.g. 1p-high,2p-high-shared.",
)
@click.option(
    "--seeds", type=click.IntRange(min=1), default=5, show_default=True, help="Seeds 0 … N-1 of every condition."
)
@click.option(
    "--predators",
    default="hierarchical",
    show_default=True,
    help="Comma-separated predator kinds to train: hierarchical, flat (the ablation), always_chase, always_stalk.",
)
@click.option(
    "--eval-episodes",
    type=click.IntRange(min=1),
    default=1000,
    show_default=True,
    help="Episodes per variant of each run's evaluation (paper: 1000).",
)
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    default=None,
    help="Worker processes, each training one stack of runs at a time [the cores].",
)
@click.option(
    "--backend",
    type=click.Choice(["local", "ray"]),
    default="local",
    show_default=True,
    help="Where stacks run: worker processes here, or Ray tasks (pip install 'pursuit-bench[ray]').",
)
@click.option(
    "--address",
    default=None,
    help="With --backend ray: the cluster to join ('auto' or HOST:PORT) [a local Ray instance started for the sweep].",
)
@click.option(
    "--keep-checkpoints",
    default="",
    help="Comma-separated episode counts at which every run keeps its checkpoint, evaluated like the final one "
    "(eval-epN.json): learning against budget, e.g. 1500,5000.",
)
@click.option("--out", type=click.Path(path_type=Path), required=True, help="Sweep folder, e.g. sweeps/NAME.")
@training_options
def sweep(
    conditions: str,
    seeds: int,
    predators: str,
    preset: str,
    episodes: int | None,
    eval_episodes: int,
    workers: int | None,
    num_envs: int,
    physics: str,
    backend: str,
    address: str | None,
    record_every: int,
    no_record: bool,
    checkpoint_every: int,
    log_every: int,
    keep_checkpoints: str,
    out: Path,
    **hyperparameters: Any,
) -> None:
    """Train and evaluate conditions × seeds × predator kinds, each run a normal run folder in
    OUT/runs/, stacked and spread over worker processes.

    Rerunning the same command skips finished runs and resumes the others from their
    checkpoints; Ctrl-C or SIGTERM checkpoints every stack (exit 130 or 143)."""
    import time

    from pursuit_bench import sweep as sweeps

    overrides = {k: v for k, v in hyperparameters.items() if v is not None}
    try:
        agent = PRESETS[preset].replace(**overrides)
        plan = sweeps.SweepPlan(
            conditions=_names(conditions, list(CONDITIONS), "conditions"),
            seeds=seeds,
            predators=_names(predators, PREDATOR_KINDS, "predators"),
            agent=agent,
            episodes=episodes or agent.episodes,
            eval_episodes=eval_episodes,
            num_envs=num_envs,
            backend=physics,
            record_every=record_every,
            checkpoint_every=checkpoint_every,
            preset=preset,
            keep_checkpoints=_episode_counts(keep_checkpoints),
        )
        sweeps.open_sweep(out, plan)
    except ValueError as error:
        raise BadInput(str(error)) from None
    configs = plan.runs()
    status = {name: sweeps.run_status(out / "runs" / name, c, plan.keep_checkpoints) for name, c in configs.items()}
    done = {name: episodes for name, (episodes, _) in status.items()}
    finished = {name for name, (_, evaluated) in status.items() if evaluated}
    total = sum(c.episodes for c in configs.values())
    per_episode = {name: sweeps.expected_cost(c) / c.episodes for name, c in configs.items()}

    def work_done() -> float:  # the ETA counts expected transitions × learners, not episodes
        return sum(per_episode[name] * n for name, n in done.items())

    work_total = sum(sweeps.expected_cost(c) for c in configs.values())
    start, start_work = time.monotonic(), work_done()

    def describe() -> str:
        rate = (work_done() - start_work) / max(time.monotonic() - start, 1e-9)
        eta = (work_total - work_done()) / rate if rate > 0 else float("nan")
        left = "?" if eta != eta else time.strftime("%H:%M:%S", time.gmtime(eta))
        return f"runs done {len(finished)}/{len(configs)} | ETA {left}"

    progress = Progress(f"sweep {out}", total, sum(done.values()), describe, every_episodes=log_every)

    def on_message(kind: str, name: str, value: Any) -> None:
        if kind == "episode":
            done[name] = max(done[name], int(value))
        elif kind == "done":
            finished.add(name)
        progress.update(sum(done.values()))

    workers = workers or os.cpu_count() or 1
    with SignalCatcher(raise_at_once=False).active() as signals:
        try:
            complete = sweeps.run_sweep(
                out,
                plan,
                workers=workers,
                record=not no_record,
                executor=backend,
                address=address,
                on_message=on_message,
                should_stop=lambda: signals.signum is not None,
            )
        except ValueError as error:  # e.g. --backend ray without Ray
            raise BadInput(str(error)) from None
        except RuntimeError as error:  # a worker failed: what it had done is kept
            raise click.ClickException(str(error)) from None
    progress.close()
    if signals.signum is not None:
        stopped = Stopped(signals.signum)
        click.echo(f"\n{stopped}: sweep stopped, every stack checkpointed; rerun the same command to go on", err=True)
        sys.exit(stopped.exit_code)
    click.echo(f"sweep {out}: {len(finished)} of {len(configs)} runs trained and evaluated")
    if not complete:
        raise click.ClickException("some runs are not finished; rerun the same command to go on")


@main.command()
@click.argument("sweep_folder", metavar="SWEEP", type=click.Path(path_type=Path))
def report(sweep_folder: Path) -> None:
    """Fig. 2 over seeds from a sweep's run folders: writes fig2.png, curves.png, report.md and
    report.json into SWEEP."""
    from pursuit_bench import report as reports
    from pursuit_bench.files import atomic_write_bytes, atomic_write_text
    from pursuit_bench.plots import curves_png, fig2_png

    try:
        results = reports.collect(sweep_folder)
    except ValueError as error:
        raise BadInput(str(error)) from None
    table = reports.panel_table(results)
    totals = reports.summary(table)
    curves = reports.curves(results)
    payload = {"sweep": str(sweep_folder), "summary": totals, "panels": table, "curves": curves}
    atomic_write_text(sweep_folder / "report.json", json.dumps(payload, indent=2) + "\n")
    atomic_write_text(sweep_folder / "report.md", reports.markdown(table, totals, sweep_folder))
    atomic_write_bytes(sweep_folder / "fig2.png", fig2_png(table))
    if curves:
        atomic_write_bytes(sweep_folder / "curves.png", curves_png(curves))
    click.echo(
        f"{totals['panels']} panels: hierarchical best in {totals['hierarchical_best']}, interval above both "
        f"baselines in {totals['hierarchical_interval_above_both']}"
    )
    click.echo(f"written: {', '.join(str(sweep_folder / n) for n in ('report.md', 'report.json', 'fig2.png'))}")
    if curves:
        click.echo(f"         {sweep_folder / 'curves.png'}")


@main.command()
@click.argument("folder", metavar="RUN", type=click.Path(path_type=Path), required=False)
@pretrained_options
@click.option("--episodes", type=click.IntRange(min=1), default=200, show_default=True, help="Episodes to play.")
@click.option(
    "--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seeds the episodes and the t-SNE."
)
def analyze(folder: Path | None, pretrained: str | None, out: Path | None, episodes: int, seed: int) -> None:
    """What the trained predators' value streams represent and when they chase (Fig. 3).

    On a run folder (or a shipped agent, --pretrained): fig3.png, modes.png, analysis.json and
    analysis.rrd. On a sweep folder: P(chase | distance) and the chase-onset distance for low
    against high chase cost, per number of predators, over seeds: modes.png and analysis.json
    in the sweep folder."""
    import torch

    from pursuit_bench import runs

    torch.set_num_threads(1)
    where = _run_or_pretrained(folder, pretrained, out)
    if pretrained is None and (where / "sweep.json").is_file():
        _analyze_sweep(where, episodes, seed)
        return
    try:
        with _locked(where, pretrained):
            if pretrained is None:
                config, agents = runs.read_config(where)[0], runs.load_agents(where)
            else:
                config, agents, _ = _pretrained_agents(pretrained)
            _analyze_run(where, config, agents, episodes, seed)
    except ValueError as error:  # RunBusy, not a run folder, not trained
        raise BadInput(str(error)) from None


def _analyze_run(folder: Path, config: TrainConfig, agents: dict[str, Any], episodes: int, seed: int) -> None:
    import numpy as np

    from pursuit_bench import analysis
    from pursuit_bench.files import atomic_write_bytes, atomic_write_text
    from pursuit_bench.plots import fig3_png, modes_png
    from pursuit_bench.recording import record_embedding

    states = analysis.collect(config.condition, agents, episodes=episodes, seed=seed)
    if not states:
        raise ValueError(f"{folder}: its predators are {config.predator}, not hierarchical: nothing to analyse")
    result, embeddings = analysis.analyse(states, seed)
    shown = {}
    for name, picked in embeddings.items():
        index = picked[:, 0].astype(int)
        shown[name] = {
            "xy": picked[:, 1:],
            "value": states[name].value[index],
            "distance": states[name].distance[index],
        }
        result[name]["embedding"] = {"state": index.tolist(), "xy": np.round(picked[:, 1:], 3).tolist()}
    payload = {"condition": config.condition, "episodes": episodes, "seed": seed, "predators": result}
    closest = {name: states[name].closest[embeddings[name][:, 0].astype(int)] for name in embeddings}
    atomic_write_bytes(folder / "fig3.png", fig3_png(result, shown, closest))
    curves = {name: result[name]["chase_by_distance"] for name in result}
    atomic_write_bytes(folder / "modes.png", modes_png(curves, f"{config.condition}: P(chase) by distance to the prey"))
    first = next(iter(embeddings))
    index = embeddings[first][:, 0].astype(int)
    partial = folder / ".analysis.rrd.tmp"
    record_embedding(
        partial,
        list(agents),
        first,
        embeddings[first][:, 1:],
        states[first].value[index],
        states[first].positions[index],
        {"condition": config.condition, "episodes": episodes, "seed": seed},
    )
    os.replace(partial, folder / "analysis.rrd")
    atomic_write_text(folder / "analysis.json", json.dumps(payload) + "\n")
    for name, r in result.items():
        onset = r["chase_onset_distance"]
        median = f"{onset['median']:.2f}" if onset["median"] is not None else "–"
        click.echo(
            f"{name}: organisation by distance R² {r['organisation']['distance']:.2f}, by V(s) "
            f"{r['organisation']['value']:.2f}; P(chase) {r['p_chase']:.2f}; chase bouts start at {median} (median)"
        )
    click.echo(f"written: fig3.png, modes.png, analysis.json, analysis.rrd in {folder}")


def _analyze_sweep(sweep_folder: Path, episodes: int, seed: int) -> None:
    import numpy as np

    from pursuit_bench import analysis, runs
    from pursuit_bench.files import atomic_write_bytes, atomic_write_text
    from pursuit_bench.plots import modes_png
    from pursuit_bench.report import interval

    groups: dict[tuple[int, str], list[tuple[np.ndarray, list[float], Any]]] = {}
    for folder in sorted((sweep_folder / "runs").glob("*-hierarchical-seed*")):
        try:
            config, _ = runs.read_config(folder)
            agents = runs.load_agents(folder)
        except ValueError:
            continue  # not trained yet
        states = analysis.collect(config.condition, agents, episodes=episodes, seed=seed)  # type: ignore[arg-type]
        condition = CONDITIONS[config.condition]
        cost = "low" if condition.chase_cost < 0.05 else "high"
        distance = np.concatenate([s.distance for s in states.values()])
        mode = np.concatenate([s.mode for s in states.values()])
        binned = analysis.chase_by_distance(distance, mode)
        onsets = [float(np.median(s.onsets)) for s in states.values() if len(s.onsets)]
        groups.setdefault((condition.n_predators, cost), []).append(
            (np.array([np.nan if v is None else v for v in binned["p_chase"]]), onsets, binned["states"])
        )
    if not groups:
        raise BadInput(f"{sweep_folder}: no trained hierarchical run to analyse")
    result, curves = {}, {}
    for (n, cost), rows in sorted(groups.items()):
        table = np.stack([r[0] for r in rows])  # (seeds, bins)
        mean = [None if np.isnan(c).all() else float(np.nanmean(c)) for c in table.T]
        cis = [interval(c[~np.isnan(c)]) if (~np.isnan(c)).sum() > 1 else None for c in table.T]
        onset = np.array([o for r in rows for o in r[1]])
        label = f"{n} predator{'s' if n > 1 else ''}, {cost} cost"
        result[label] = {
            "runs": len(rows),
            "p_chase": mean,
            "p_chase_ci": cis,
            "chase_onset_median": float(np.median(onset)) if len(onset) else None,
            "chase_onset_ci": interval(onset) if len(onset) > 1 else None,
        }
        curves[label] = {
            "bins": analysis.DISTANCE_BINS.tolist(),
            "p_chase": mean,
            "states": np.sum([r[2] for r in rows], axis=0).tolist(),
            "ci": [[None if c is None else c[0] for c in cis], [None if c is None else c[1] for c in cis]],
        }
    atomic_write_text(sweep_folder / "analysis.json", json.dumps(result, indent=2) + "\n")
    title = "P(chase) by distance, low vs high chase cost (mean over seeds, 95 % CI)"
    atomic_write_bytes(sweep_folder / "modes.png", modes_png(curves, title))
    for label, r in result.items():
        median = f"{r['chase_onset_median']:.2f}" if r["chase_onset_median"] is not None else "–"
        click.echo(f"{label}: {r['runs']} runs, chase bouts start at {median} (median)")
    click.echo(f"written: modes.png, analysis.json in {sweep_folder}")


#: The first bytes of every Rerun recording.
RRD_MAGIC = b"RRF2"


@main.command()
@click.argument("path", type=click.Path(path_type=Path))
def view(path: Path) -> None:
    """Open a recording (.rrd), or every recording of a run folder, in the Rerun viewer."""
    if path.is_dir():
        from pursuit_bench import runs

        files = runs.recordings(path)
        if not files:
            raise BadInput(f"{path}: the folder holds no recording (.rrd)")
    elif not path.is_file():
        raise BadInput(f"{path}: no such recording")
    else:
        with path.open("rb") as f:
            head = f.read(len(RRD_MAGIC))
        if head != RRD_MAGIC:
            raise BadInput(f"{path}: not a Rerun recording (.rrd)")
        files = [path]
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        shown = " ".join(str(f) for f in files)
        raise click.ClickException(
            f"no display here to open the viewer on. Copy {shown} to a machine with one and run "
            f"`rerun {shown}`, or serve the web viewer from here: `rerun --web-viewer {shown}` "
            "and open the address it prints in a browser"
        )
    rerun = shutil.which("rerun")
    args = [rerun] if rerun else [sys.executable, "-m", "rerun"]
    raise SystemExit(subprocess.call([*args, *map(str, files)]))


if __name__ == "__main__":
    main()
