"""``pursuit-bench eval``: a trained RUN, or the shipped agents of a condition, evaluated by the
paper's protocol (:func:`~pursuit_bench.stack.evaluate_folder`, :func:`~pursuit_bench.stack.evaluate_into`).
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from typing import Any

import click

from pursuit_bench import runs
from pursuit_bench.cli.options import (
    BadInput,
    obstacles_option,
    pretrained_options,
    run_or_pretrained,
    threads_option,
    trained_agents,
)
from pursuit_bench.signals import STOP_SIGNALS, SignalCatcher, Stopped


@click.command(name="eval", short_help="Evaluate a run or the shipped agents by the paper's protocol.")
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
@obstacles_option
@threads_option
@click.option(
    "--tag",
    default=None,
    help="Write eval-TAG.json, .png and .rrd instead of eval.*, so that evaluations with other seeds "
    "or episode counts sit side by side [with --agent: the replaced agents' names].",
)
@click.option(
    "--agent",
    "agents",
    multiple=True,
    metavar="NAME=MODULE:FACTORY",
    help="Replace agent NAME (predator_0, …, prey_0) by the object MODULE:FACTORY() returns, with act(observation) "
    "(pursuit_bench/external.py), and evaluate it like a trained one. Repeatable.",
)
def evaluate(
    run: Path | None,
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    num_envs: int,
    no_record: bool,
    obstacles: int | None,
    threads: int,
    tag: str | None,
    agents: tuple[str, ...],
) -> None:
    """Evaluate a trained RUN (or, with --pretrained, a shipped agent) by the paper's protocol;
    writes eval.json, eval.png and eval.rrd.

    The three files appear together when the evaluation is complete: Ctrl-C or SIGTERM leaves
    the previous ones as they were (exit 130 or 143)."""
    folder = run_or_pretrained(run, pretrained, out)
    specs = _agent_specs(agents)
    if specs and tag is None:
        tag = "-".join(specs)  # eval-predator_0.json: the run's own eval.json stays its own
    settings: dict[str, Any] = {"episodes": episodes, "seed": seed, "num_envs": num_envs, "record": not no_record}
    try:
        paths = runs.eval_paths(folder, tag)
        with trained_agents(folder, pretrained, threads, obstacles) as (config, trained, about):
            _evaluate_run(folder, paths, config, trained, about, tag, settings, specs)
    except ValueError as error:  # RunBusy, a bad --agent, …
        raise BadInput(str(error)) from None


def _agent_specs(values: tuple[str, ...]) -> dict[str, str]:
    specs = {}
    for value in values:
        name, _, spec = value.partition("=")
        if not name or not spec:
            raise BadInput(f"--agent {value!r}: expected NAME=MODULE:FACTORY, e.g. predator_0=my_agents:make")
        specs[name] = spec
    return specs


def _evaluate_run(
    run: Path,
    paths: dict[str, Path],
    config: Any,
    agents: dict[str, Any],
    about: dict[str, Any],
    tag: str | None,
    settings: dict[str, Any],
    specs: dict[str, str],
) -> None:
    """Evaluate and report. A signal is acted on at the next safe point (a step, or just before
    the files are put in place), whatever library call it lands in: before that point the
    previous files stay and the exit status is 130 or 143; after it the new files are complete
    and the status is 0."""
    from pursuit_bench import external
    from pursuit_bench.stack import evaluate_into

    kind = None
    if specs:
        agents = external.replaced(agents, specs)
        about["external_agents"] = specs
        first = next(iter(agents.values()))
        kind = first.kind if isinstance(first, external.ExternalAgent) else None
    try:
        with SignalCatcher(raise_at_once=False).active() as signals:
            result = evaluate_into(
                paths, config, agents, {**about, "tag": tag}, check=signals.check, predator_kind=kind, **settings
            )
            for stop_signal in STOP_SIGNALS:  # the files are complete: a later signal changes nothing
                signal.signal(stop_signal, signal.SIG_IGN)
    except Stopped as stopped:
        click.echo(f"\n{stopped}: evaluation stopped; {run} keeps its previous results", err=True)
        sys.exit(stopped.exit_code)
    if signals.signum is not None:
        click.echo(f"{Stopped(signals.signum)} arrived after the results were complete: they are written", err=True)
    kind = result["predator_kind"]
    for panel in result["panels"]:
        click.echo(
            f"{panel['predator']}: {kind} {panel['trained']:+.3f}  "
            f"always-chase {panel['always_chase']:+.3f}  always-stalk {panel['always_stalk']:+.3f}"
        )
    click.echo(f"capture rate {result['capture_rate']:.1%}; results in {paths['json']} and {paths['png']}")
    if settings["record"]:
        click.echo(f"recording: {paths['rrd']}   (pursuit-bench view {paths['rrd']})")
