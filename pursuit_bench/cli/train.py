"""``pursuit-bench train``: options into a :class:`~pursuit_bench.training.train.TrainConfig`, the run
folder made ready (new, resumed or replaced), then :func:`~pursuit_bench.training.stack.train_stack` with
progress on the terminal or in the log.
"""

from __future__ import annotations

import dataclasses
import shutil
import sys
import uuid
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from click.core import ParameterSource

from pursuit_bench.agents.config import PRESET_ARENAS, PRESETS
from pursuit_bench.cli.options import (
    PREDATOR_KINDS,
    BadInput,
    OutFolder,
    check_out_folder,
    in_option_words,
    recording_every,
    threads_option,
    training_options,
)
from pursuit_bench.cli.progress import Progress
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.io.signals import SignalCatcher, Stopped

if TYPE_CHECKING:
    from pursuit_bench.training.train import EpisodeRecord
    from pursuit_bench.training.train_config import TrainConfig

#: Options that only say how this process runs: free to differ when a run is resumed.
RUNTIME_OPTIONS = {"out", "resume", "force", "no_record", "threads", "log_every", "episodes", "tensorboard"}


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
    from pursuit_bench.training import runs

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
    """:func:`~pursuit_bench.training.runs.prepare`, its refusals as the command's one-line errors."""
    from pursuit_bench.training import runs

    try:
        state, note = runs.prepare(out, config, settings, resume, force)
    except runs.FolderRefused as refused:
        raise BadInput(str(refused)) from None
    if note:
        click.echo(note, err=True)
    return state


def _describe(returns: dict[str, list[float]], captures: list[bool], epsilon: float) -> str:
    """The last 100 episodes: every agent's mean return, the capture rate, ε."""
    if not captures:
        return "no episode finished yet"
    parts = [f"{name} {sum(r[-100:]) / len(r[-100:]):+.2f}" for name, r in returns.items()]
    recent = captures[-100:]
    return f"return {' '.join(parts)} | capture {sum(recent) / len(recent):.0%} | ε {epsilon:.2f}"


@click.command(short_help="Train every agent of a condition into a run folder.")
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
@click.option("--out", type=OutFolder(), default=None, help="Run folder [runs/CONDITION-seedS].")
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
    help="The predators: the paper's hierarchical agent, the flat ablation (24 actions, no rule), the "
    "residual predator (mode and a ±60° correction of the rule's direction, 10 actions), or a fixed baseline "
    "that does not learn.",
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
    "--tensorboard",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Also write each episode's scalars (returns, losses, ε, β, chase fractions, length, captured) "
    "as TensorBoard event files in DIR/<run folder's name>: tensorboard --logdir DIR. Needs the "
    "tensorboard extra.",
    metavar="DIR",
)
@threads_option
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
    num_envs: int | None,
    predator: str,
    prey: str,
    batched_learners: bool,
    physics: str,
    obstacles: int,
    obstacle_radius: float,
    avoidance: bool,
    record_every: int | None,
    no_record: bool,
    checkpoint_every: int,
    threads: int,
    log_every: int,
    tensorboard: Path | None,
    **hyperparameters: Any,
) -> None:
    """Train every agent of a condition together (independent learners) into a run folder.

    Ctrl-C or SIGTERM saves a checkpoint and stops (exit 130 or 143); `--resume` continues."""
    from pursuit_bench.training import runs  # no torch yet: refusals come at once
    from pursuit_bench.training.train_config import TrainConfig

    every = recording_every(no_record, record_every)
    if tensorboard is not None:  # a missing extra is said before any work (cli/entry.py's message)
        import tensorboard as _  # noqa: F401
    if resume and force:
        raise BadInput("--resume and --force contradict each other: pick one")
    out = out or Path("runs") / (
        f"{condition}-obstacles{obstacles}-seed{seed}" if obstacles else f"{condition}-seed{seed}"
    )
    check_out_folder(out)
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
                num_envs=num_envs or PRESET_ARENAS[preset],
                seed=seed,
                predator=predator,  # type: ignore[arg-type]
                prey=prey,  # type: ignore[arg-type]
                batched_learners=batched_learners,
                backend=physics,  # type: ignore[arg-type]
                obstacles=obstacles,
                obstacle_radius=obstacle_radius,
                avoidance=avoidance,
            )
        except ValueError as error:
            raise BadInput(in_option_words(error)) from None
        settings = {
            "preset": preset,
            "record_every": every,
            "checkpoint_every": checkpoint_every,
            "recording_id": uuid.uuid4().hex,
        }
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:
        with SignalCatcher(raise_at_once=False).active() as signals, runs.locked(out):
            state = _prepare_folder(out, config, settings, resume, force)  # refusals before torch loads
            import torch

            torch.set_num_threads(threads)
            if note:
                click.echo(f"{out}: {note}", err=True)
            _train_run(
                out,
                config,
                settings,
                state,
                signals,
                record=not no_record,
                log_every=log_every,
                tensorboard=None if tensorboard is None else tensorboard / out.resolve().name,
            )
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
    tensorboard: Path | None = None,
) -> None:
    """Train (the folder ready and locked) until done or a signal, showing progress (and writing
    TensorBoard's event files in ``tensorboard`` when given)."""
    from pursuit_bench.training.stack import FolderRun, train_stack
    from pursuit_bench.training.tensorboard_log import TensorBoardLog

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
    board = None if tensorboard is None else TensorBoardLog(tensorboard, run.episodes_done)

    def on_episode(_: int, episode: EpisodeRecord) -> None:
        if board is not None:
            board.write(episode)
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
        eta=True,
    )
    try:
        train_stack([run], record=record, should_stop=lambda: signals.signum is not None, on_episode=on_episode)
    finally:
        if board is not None:
            board.close()
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
    if tensorboard is not None:
        click.echo(f"  TensorBoard: tensorboard --logdir {tensorboard.parent}")
