"""A training run's folder: what it holds and how it is written and read back. Reading its
configuration and holding its lock import neither torch nor the physics.

``runs/NAME/`` holds ``config.json`` (the resolved configuration), ``metrics.jsonl`` (one row
per episode), ``checkpoint.pt`` (the latest checkpoint), ``train.rrd`` (the Rerun recording;
a resumed run adds ``train.resume1.rrd``, …, pieces of one recording with the same recording
id) and, after ``eval``, ``eval.json``, ``eval.png`` and ``eval.rrd`` (``eval-TAG.*`` with
``--tag``). The config, the checkpoint and the results are written atomically; ``.lock`` is held
by the one process that trains or evaluates in the folder.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pursuit_bench.io.files import RunBusy as RunBusy  # the lock lives in files.py: no torch, quick refusals
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.io.files import locked as locked
from pursuit_bench.training.train_config import TrainConfig

if TYPE_CHECKING:
    from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent

RUN_FORMAT = "pursuit-bench-run-1"
CONFIG = "config.json"
METRICS = "metrics.jsonl"
CHECKPOINT = "checkpoint.pt"
LOCK = ".lock"  # what files.locked holds
RUN_FILES = (CONFIG, METRICS, CHECKPOINT)
_TAG = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")


def eval_paths(folder: Path, tag: str | None = None) -> dict[str, Path]:
    """``{"json", "png", "rrd", "csv"}``: ``eval.*``, or ``eval-TAG.*`` with a tag; ``"tracks"``:
    the folder ``eval-tracks`` (``eval-TAG-tracks``)."""
    if tag is not None and not _TAG.fullmatch(tag):
        raise ValueError(f"tag={tag!r}: expected letters, digits, '_', '-' or '.' (not first)")
    stem = "eval" if tag is None else f"eval-{tag}"
    return {kind: folder / f"{stem}.{kind}" for kind in ("json", "png", "rrd", "csv")} | {
        "tracks": folder / f"{stem}-tracks"
    }


def holds_only_unstarted_or_nothing(folder: Path) -> bool:
    """True for a folder a new run may take without ``--force``: empty (but for a lock), or
    holding a run that never reached its first checkpoint."""
    if not folder.exists():
        return True
    if is_run(folder):
        return not (folder / CHECKPOINT).exists()
    return all(p.name == LOCK for p in folder.iterdir())


def is_run(folder: Path) -> bool:
    return (folder / CONFIG).is_file()


def write_config(folder: Path, config: TrainConfig, settings: dict[str, Any]) -> None:
    """The resolved configuration: the training config and the run's own settings."""
    payload = {"format": RUN_FORMAT, "train": config.to_dict(), "run": settings}
    atomic_write_text(folder / CONFIG, json.dumps(payload, indent=2) + "\n")


def read_config(folder: Path) -> tuple[TrainConfig, dict[str, Any]]:
    """``(config, settings)`` of a run folder, or ValueError saying what is wrong."""
    path = folder / CONFIG
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such run folder")
    if not path.is_file():
        raise ValueError(f"{folder}: not a pursuit-bench run folder (no {CONFIG})")
    try:
        payload = json.loads(path.read_text())
        if payload.get("format") != RUN_FORMAT:
            raise ValueError(f"format {payload.get('format')!r}")
        return TrainConfig.from_dict(payload["train"]), dict(payload.get("run", {}))
    except (ValueError, KeyError, TypeError, AttributeError) as error:
        raise ValueError(f"{path}: not a pursuit-bench run configuration ({error})") from None


def milestone_checkpoint(episodes: int) -> str:
    """The name of the checkpoint a run keeps at ``episodes`` (a sweep's ``keep_checkpoints``)."""
    return f"checkpoint-ep{episodes}.pt"


def save_checkpoint(folder: Path, state: dict[str, Any], name: str = CHECKPOINT) -> None:
    from pursuit_bench.agents import checkpoint

    checkpoint.save(folder / name, {"kind": "run", **state})


def load_checkpoint(folder: Path, name: str = CHECKPOINT) -> dict[str, Any]:
    """The run's latest checkpoint (or the one called ``name``), or ValueError (missing,
    truncated, corrupted, foreign)."""
    from pursuit_bench.agents import checkpoint

    path = folder / name
    if not path.is_file():
        raise ValueError(f"{folder}: no checkpoint yet ({name} is missing)")
    state = checkpoint.read(path)
    if state.get("kind") != "run" or "agents" not in state:
        raise ValueError(f"{path}: not a training-run checkpoint")
    return state


