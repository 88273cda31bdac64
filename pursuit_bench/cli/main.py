"""``pursuit-bench``: train, evaluate and look at agents from the command line.

The commands parse options into configurations and call the library (``train.Trainer``,
``evaluate.evaluate_agents``, ``recording.Recorder``); they hold no logic of their own beyond
run folders, progress and errors. Bad input is a one-line error and exit status 2.
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
import itertools
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import click
import torch

from pursuit_bench import runs
from pursuit_bench.agents.config import PRESETS, AgentConfig
from pursuit_bench.conditions import CONDITIONS
from pursuit_bench.evaluate import evaluate_agents
from pursuit_bench.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.plots import reward_bars_png
from pursuit_bench.recording import Recorder
from pursuit_bench.train import EpisodeRecord, TrainConfig, Trainer


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
        help_text = docs.get(f.name, "") + f" [paper: {getattr(PRESETS['paper'], f.name)}, "
        help_text += f"quick: {getattr(PRESETS['quick'], f.name)}]"
        command = click.option(flag, f.name, type=kind, default=None, help=help_text)(command)
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


def _start_run(out: Path, config: TrainConfig, settings: dict[str, Any], resume: bool, force: bool) -> dict | None:
    """Prepare the run folder; returns the checkpoint state to resume from, or None."""
    if resume and force:
        raise BadInput("--resume and --force contradict each other: pick one")
    if out.exists() and not out.is_dir():
        raise BadInput(f"--out {out}: exists and is not a folder")
    if resume:
        try:
            saved, _ = runs.read_config(out)
            state = runs.load_checkpoint(out)
        except ValueError as error:
            raise BadInput(f"cannot resume: {error}") from None
        if saved != dataclasses.replace(config, episodes=saved.episodes):
            raise BadInput(f"--resume: {out} holds a run with another configuration; leave the options as they were")
        runs.keep_metrics(out, int(state["episodes_done"]))
        runs.write_config(out, config, settings)
        return state
    if out.exists() and any(out.iterdir()):
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
    out.mkdir(parents=True, exist_ok=True)
    runs.write_config(out, config, settings)
    return None


def _progress_line(record: EpisodeRecord | None, returns: list[float], captures: list[bool], epsilon: float) -> str:
    if record is None:
        return ""
    window = slice(-100, None)
    ret = sum(returns[window]) / max(len(returns[window]), 1)
    cap = sum(captures[window]) / max(len(captures[window]), 1)
    return f"return {ret:+.2f} | capture {cap:.0%} | ε {epsilon:.2f}"


@main.command()
@click.option("--condition", type=click.Choice(list(CONDITIONS)), default="1p-high", show_default=True)
@click.option(
    "--preset", type=click.Choice(list(PRESETS)), default="quick", show_default=True, help="Hyper-parameters."
)
@click.option("--episodes", type=click.IntRange(min=1), default=None, help="Episodes to train [preset's].")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--out", type=click.Path(path_type=Path), default=None, help="Run folder [runs/CONDITION-seedS].")
@click.option("--resume", is_flag=True, help="Continue the run in --out from its last checkpoint.")
@click.option("--force", is_flag=True, help="Start over in --out, replacing the run there.")
@click.option("--num-envs", type=click.IntRange(min=1), default=8, show_default=True, help="Arenas stepped together.")
@click.option(
    "--predator",
    type=click.Choice(["hierarchical", "flat", "always_chase", "always_stalk"]),
    default="hierarchical",
    show_default=True,
)
@click.option("--prey", type=click.Choice(["learning", "scripted"]), default="learning", show_default=True)
@click.option("--batched-learners/--separate-learners", default=True, show_default=True)
@click.option("--backend", type=click.Choice(["pymunk", "numpy"]), default="pymunk", show_default=True)
@click.option(
    "--record-every", type=click.IntRange(min=1), default=100, show_default=True, help="Record every Nth episode."
)
@click.option("--no-record", is_flag=True, help="Write no Rerun recording.")
@click.option("--checkpoint-every", type=click.IntRange(min=1), default=100, show_default=True, help="Episodes.")
@click.option(
    "--threads", type=click.IntRange(min=1), default=1, show_default=True, help="torch threads (1: repeatable)."
)
@hyperparameter_options
def train(
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
    backend: str,
    record_every: int,
    no_record: bool,
    checkpoint_every: int,
    threads: int,
    **hyperparameters: Any,
) -> None:
    """Train every agent of a condition together (independent learners) into a run folder."""
    torch.set_num_threads(threads)
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
            backend=backend,  # type: ignore[arg-type]
        )
    except ValueError as error:
        raise BadInput(str(error)) from None
    out = out or Path("runs") / f"{condition}-seed{seed}"
    settings = {"preset": preset, "record_every": record_every, "checkpoint_every": checkpoint_every}
    state = _start_run(out, config, settings, resume, force)
    recorder = None
    if not no_record:  # training records every Nth episode: send each at once
        agent_names = list(CONDITIONS[condition].agent_names)
        described = {"condition": condition, **config.to_dict(), **settings}
        recorder = Recorder(runs.recording_path(out), agent_names, described, episodes_per_send=1)
    metrics = (out / runs.METRICS).open("a")
    watched = CONDITIONS[condition].agent_names[0]
    returns: list[float] = []
    captures: list[bool] = []
    last: list[EpisodeRecord] = []

    def on_episode(record: EpisodeRecord) -> None:
        metrics.write(json.dumps(record.as_row()) + "\n")
        returns.append(record.returns[watched])
        captures.append(record.captured)
        last[:] = [record]

    trainer = Trainer(config, on_episode, recorder=recorder, record_every=record_every)
    if state is not None:
        trainer.load_state_dict(state)
        click.echo(f"resuming {out} at episode {trainer.episodes_done} of {config.episodes}", err=True)
    next_checkpoint = (trainer.episodes_done // checkpoint_every + 1) * checkpoint_every
    learner = trainer.groups[0].learner if trainer.groups else None  # its ε is shown
    progress: Any = click.progressbar(
        length=config.episodes,
        label=f"training {condition}",
        file=sys.stderr,
        item_show_func=lambda _: _progress_line(
            last[0] if last else None, returns, captures, learner.epsilon if learner else 0.0
        ),
    )
    try:
        with progress as bar:
            bar.update(trainer.episodes_done)
            while trainer.episodes_done < config.episodes:
                before = trainer.episodes_done
                trainer.step()
                bar.update(trainer.episodes_done - before, current_item=last[0] if last else None)
                if trainer.episodes_done >= next_checkpoint:
                    metrics.flush()
                    runs.save_checkpoint(out, trainer.state_dict())
                    next_checkpoint += checkpoint_every
    except KeyboardInterrupt:
        metrics.close()
        runs.save_checkpoint(out, trainer.state_dict())
        runs.keep_metrics(out, trainer.episodes_done)
        if recorder is not None:
            recorder.close()
        click.echo(
            f"\ninterrupted at episode {trainer.episodes_done}: checkpoint saved; "
            f"continue with: pursuit-bench train --out {out} --resume (and the same options)",
            err=True,
        )
        sys.exit(130)
    metrics.close()
    runs.save_checkpoint(out, trainer.state_dict())
    runs.keep_metrics(out, trainer.episodes_done)
    if recorder is not None:
        recorder.close()
    click.echo(f"trained {trainer.episodes_done} episodes of {condition} into {out}/")
    click.echo(f"  metrics: {out / runs.METRICS}   checkpoint: {out / runs.CHECKPOINT}")
    if recorder is not None:
        click.echo(f"  recording: {recorder.path}   (pursuit-bench view {recorder.path})")


@main.command(name="eval")
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--episodes", type=click.IntRange(min=1), default=1000, show_default=True)
@click.option("--seed", type=int, default=12345, show_default=True)
@click.option("--num-envs", type=click.IntRange(min=1), default=64, show_default=True)
@click.option("--no-record", is_flag=True, help="Write no Rerun recording of the evaluated episodes.")
@click.option("--threads", type=click.IntRange(min=1), default=1, show_default=True)
def evaluate(run: Path, episodes: int, seed: int, num_envs: int, no_record: bool, threads: int) -> None:
    """Evaluate a trained RUN by the paper's protocol; writes eval.json, eval.png and eval.rrd."""
    torch.set_num_threads(threads)
    try:
        config, _ = runs.read_config(run)
        state = runs.load_checkpoint(run)
        trainer = Trainer(dataclasses.replace(config, num_envs=1))
        trainer.load_state_dict(state)
    except ValueError as error:
        raise BadInput(str(error)) from None
    names = list(CONDITIONS[config.condition].agent_names)
    recorder = None
    if not no_record:
        recorder = Recorder(
            run / runs.EVAL_RRD, names, {"condition": config.condition, "evaluation": True, **config.to_dict()}
        )
    try:
        result = evaluate_agents(
            config.condition,
            trainer.agents,  # type: ignore[arg-type]
            episodes=episodes,
            seed=seed,
            prey_epsilon=0.1 if config.prey == "learning" else None,
            num_envs=num_envs,
            recorder=recorder,
            backend=config.backend,
        )
    finally:
        if recorder is not None:
            recorder.close()
    result["trained_episodes"] = int(state["episodes_done"])
    result["predator_kind"] = config.predator
    atomic_write_text(run / runs.EVAL_JSON, json.dumps(result, indent=2) + "\n")
    atomic_write_bytes(run / runs.EVAL_PNG, reward_bars_png(result))
    for panel in result["panels"]:
        click.echo(
            f"{panel['predator']}: hierarchical {panel['hierarchical']:+.3f}  "
            f"always-chase {panel['always_chase']:+.3f}  always-stalk {panel['always_stalk']:+.3f}"
        )
    click.echo(
        f"capture rate {result['capture_rate']:.1%}; results in {run / runs.EVAL_JSON} and {run / runs.EVAL_PNG}"
    )
    if recorder is not None:
        click.echo(f"recording: {recorder.path}   (pursuit-bench view {recorder.path})")


@main.command()
@click.argument("file", type=click.Path(path_type=Path))
def view(file: Path) -> None:
    """Open a recording (.rrd) in the Rerun viewer."""
    if not file.is_file():
        raise BadInput(f"{file}: no such recording")
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise click.ClickException(
            f"no display here to open the viewer on. Copy {file} to a machine with one and run "
            f"`rerun {file.name}`, or serve the web viewer from here: `rerun --web-viewer {file}` "
            "and open the address it prints in a browser"
        )
    rerun = shutil.which("rerun") or sys.executable
    args = [rerun, str(file)] if rerun != sys.executable else [sys.executable, "-m", "rerun", str(file)]
    raise SystemExit(subprocess.call(args))


if __name__ == "__main__":
    main()
