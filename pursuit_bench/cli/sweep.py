"""``pursuit-bench sweep``: options into a :class:`~pursuit_bench.training.sweep.SweepPlan`, then
:func:`~pursuit_bench.training.sweep.run_sweep` with progress (an ETA by expected transitions).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any

import click

from pursuit_bench.agents.config import PRESET_ARENAS, PRESETS
from pursuit_bench.cli.options import (
    PREDATOR_KINDS,
    BadInput,
    OutFolder,
    check_out_folder,
    episode_counts,
    in_option_words,
    names,
    recording_every,
    threads_option,
    training_options,
)
from pursuit_bench.cli.progress import Progress
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.io.signals import SignalCatcher, Stopped


@click.command(short_help="Train and evaluate conditions × seeds × predator kinds.")
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
    help="'all' or comma-separated predator kinds to train: hierarchical, flat (the ablation), residual (the "
    "rule corrected), always_chase, always_stalk.",
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
@click.option("--out", type=OutFolder(), required=True, help="Sweep folder, e.g. sweeps/NAME.")
@threads_option
@training_options
def sweep(
    conditions: str,
    seeds: int,
    predators: str,
    preset: str,
    episodes: int | None,
    eval_episodes: int,
    workers: int | None,
    num_envs: int | None,
    physics: str,
    obstacles: int,
    obstacle_radius: float,
    avoidance: bool,
    backend: str,
    address: str | None,
    record_every: int | None,
    no_record: bool,
    checkpoint_every: int,
    log_every: int,
    keep_checkpoints: str,
    out: Path,
    threads: int,
    **hyperparameters: Any,
) -> None:
    """Train and evaluate conditions × seeds × predator kinds, each run a normal run folder in
    OUT/runs/, stacked and spread over worker processes.

    Rerunning the same command skips finished runs and resumes the others from their
    checkpoints; Ctrl-C or SIGTERM checkpoints every stack (exit 130 or 143)."""
    chosen = names(conditions, list(CONDITIONS), "conditions")  # refused before the heavy imports
    kinds = names(predators, PREDATOR_KINDS, "predators")
    kept = episode_counts(keep_checkpoints)
    check_out_folder(out)

    from pursuit_bench.figures.plots import reward_bars_png
    from pursuit_bench.training import sweep as sweeps

    # signals are caught from before the plan is written: one that lands before the workers start
    # stops the sweep there (a process started with SIGTERM ignored would otherwise miss it)
    with SignalCatcher(raise_at_once=False).active() as signals:
        overrides = {k: v for k, v in hyperparameters.items() if v is not None}
        try:
            agent = PRESETS[preset].replace(**overrides)
            plan = sweeps.SweepPlan(
                conditions=chosen,
                seeds=seeds,
                predators=kinds,
                agent=agent,
                episodes=episodes or agent.episodes,
                eval_episodes=eval_episodes,
                num_envs=num_envs or PRESET_ARENAS[preset],
                backend=physics,
                record_every=recording_every(no_record, record_every),
                checkpoint_every=checkpoint_every,
                preset=preset,
                keep_checkpoints=kept,
                obstacles=obstacles,
                obstacle_radius=obstacle_radius,
                avoidance=avoidance,
            )
            _check_backend(backend)  # before the plan is written: a refused sweep leaves no folder
            note = sweeps.open_sweep(out, plan)
        except ValueError as error:
            raise BadInput(in_option_words(error)) from None
        if note:
            click.echo(f"{out}: {note}", err=True)
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
            left = eta_text(work_done(), start_work, work_total, time.monotonic() - start)
            return f"runs done {len(finished)}/{len(configs)} | ETA {left}"

        progress = Progress(f"sweep {out}", total, sum(done.values()), describe, every_episodes=log_every)

        def on_message(kind: str, name: str, value: Any) -> None:
            if kind == "episode":
                done[name] = max(done[name], int(value))
            elif kind == "done":
                finished.add(name)
            progress.update(sum(done.values()))

        workers = workers or os.cpu_count() or 1
        try:
            complete = sweeps.run_sweep(
                out,
                plan,
                workers=workers,
                threads=threads,
                record=not no_record,
                executor=backend,
                address=address,
                on_message=on_message,
                should_stop=lambda: signals.signum is not None,
                figure=reward_bars_png,
            )
        except ValueError as error:  # e.g. --backend ray without Ray
            raise BadInput(str(error)) from None
        except RuntimeError as error:  # a worker failed: what it had done is kept
            raise click.ClickException(str(error)) from None
    progress.close()
    if signals.signum is not None:
        stopped = Stopped(signals.signum)
        saved = {name: sweeps.run_status(out / "runs" / name, c, plan.keep_checkpoints) for name, c in configs.items()}
        started = {name: n for name, (n, _) in saved.items() if n > 0}
        others = len(configs) - len(started)
        fresh = f"the other {others} start from the beginning; " if others > 1 else ""
        fresh = "the other one starts from the beginning; " if others == 1 else fresh
        click.echo(
            f"\n{stopped}: sweep stopped. On disk: {len(started)} of {len(configs)} runs with a checkpoint "
            f"({sum(started.values())} episodes in all), {sum(done for _, done in saved.values())} finished; "
            f"{fresh}rerun the same command to go on.",
            err=True,
        )
        sys.exit(stopped.exit_code)
    click.echo(f"sweep {out}: {len(finished)} of {len(configs)} runs trained and evaluated")
    if not complete:
        raise click.ClickException("some runs are not finished; rerun the same command to go on")


def eta_text(done: float, start: float, total: float, elapsed: float) -> str:
    """The time a sweep has left at the rate since this command started (``done`` and ``start``:
    the expected work done now and when it started; ``total`` all of it), ``HH:MM:SS``; marked
    ``≥ … (early)`` until a tenth of the work left at the start is done, for the first episodes of a
    run cost less than later ones (its replay fills before it learns), so an early rate runs fast;
    ``?`` before any work is done."""
    rate = (done - start) / max(elapsed, 1e-9)
    if rate <= 0:
        return "?"
    left = time.strftime("%H:%M:%S", time.gmtime((total - done) / rate))
    return f"≥ {left} (early)" if done - start < 0.1 * (total - start) else left


def _check_backend(backend: str) -> None:
    """A ValueError saying what to install if the sweep cannot run on ``backend`` here (Ray not
    installed). Here, not in training/sweep.py: the residual study requires training's files to be
    the rule study's build's (studies/residual-value/design.py)."""
    if backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise ValueError("--backend ray needs Ray: pip install 'pursuit-bench[ray]'") from None
