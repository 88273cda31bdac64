"""``pursuit-bench eval``: a trained RUN, or the shipped agents of a condition, evaluated by the
paper's protocol (:func:`~pursuit_bench.training.evaluate.evaluate_folder`,
:func:`~pursuit_bench.training.evaluate.evaluate_into`).
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from typing import Any

import click

from pursuit_bench.cli.options import (
    BadInput,
    check_run_folder,
    obstacles_option,
    pretrained_options,
    run_or_pretrained,
    threads_option,
    trained_agents,
)
from pursuit_bench.io.signals import STOP_SIGNALS, SignalCatcher, Stopped
from pursuit_bench.training import runs


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
@click.option(
    "--csv",
    "csv",
    is_flag=True,
    help="Also write eval.csv: the trained variant's trajectories, a row per agent and step (position, "
    "velocity, mode, reward, wall, captured; units in the column names: docs/use.md).",
)
@click.option(
    "--tracks",
    "tracks",
    is_flag=True,
    help="Also write eval-tracks/: the trained variant's episodes as movement datasets (netCDF, one file "
    "per episode; the animal-tracking toolbox's format: docs/pursuit-law.md). Needs the animals extra.",
)
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
    "(pursuit_bench/agents/external.py), or by a Stable-Baselines3 model trained on the single-agent view "
    "(NAME=MODEL.zip, any algorithm), and evaluate it like a trained one. Repeatable.",
)
@click.option(
    "--perturb",
    "perturb",
    multiple=True,
    metavar="NAME=VALUE",
    help="Evaluate in a perturbed world or with perturbed senses, every variant alike: obs-noise=σ, delay=k, "
    "act-noise=p, damping=f, predator-accel=f, prey-accel=f, obstacles=N (docs/robustness.md). Repeatable; "
    "writes eval-perturb-<…>.* unless --tag.",
)
@click.option(
    "--opponents",
    metavar="OTHER",
    default=None,
    help="Held-out opponents: RUN's predators against OTHER's prey (a run folder with as many predators, "
    "'pretrained:CONDITION' for a shipped agent's, or 'scripted' for FleeingPrey), and RUN's prey against OTHER's "
    "predators; writes eval-vs-<OTHER>.* unless --tag.",
)
def evaluate(
    run: Path | None,
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    num_envs: int,
    no_record: bool,
    csv: bool,
    tracks: bool,
    obstacles: int | None,
    threads: int,
    tag: str | None,
    agents: tuple[str, ...],
    perturb: tuple[str, ...],
    opponents: str | None,
) -> None:
    """Evaluate a trained RUN (or, with --pretrained, a shipped agent) by the paper's protocol;
    writes eval.json, eval.png and eval.rrd.

    The three files appear together when the evaluation is complete: Ctrl-C or SIGTERM leaves
    the previous ones as they were (exit 130 or 143)."""
    if tracks:  # a missing extra is said before any work (cli/entry.py's message)
        import movement  # noqa: F401
    folder = run_or_pretrained(run, pretrained, out)
    if pretrained is None:
        check_run_folder(folder)  # before numba and torch load: a refusal comes at once
    specs = _agent_specs(agents)
    from pursuit_bench.env.perturbations import Perturbations

    try:
        perturbations = Perturbations.parse(perturb)
    except ValueError as error:
        raise BadInput(str(error)) from None
    if opponents is not None:
        _check_opponents_option(opponents)
    if tag is None:  # the run's own eval.json stays its own
        parts = [*specs, *([f"perturb-{perturbations.tag}"] if perturbations.changed else [])]
        parts += [f"vs-{Path(opponents.replace(':', '-')).name}"] if opponents is not None else []
        tag = "-".join(parts) or None
    settings: dict[str, Any] = {
        "episodes": episodes,
        "seed": seed,
        "num_envs": num_envs,
        "record": not no_record,
        "csv": csv,
        "tracks": tracks,
    }
    settings["perturbations"] = perturbations
    try:
        paths = runs.eval_paths(folder, tag)
        with trained_agents(folder, pretrained, threads, obstacles) as (config, trained, about):
            if opponents is not None:
                trained, about = _held_out(config, trained, about, opponents, settings)
            _evaluate_run(folder, paths, config, trained, about, tag, settings, specs)
    except ValueError as error:  # RunBusy, a bad --agent, …
        raise BadInput(str(error)) from None


#: How --opponents names a shipped agent's condition.
SHIPPED = "pretrained:"


def _check_opponents_option(opponents: str) -> None:
    """Refuse an --opponents value before anything heavy is imported."""
    from pursuit_bench.env.conditions import CONDITIONS

    if opponents.startswith(SHIPPED):
        if opponents.removeprefix(SHIPPED) not in CONDITIONS:
            raise BadInput(f"--opponents {opponents}: expected pretrained:CONDITION, one of {', '.join(CONDITIONS)}")
    elif opponents != "scripted" and not (Path(opponents) / "config.json").is_file():
        raise BadInput(
            f"--opponents {opponents}: expected a run folder (with config.json), pretrained:CONDITION or 'scripted'"
        )


def _held_out(
    config: Any, agents: dict[str, Any], about: dict[str, Any], opponents: str, settings: dict[str, Any]
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The agents to evaluate against held-out opponents (the run's predators, OTHER's prey or
    FleeingPrey), and ``about`` with the other side's result: OTHER's predators against the
    run's prey by the same protocol (its ``prey_check`` scores the run's prey)."""
    from pursuit_bench.agents.kinds import ScriptedAgent
    from pursuit_bench.analysis.robustness import check_opponents
    from pursuit_bench.rules.policies import FleeingPrey
    from pursuit_bench.training.evaluate import evaluate_agents

    prey = agents["prey_0"]
    if opponents == "scripted":
        obstacles = bool(config.task_options.get("obstacles"))
        return {**agents, "prey_0": ScriptedAgent("prey_0", FleeingPrey(obstacles=obstacles))}, {
            **about,
            "opponents": {"prey": "FleeingPrey"},
        }
    if opponents.startswith(SHIPPED):
        from pursuit_bench import pretrained

        other_config, other, _ = pretrained.described(opponents.removeprefix(SHIPPED))
    else:
        other_config, other, _ = runs.described(Path(opponents))
    mine = "the shipped agents" if "pretrained" in about else "the run"
    check_opponents(config, other_config, mine=mine, theirs=opponents, retrainable="pretrained" not in about)
    prey_side = evaluate_agents(
        config.condition,
        {**{k: v for k, v in other.items() if k != "prey_0"}, "prey_0": prey},
        episodes=settings["episodes"],
        seed=settings["seed"],
        num_envs=settings["num_envs"],
        backend=config.backend,
        predator_kind=other_config.predator,
        task_options=config.task_options,
        avoidance=other_config.avoids,
        perturbations=settings["perturbations"],
    )
    held_out = {"prey": str(opponents), "prey_side": prey_side}
    return {**agents, "prey_0": other["prey_0"]}, {**about, "opponents": held_out}


