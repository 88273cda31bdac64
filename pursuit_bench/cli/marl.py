"""``pursuit-bench marl train``: one of BenchMARL's algorithms trained on a condition, its teams
written as files ``score`` and ``eval --agent`` play (:mod:`pursuit_bench.marl.train`,
docs/tutorials/benchmarl.md). Needs the ``marl`` extra."""

from __future__ import annotations

import json
from pathlib import Path

import click

from pursuit_bench.cli.options import BadInput
from pursuit_bench.env.conditions import CONDITIONS

#: What the command says when BenchMARL is not installed.
NEEDS_EXTRA = (
    "BenchMARL is not installed: pip install 'pursuit-bench[marl]' (torch 2.13.0 first, docs/getting-started.md)"
)


@click.group(
    name="marl", short_help="The field's MARL algorithms (BenchMARL: IPPO, MAPPO, IQL, QMIX) on pursuit-bench."
)
def marl() -> None:
    """Train BenchMARL's algorithms on pursuit-bench (the marl extra)."""


def _setting(text: str) -> tuple[str, str]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise BadInput(f"--set {text}: expected KEY=VALUE, e.g. on_policy_n_minibatch_iters=2")
    return key, value


@marl.command(name="train")
@click.option(
    "--algorithm", type=click.Choice(["ippo", "mappo", "iql", "qmix"]), required=True, help="BenchMARL's algorithm."
)
@click.option("--condition", type=click.Choice(list(CONDITIONS)), required=True, help="The condition to train in.")
@click.option(
    "--frames", type=click.IntRange(min=1), required=True, help="The budget in env steps (BenchMARL's frames)."
)
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="The experiment's seed.")
@click.option(
    "--set",
    "settings",
    multiple=True,
    metavar="KEY=VALUE",
    help="Change a field of BenchMARL's experiment configuration (repeatable); its defaults otherwise.",
)
@click.option(
    "--out", type=click.Path(path_type=Path, file_okay=False), required=True, help="The run folder (rerun: resume)."
)
def train(algorithm: str, condition: str, frames: int, seed: int, settings: tuple[str, ...], out: Path) -> None:
    """Train ALGORITHM's predators and prey together in CONDITION for FRAMES env steps; write
    OUT/predator.safetensors and OUT/prey.safetensors (team files: weights only) and
    OUT/marl.json. Rerunning the command on OUT resumes from BenchMARL's last checkpoint."""
    try:
        from pursuit_bench.marl import train as marl_train
    except ModuleNotFoundError as error:
        raise BadInput(f"{NEEDS_EXTRA} ({error})") from None
    from pursuit_bench.io.signals import SignalCatcher, Stopped

    try:
        run = marl_train.MarlRun(algorithm, condition, frames, seed, tuple(_setting(s) for s in settings))
        marl_train.check_folder(run, out)
    except ValueError as error:
        raise BadInput(str(error)) from None
    try:
        with SignalCatcher(raise_at_once=True).active():
            summary = marl_train.train(run, out)
    except ValueError as error:
        raise BadInput(str(error)) from None
    except Stopped as stop:
        click.echo(f"stopped ({stop}): rerun the same command to resume from the last checkpoint in {out}", err=True)
        raise SystemExit(stop.exit_code) from None
    click.echo(json.dumps({k: summary[k] for k in ("frames", "teams", "export_disagreements")}))
    click.echo(
        f"score the predators: pursuit-bench score {out / 'predator.safetensors'} --role predator --out …", err=True
    )
