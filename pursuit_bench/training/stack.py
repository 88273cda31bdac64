"""Run folders trained as one stack: what ``train`` and each worker of ``sweep`` do once they
hold the folders' locks (a run folder's evaluation is ``evaluate.evaluate_folder``).

A stack is K runs in one :class:`~pursuit_bench.training.train.Trainer`. Each run writes its own folder
(``runs.py``): metrics as its episodes finish, a recording of every k-th episode, a checkpoint
when it finishes. The unfinished runs are checkpointed together, so that a stack resumes as one.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.training import runs
from pursuit_bench.training.train import EpisodeRecord, TrainConfig, Trainer
from pursuit_bench.trajectories.recording import Recorder


@dataclass
class FolderRun:
    """One run of a stack: its folder (prepared, config written, locked by the caller), its
    configuration, its settings (``record_every``, ``checkpoint_every``, ``recording_id``) and
    the checkpoint it resumes from (None: from the start)."""

    folder: Path
    config: TrainConfig
    settings: dict[str, Any]
    state: dict[str, Any] | None = None

    @property
    def episodes_done(self) -> int:
        return int(self.state["episodes_done"]) if self.state else 0

    @property
    def env_steps(self) -> int:
        return int(self.state["env_steps"]) if self.state else 0


def train_stack(
    stack: list[FolderRun],
    *,
    record: bool = True,
    should_stop: Callable[[], bool] = lambda: False,
    on_episode: Callable[[int, EpisodeRecord], None] | None = None,
) -> bool:
    """Train the runs of ``stack`` as one until each has its episodes, or until ``should_stop()``
    (then every unfinished run is checkpointed). ``on_episode(k, record)`` hears each episode
    of run k. Returns whether every run finished."""
    places = [k for k, r in enumerate(stack) if r.episodes_done < r.config.episodes]
    todo = [stack[k] for k in places]
    if not todo:
        return True
    recorders: list[Recorder | None] = []
    for r in todo:
        recorder = None
        if record:  # training records every Nth episode: send each at once
            recorder = Recorder(
                runs.recording_path(r.folder),
                list(CONDITIONS[r.config.condition].agent_names),
                {"condition": r.config.condition, **r.config.to_dict(), **r.settings},
                episodes_per_send=1,
                recording_id=r.settings.get("recording_id") or str(r.folder),
            )
        recorders.append(recorder)
    for r in todo:  # rows written after the checkpoint (a killed process) are trained again
        runs.keep_metrics(r.folder, r.episodes_done)
    metrics = [(r.folder / runs.METRICS).open("a") for r in todo]

    keep = [{int(n) for n in r.settings.get("keep_checkpoints", ())} for r in todo]

    def writer(k: int) -> Callable[[EpisodeRecord], None]:
        def write(record: EpisodeRecord) -> None:
            metrics[k].write(json.dumps(record.as_row()) + "\n")
            if record.episode in keep[k]:  # a milestone: its state as the episode ends, kept for later evaluation
                runs.save_checkpoint(todo[k].folder, trainer.state_dict(k), runs.milestone_checkpoint(record.episode))
            if on_episode is not None:
                on_episode(places[k], record)

        return write

    trainer = Trainer(
        [r.config for r in todo],
        [writer(k) for k in range(len(todo))],
        recorder=recorders,
        record_every=[int(r.settings.get("record_every", 100)) for r in todo],
    )
    for k, r in enumerate(todo):
        if r.state is not None:
            trainer.load_state_dict(r.state, run=k)
    trainer.check_lockstep()
    every = [int(r.settings.get("checkpoint_every", 100)) for r in todo]
    next_checkpoint = [(run.episodes_done // e + 1) * e for run, e in zip(trainer.runs, every, strict=True)]
    closed = [False] * len(todo)

    def close(k: int) -> None:
        """Checkpoint run k, trim its metrics to the checkpoint, finish its recording."""
        metrics[k].close()
        runs.save_checkpoint(todo[k].folder, trainer.state_dict(k))
        runs.keep_metrics(todo[k].folder, trainer.runs[k].episodes_done)
        if recorders[k] is not None:
            recorders[k].close()  # type: ignore[union-attr]
        closed[k] = True

    try:
        while not trainer.finished and not should_stop():
            trainer.step()
            due = False
            for k, run in enumerate(trainer.runs):
                if closed[k]:
                    continue
                if run.finished:
                    close(k)
                elif run.episodes_done >= next_checkpoint[k]:
                    due = True
            if due:  # every unfinished run at once: they resume together
                for k, run in enumerate(trainer.runs):
                    if not closed[k]:
                        metrics[k].flush()
                        runs.save_checkpoint(todo[k].folder, trainer.state_dict(k))
                        next_checkpoint[k] = (run.episodes_done // every[k] + 1) * every[k]
    finally:
        for k in range(len(todo)):
            if not closed[k]:
                close(k)
    return trainer.finished