def keep_metrics(folder: Path, episodes: int) -> None:
    """Drop metric rows past ``episodes`` (written after the checkpoint a run resumes from)."""
    path = folder / METRICS
    if not path.exists():
        return
    rows = []
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            continue  # a line cut short by a kill
        if row.get("episode", 0) <= episodes:
            rows.append(line)
    atomic_write_text(path, "".join(r + "\n" for r in rows))


def load_agents(
    folder: str | os.PathLike[str], state: dict[str, Any] | None = None
) -> dict[str, LearningAgent | ScriptedAgent]:
    """The agents of a trained run folder by name (``predator_0`` …, ``prey_0``), with the
    weights of its last checkpoint, ready for ``act(observation)`` and
    :func:`~pursuit_bench.training.evaluate.evaluate_agents`. ``ValueError`` if the folder holds no
    trained run. ``state``: the folder's checkpoint, if the caller has read it already."""
    from pursuit_bench.env.task import obs_size
    from pursuit_bench.training.train import build_agents, load_agents_state

    folder = Path(folder)
    config, _ = read_config(folder)
    state = state if state is not None else load_checkpoint(folder)
    _, (agents,) = build_agents([config], [obs_size(config.task.n_agents, config.obstacles > 0)])
    load_agents_state(agents, state, config.condition)
    return agents


def described(
    folder: Path, checkpoint_name: str = CHECKPOINT
) -> tuple[TrainConfig, dict[str, LearningAgent | ScriptedAgent], dict[str, Any]]:
    """A trained run's agents with how they were trained: (training config, agents by name with
    that checkpoint's weights, what an evaluation says of them: ``trained_episodes``); the run
    folder's twin of ``pretrained.described``."""
    config, _ = read_config(folder)
    state = load_checkpoint(folder, checkpoint_name)
    return config, load_agents(folder, state), {"trained_episodes": int(state["episodes_done"])}


def recording_path(folder: Path) -> Path:
    """``train.rrd``, or the next ``train.resumeK.rrd`` if earlier sessions wrote theirs."""
    path = folder / "train.rrd"
    k = 0
    while path.exists():
        k += 1
        path = folder / f"train.resume{k}.rrd"
    return path


def recordings(folder: Path) -> list[Path]:
    """The run's recordings: the training pieces in order, then the evaluations."""
    pieces = sorted(folder.glob("train*.rrd"), key=lambda p: (len(p.name), p.name))
    return pieces + sorted(folder.glob("eval*.rrd"))


class FolderRefused(ValueError):
    """A run folder that cannot take the run asked for (:func:`prepare`); the message is one line
    for the user."""


def prepare(
    out: Path, config: TrainConfig, settings: dict[str, Any], resume: bool, force: bool
) -> tuple[dict[str, Any] | None, str | None]:
    """Make ``out`` hold this run (its lock held by the caller): resumed (``resume``: the checkpoint
    to go on from, or None where there is none yet), started over (``force``), or new; returns the
    checkpoint to resume from, or None, and a note for the user. Raises :class:`FolderRefused`
    where ``out`` holds something else, or a run that ``resume``/``force`` were not asked for."""
    if resume:
        state, note = None, None
        if (out / CHECKPOINT).exists():
            try:
                state = load_checkpoint(out)
            except ValueError as error:
                raise FolderRefused(f"cannot resume: {error}") from None
            if state["episodes_done"] > config.episodes:
                raise FolderRefused(
                    f"--episodes {config.episodes}: {out} has already trained {state['episodes_done']} episodes; "
                    "give at least that many"
                )
        else:
            note = f"{out}: no checkpoint yet; starting the run from its beginning"
        write_config(out, config, settings)
        return state, note
    if not holds_only_unstarted_or_nothing(out):
        if not is_run(out):
            raise FolderRefused(f"--out {out}: the folder is not empty and holds no pursuit-bench run; choose another")
        if not force:
            try:
                saved, _ = read_config(out)
                same = saved == config
            except ValueError:
                same = False
            what = "this run" if same else "a different run"
            raise FolderRefused(
                f"--out {out} already holds {what}: pass --resume to continue it or --force to start over"
            )
    clear(out)
    write_config(out, config, settings)
    return None, None


def clear(folder: Path) -> None:
    """Remove a run's own files (and only those) so that a fresh run can start there."""
    for name in RUN_FILES:
        (folder / name).unlink(missing_ok=True)
    for pattern in ("train*.rrd", "eval.*", "eval-*.*", ".*.tmp", "checkpoint-ep*.pt"):
        for path in folder.glob(pattern):
            path.unlink()
