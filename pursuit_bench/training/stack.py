"""Run folders trained as one stack, and a run folder evaluated: what ``train``, ``eval`` and
each worker of ``sweep`` do once they hold the folders' locks.

A stack is K runs in one :class:`~pursuit_bench.training.train.Trainer`. Each run writes its own folder
(``runs.py``): metrics as its episodes finish, a recording of every k-th episode, a checkpoint
when it finishes. The unfinished runs are checkpointed together, so that a stack resumes as one.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.perturbations import Perturbations
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.training import runs
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.recording import Recorder
from pursuit_bench.training.train import EpisodeRecord, TrainConfig, Trainer

#: Draws an evaluation's figure: ``figure(result, run name) -> PNG bytes`` (the command line
#: passes ``study.plots.reward_bars_png``; this layer draws nothing itself).
Figure = Callable[[dict[str, Any], str], bytes]


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


def evaluate_folder(
    folder: Path, *, tag: str | None = None, checkpoint: str = runs.CHECKPOINT, **options: Any
) -> dict[str, Any]:
    """Evaluate a trained run folder (its lock held by the caller) by the paper's protocol and
    write ``eval.json``, ``eval.rrd`` and, with a ``figure``, ``eval.png`` (``eval-TAG.*``)
    into it: :func:`evaluate_into` with these ``options`` (``episodes`` and ``seed`` needed).
    ``checkpoint``: which of the folder's checkpoints (the latest by default, or a milestone's).
    Returns the result."""
    config, agents, about = runs.described(folder, checkpoint)
    return evaluate_into(runs.eval_paths(folder, tag), config, agents, {**about, "tag": tag}, **options)


def evaluate_into(
    paths: dict[str, Path],
    config: TrainConfig,
    agents: dict[str, LearningAgent | ScriptedAgent],
    about: dict[str, Any],
    *,
    episodes: int,
    seed: int,
    num_envs: int = 64,
    record: bool = True,
    check: Callable[[], None] = lambda: None,
    predator_kind: str | None = None,
    perturbations: Perturbations | None = None,
    figure: Figure | None = None,
) -> dict[str, Any]:
    """Evaluate ``agents``, trained by ``config``, by the paper's protocol and write the result
    (with ``about`` and the training config), its ``figure`` (if given) and a recording to ``paths``
    (``runs.eval_paths``) together: each is written under a temporary name and renamed when all
    are complete, so an interruption leaves the previous ones as they were. ``check()`` is
    called before every step and once more before the files are put in place: an exception it
    raises stops the evaluation with the previous files untouched. ``predator_kind`` names the
    predators in the result (default: the config's); ``perturbations`` change the world and the
    senses of every variant alike (:mod:`pursuit_bench.env.perturbations`)."""
    partial = {kind: path.with_name(f".{path.name}.tmp") for kind, path in paths.items()}
    recorder = None
    try:
        if record:
            described = {"condition": config.condition, "evaluation": True, **config.to_dict()}
            recorder = Recorder(partial["rrd"], list(agents), described)
        result = evaluate_agents(
            config.condition,
            agents,  # type: ignore[arg-type]
            episodes=episodes,
            seed=seed,
            num_envs=num_envs,
            recorder=recorder,
            check=check,
            perturbations=perturbations,
            **{**config.protocol, "predator_kind": predator_kind or config.predator},
        )
        result.update({**about, "training": config.to_dict()})
        if recorder is not None:
            recorder.close()
        if figure is not None:
            atomic_write_bytes(partial["png"], figure(result, paths["json"].parent.name))
        atomic_write_text(partial["json"], json.dumps(result, indent=2) + "\n")
        check()  # the last point at which the previous results stay as they were
        for kind in ("rrd", "png", "json"):  # eval.json last: it says the set is complete
            if partial[kind].exists():
                os.replace(partial[kind], paths[kind])
        if recorder is None:
            paths["rrd"].unlink(missing_ok=True)  # an older recording would not match
        if figure is None:
            paths["png"].unlink(missing_ok=True)  # nor an older figure
    except BaseException:
        if recorder is not None:
            recorder.close()
        for path in partial.values():
            path.unlink(missing_ok=True)
        raise
    return result
