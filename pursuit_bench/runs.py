"""A training run's folder: what it holds and how it is written and read back.

``runs/NAME/`` holds ``config.json`` (the resolved configuration), ``metrics.jsonl`` (one row
per episode), ``checkpoint.pt`` (the latest checkpoint), ``train.rrd`` (the Rerun recording;
a resumed run writes ``train.resume1.rrd``, …) and, after ``eval``, ``eval.json``, ``eval.png``
and ``eval.rrd``. The config, the checkpoint and the results are written atomically.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from pursuit_bench.agents import checkpoint
from pursuit_bench.files import atomic_write_text
from pursuit_bench.train import TrainConfig

RUN_FORMAT = "pursuit-bench-run-1"
CONFIG = "config.json"
METRICS = "metrics.jsonl"
CHECKPOINT = "checkpoint.pt"
EVAL_JSON = "eval.json"
EVAL_PNG = "eval.png"
EVAL_RRD = "eval.rrd"
RUN_FILES = (CONFIG, METRICS, CHECKPOINT, EVAL_JSON, EVAL_PNG, EVAL_RRD)


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


def save_checkpoint(folder: Path, state: dict[str, Any]) -> None:
    checkpoint.save(folder / CHECKPOINT, {"kind": "run", **state})


def load_checkpoint(folder: Path) -> dict[str, Any]:
    """The run's latest checkpoint, or ValueError (missing, truncated, corrupted, foreign)."""
    path = folder / CHECKPOINT
    if not path.is_file():
        raise ValueError(f"{folder}: no checkpoint yet ({CHECKPOINT} is missing)")
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


def recording_path(folder: Path) -> Path:
    """``train.rrd``, or the next ``train.resumeK.rrd`` if earlier sessions wrote theirs."""
    path = folder / "train.rrd"
    k = 0
    while path.exists():
        k += 1
        path = folder / f"train.resume{k}.rrd"
    return path


def clear(folder: Path) -> None:
    """Remove a run's own files (and only those) so that a fresh run can start there."""
    for name in RUN_FILES:
        (folder / name).unlink(missing_ok=True)
    for rrd in folder.glob("train*.rrd"):
        rrd.unlink()
