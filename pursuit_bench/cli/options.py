"""What the commands share: the one-line error, the options of train and sweep (one per
hyper-parameter, with the presets' values in the help), name lists, and RUN or --pretrained.
"""

from __future__ import annotations

import ast
import contextlib
import dataclasses
import inspect
import itertools
import os
import re
import shutil
import tempfile
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import click

from pursuit_bench.agents.config import PRESET_ARENAS, PRESETS, AgentConfig
from pursuit_bench.env.conditions import CONDITIONS, MAX_OBSTACLES, OBSTACLE_RADII, OBSTACLE_RADIUS

PREDATOR_KINDS = ("hierarchical", "flat", "residual", "always_chase", "always_stalk")
#: Training budgets above this (100 times the paper's 1e6 episodes) are surely a typing error.
MAX_EPISODES = 100_000_000
RECORD_EVERY = 100


def recording_every(no_record: bool, record_every: int | None) -> int:
    """The recording period, refusing ``--record-every`` beside ``--no-record``."""
    if no_record and record_every is not None:
        raise BadInput("--record-every goes with recording: leave it out with --no-record")
    return RECORD_EVERY if record_every is None else record_every


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
            type=click.IntRange(min=1, max=MAX_EPISODES),
            default=None,
            help="Episodes to train [preset's: "
            + ", ".join(f"{name} {preset.episodes}" for name, preset in PRESETS.items())
            + "]. With train --resume: the run's saved target unless given, which extends or shortens the run.",
        ),
        click.option(
            "--num-envs",
            type=click.IntRange(min=1),
            default=None,
            help="Arenas stepped together [preset's: "
            + ", ".join(f"{name} {PRESET_ARENAS[name]}" for name in PRESETS)
            + "].",
        ),
        click.option(
            "--physics",
            "physics",
            type=click.Choice(["pymunk", "numpy"]),
            default="pymunk",
            show_default=True,
            help="Physics backend of the arenas: pymunk (the reference) or the numpy twin.",
        ),
        *obstacle_options(),
        click.option(
            "--avoidance/--no-avoidance",
            default=True,
            show_default=True,
            help="With obstacles: the lower layer of the hierarchical predator and of the baselines "
            "steers around them; --no-avoidance keeps plain parallel navigation.",
        ),
        click.option(
            "--record-every",
            type=click.IntRange(min=1),
            default=None,
            help=f"Record every Nth episode [{RECORD_EVERY}].",
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


def obstacle_options() -> list[Any]:
    """``--obstacles N`` and ``--obstacle-radius R`` of train and sweep (docs/obstacles.md)."""
    return [
        click.option(
            "--obstacles",
            type=click.IntRange(0, MAX_OBSTACLES),
            default=0,
            show_default=True,
            help="Static circular obstacles per arena (0: the paper's empty arena).",
        ),
        click.option(
            "--obstacle-radius",
            type=click.FloatRange(*OBSTACLE_RADII),
            default=OBSTACLE_RADIUS,
            show_default=True,
            help="Radius of every obstacle.",
        ),
    ]


def obstacles_option(command: Any) -> Any:
    """``--obstacles N`` of eval, analyze and law: play with N obstacles instead of the run's."""
    return click.option(
        "--obstacles",
        type=click.IntRange(0, MAX_OBSTACLES),
        default=None,
        help="Play with N obstacles instead of as many as the agents trained with [theirs]. Agents trained "
        "without obstacles observe no range readings, so 0 and N > 0 do not mix.",
    )(command)


def with_obstacles(config: Any, obstacles: int | None) -> Any:
    """``config`` (a TrainConfig) with ``obstacles`` obstacles (None: as it is); refused where
    the agents' observations would change shape (0 against N > 0)."""
    if obstacles is None or obstacles == config.obstacles:
        return config
    if (obstacles > 0) != (config.obstacles > 0):
        raise BadInput(
            f"--obstacles {obstacles}: these agents were trained with {config.obstacles} obstacles; with and "
            "without obstacles they observe different things (range readings): give a count > 0 only for agents "
            "trained with obstacles, 0 for none"
        )
    return dataclasses.replace(config, obstacles=obstacles)


def threads_option(command: Any) -> Any:
    """``--threads``: torch threads (1, the default, makes results repeat)."""
    return click.option(
        "--threads", type=click.IntRange(min=1), default=1, show_default=True, help="torch threads (1: repeatable)."
    )(command)


def names(value: str, known: list[str] | tuple[str, ...], what: str) -> tuple[str, ...]:
    """``all`` or a comma-separated list of known names."""
    if value == "all":
        return tuple(known)
    names = tuple(v.strip() for v in value.split(",") if v.strip())
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise BadInput(f"--{what} {value!r}: expected 'all' or a comma-separated list of {', '.join(known)}")
    return names


def episode_counts(value: str) -> tuple[int, ...]:
    """A comma-separated list of episode counts (possibly empty)."""
    try:
        return tuple(sorted({int(v) for v in value.split(",") if v.strip()}))
    except ValueError:
        raise BadInput(
            f"--keep-checkpoints {value!r}: expected comma-separated episode counts, e.g. 1500,5000"
        ) from None


def pretrained_options(command: Any) -> Any:
    """``--pretrained CONDITION`` and ``--out DIR``: the shipped agents instead of a RUN."""
    command = click.option(
        "--out",
        type=OutFolder(),
        default=None,
        help="With --pretrained: the folder for the results [runs/pretrained-CONDITION].",
    )(command)
    return click.option(
        "--pretrained",
        type=click.Choice(list(CONDITIONS)),
        default=None,
        help="Use the trained agents shipped with the package for this condition (REPRODUCTION.md) instead of a RUN.",
    )(command)


def run_or_pretrained(run: Path | None, pretrained: str | None, out: Path | None) -> Path:
    """The folder a command works in: RUN, or --out (default runs/pretrained-CONDITION) with --pretrained."""
    if (run is None) == (pretrained is None):
        raise click.UsageError("give a RUN folder or --pretrained CONDITION (one of the two)")
    if out is not None and pretrained is None:
        raise click.UsageError("--out goes with --pretrained; a RUN's results go into the RUN")
    if pretrained is not None:
        folder = out if out is not None else Path("runs") / f"pretrained-{pretrained}"
        check_out_folder(folder)
        if (folder / "config.json").exists():
            raise click.UsageError(f"--out {folder} holds a training run, whose results are its own: choose another")
        return folder
    assert run is not None
    return run


def check_out_folder(out: Path) -> None:
    """BadInput unless ``--out`` is a folder this process can write in, or can make: no part of
    its path is a file, and a file can be made there. What the check makes (the missing folders,
    a probe file) it removes again, so that a refusal later leaves nothing behind."""
    missing = []
    try:
        for part in (out, *out.parents):
            if part.exists():
                if not part.is_dir():
                    what = "exists and is not a folder" if part == out else f"{part} is a file"
                    raise BadInput(f"--out {out}: {what}")
                break
            missing.append(part)
        try:
            for part in reversed(missing):
                part.mkdir()
            fd, probe = tempfile.mkstemp(dir=out, prefix=".write-check.")
            os.close(fd)
            os.unlink(probe)
        finally:
            for part in missing:  # the deepest first; one made meanwhile by another process stays
                with contextlib.suppress(OSError):
                    part.rmdir()
    except OSError as error:
        raise BadInput(f"--out {out}: cannot write there ({error.strerror or error})") from None


class OutFolder(click.Path):
    """The type of every ``--out``: a folder :func:`check_out_folder` accepts, checked as the
    command line is read (before any work), and never the empty path (pathlib reads it as '.')."""

    def __init__(self) -> None:
        super().__init__(path_type=Path)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, str) and not value.strip():
            raise BadInput(f"--out {value!r}: an empty path; give a folder")
        out = Path(os.fsdecode(super().convert(value, param, ctx)))
        check_out_folder(out)
        return out


