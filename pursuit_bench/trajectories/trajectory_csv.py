"""The evaluated episodes' trajectories as one CSV file (``eval --csv``): a row per agent and
step, the column names carrying their units, readable by any spreadsheet, pandas or R.

Columns: ``episode`` (from 1, as eval.rrd numbers them), ``step`` (0 is the start state, then
each step's end), ``time_s`` (step × 0.1 s), ``agent`` (predator_0 …, prey_0), ``role``,
``x_arena`` and ``y_arena`` (the position in arena units: the square arena spans −1 to 1 on each
axis, a disk's radius is 0.05), ``vx_arena_per_s`` and ``vy_arena_per_s`` (the velocity over the
step, the position's change divided by 0.1 s: the world's velocity after the step for a disk
that touched nothing; 0 at the start, where every disk is at rest), ``mode`` (a predator's mode
in the step: ``chase`` or ``stalk``; empty for the prey and at step 0), ``reward`` (received
after the step; empty at step 0), ``wall`` (1 when touching a wall at the step's end) and
``captured`` (1 when a predator overlaps the prey at the step's end; for the prey, when any does).

The episodes are the trained variant's, in the order of their numbers (the file is written when
the evaluation ends, under a temporary name, with the other files)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pursuit_bench.env.world import DT

if TYPE_CHECKING:
    from pursuit_bench.trajectories.recording import EpisodeTrace

COLUMNS = (
    "episode",
    "step",
    "time_s",
    "agent",
    "role",
    "x_arena",
    "y_arena",
    "vx_arena_per_s",
    "vy_arena_per_s",
    "mode",
    "reward",
    "wall",
    "captured",
)
MODES = ("stalk", "chase")


class TrajectoryCSV:
    """Collects episodes (``log_episode``, as a recorder hears them) and writes them to ``path``
    on :meth:`close`."""

    def __init__(self, path: Path, agent_names: list[str]) -> None:
        self.path, self.names = path, list(agent_names)
        self._episodes: dict[int, EpisodeTrace] = {}

    def log_episode(self, episode: int, trace: EpisodeTrace) -> None:
        self._episodes[episode] = trace

    def close(self) -> None:
        """Write every episode heard, in the order of their numbers."""
        with self.path.open("w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(COLUMNS)
            for episode in sorted(self._episodes):
                writer.writerows(episode_rows(episode, self._episodes[episode], self.names))


def episode_rows(episode: int, trace: EpisodeTrace, names: list[str]) -> list[list[object]]:
    """One episode's rows: step by step, each agent in ``names`` order."""
    positions = np.asarray(trace.positions, dtype=float)  # (T + 1, n, 2)
    velocities = np.zeros_like(positions)
    velocities[1:] = np.diff(positions, axis=0) / DT
    n_predators = len(names) - 1
    any_capture = np.asarray(np.asarray(trace.captured, dtype=bool).any(axis=1))
    rows: list[list[object]] = []
    for step in range(len(positions)):
        for k, name in enumerate(names):
            predator = k < n_predators
            after = step - 1  # the index of the step that ended here
            mode = MODES[int(trace.modes[after, k])] if predator and step else ""
            reward = repr(float(trace.rewards[after, k])) if step else ""
            wall = int(trace.wall[after, k]) if step else 0
            caught = int(trace.captured[after, k] if predator else any_capture[after]) if step else 0
            rows.append(
                [
                    episode,
                    step,
                    repr(round(step * DT, 10)),
                    name,
                    "predator" if predator else "prey",
                    repr(float(positions[step, k, 0])),
                    repr(float(positions[step, k, 1])),
                    repr(float(velocities[step, k, 0])),
                    repr(float(velocities[step, k, 1])),
                    mode,
                    reward,
                    wall,
                    caught,
                ]
            )
    return rows