def _outcomes(check: dict[str, float]) -> str:
    """A prey's check in words: its return and how its episodes ended, the four ways that add to
    one (``prey_outcomes``: a predator's running into a wall ends the episode too)."""
    rest = max(0.0, 1.0 - check["captured"] - check["left_area"] - check["survived"])
    return (
        f"return {check['return']:+.3f}, caught {check['captured']:.1%}, ran into a wall {check['left_area']:.1%}, "
        f"a predator ran into a wall {rest:.1%}, survived to the time limit {check['survived']:.1%}"
    )


def _agent_specs(values: tuple[str, ...]) -> dict[str, str]:
    specs = {}
    for value in values:
        name, _, spec = value.partition("=")
        if not name or not spec:
            raise BadInput(
                f"--agent {value!r}: expected NAME=MODULE:FACTORY or NAME=MODEL.zip, e.g. predator_0=my_agents:make"
            )
        if name in specs:
            raise BadInput(f"--agent {name}: given twice")
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
    from pursuit_bench.agents import external
    from pursuit_bench.figures.plots import reward_bars_png
    from pursuit_bench.training.evaluate import evaluate_into

    kind = None
    if specs:
        agents = external.replaced(agents, specs)
        about["external_agents"] = specs
        first = next(iter(agents.values()))
        kind = first.kind if isinstance(first, external.ExternalAgent) else None
    try:
        with SignalCatcher(raise_at_once=False).active() as signals:
            result = evaluate_into(
                paths,
                config,
                agents,
                {**about, "tag": tag},
                check=signals.check,
                predator_kind=kind,
                figure=reward_bars_png,
                **settings,
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
    held_out = result.get("opponents", {})
    side = held_out.get("prey_side")
    check = result.get("prey_check")
    if check is not None:
        external = result["prey_kind"].startswith("external")
        who = (
            result["prey_kind"]
            if external
            else f"{held_out['prey']}'s learned prey"
            if side is not None
            else "the learned prey"
        )
        click.echo(
            f"prey_0 ({who}), greedy: {_outcomes(check['learned_greedy'])}; "
            f"FleeingPrey in its place: {_outcomes(check['fleeing_prey'])}"
        )
    elif held_out.get("prey") == "FleeingPrey":
        click.echo("prey_0: FleeingPrey (scripted), in the evaluated agents' prey's place")
    if side is not None:
        check = side["prey_check"]["learned_greedy"]
        click.echo(f"the evaluated agents' own prey against {held_out['prey']}'s predators, greedy: {_outcomes(check)}")
    if result.get("perturbations"):
        click.echo("perturbed: " + ", ".join(f"{k}={v:g}" for k, v in result["perturbations"].items()))
    protocol, epsilon = "", result.get("protocol", {}).get("prey_epsilon")
    if result.get("prey_check") is not None and epsilon is not None:  # beside a greedy prey's outcomes
        protocol = f" (the paper's protocol: the prey ε-greedy with ε = {epsilon:g}, not greedy as above)"
    click.echo(f"capture rate {result['capture_rate']:.1%}{protocol}; results in {paths['json']} and {paths['png']}")
    if settings["record"]:
        click.echo(f"recording: {paths['rrd']}   (pursuit-bench view {paths['rrd']})")
    if settings["csv"]:
        click.echo(f"trajectories: {paths['csv']}")
    if settings["tracks"]:
        click.echo(f"movement datasets: {paths['tracks']}/ (xarray.open_dataset reads each)")