def check_run_folder(folder: Path) -> None:
    """BadInput unless ``folder`` is a run folder (a folder with config.json); imports nothing."""
    if folder.exists() and not folder.is_dir():
        raise BadInput(f"{folder}: a file, not a run folder")
    if not folder.is_dir():
        raise BadInput(f"{folder}: no such run folder")
    if not (folder / "config.json").is_file():
        raise BadInput(f"{folder}: not a pursuit-bench run folder (no config.json)")


@contextlib.contextmanager
def locked(folder: Path, pretrained: str | None) -> Iterator[None]:
    """Hold ``folder``'s lock: a RUN (checked to be one before a lock file is made in it), or the
    results folder of --pretrained (made if missing, and removed again, lock and all, if what ran
    in it failed). Imports nothing heavy: a refusal is quick."""
    from pursuit_bench.io.files import locked as lock

    made = False
    if pretrained is None:
        check_run_folder(folder)
    else:
        made = not folder.exists()
        folder.mkdir(parents=True, exist_ok=True)
    try:
        with lock(folder):
            yield
    except BaseException:
        if made:
            shutil.rmtree(folder, ignore_errors=True)
        raise


@contextlib.contextmanager
def trained_agents(
    folder: Path, pretrained: str | None, threads: int, obstacles: int | None = None
) -> Iterator[tuple[Any, dict[str, Any], dict]]:
    """Hold ``folder``'s lock (:func:`locked`) with torch on ``threads`` threads, and give the
    agents to work with: (training config, agents by name, what an evaluation says of them), a
    RUN's last checkpoint's (``runs.described``) or the shipped ones' (``pretrained.described``);
    the config with ``obstacles`` obstacles when given (:func:`with_obstacles`)."""
    with locked(folder, pretrained):
        import torch

        from pursuit_bench import pretrained as shipped
        from pursuit_bench.training import runs

        torch.set_num_threads(threads)
        config, agents, about = runs.described(folder) if pretrained is None else shipped.described(pretrained)
        yield with_obstacles(config, obstacles), agents, about


def in_option_words(error: Exception) -> str:
    """A configuration's error as the user typed it: a message starting ``field_name=value:``
    becomes ``--field-name value:`` (``keep_checkpoints=[500]`` -> ``--keep-checkpoints 500``)."""
    text = str(error)
    match = re.match(r"([a-z][a-z0-9_]*)=(\[[^\]]*\]|\S+?)(:.*)", text, re.DOTALL)
    if match is None:
        return text
    name, value, rest = match.groups()
    if value.startswith("["):
        value = ",".join(v.strip() for v in value[1:-1].split(",") if v.strip())
    return f"--{name.replace('_', '-')} {value}{rest}"
