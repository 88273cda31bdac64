"""The evaluated episodes as movement datasets (``eval --tracks``): a folder of netCDF files, one
per episode (``episode-0001.nc`` …), each a poses dataset of :mod:`pursuit_bench.io.tracks` with
the episode's number, the condition and how it ended in its attributes. The trained variant's
episodes, as eval.rrd and eval.csv hold them."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pursuit_bench.env.world import DT
from pursuit_bench.io import tracks

if TYPE_CHECKING:
    from pursuit_bench.trajectories.recording import EpisodeTrace


class MovementTracks:
    """Collects episodes (as a recorder hears them) and writes one file each into ``folder`` on
    :meth:`close` (the folder made then)."""

    def __init__(self, folder: Path, agent_names: list[str], condition: str) -> None:
        self.folder, self.names, self.condition = folder, list(agent_names), condition
        self._episodes: dict[int, EpisodeTrace] = {}

    def log_episode(self, episode: int, trace: EpisodeTrace) -> None:
        self._episodes[episode] = trace

    def close(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)
        self.folder.mkdir(parents=True)
        width = max(4, len(str(max(self._episodes, default=0))))
        for episode in sorted(self._episodes):
            trace = self._episodes[episode]
            captured = bool(np.asarray(trace.captured).any())
            ended = "captured" if captured else "time limit" if trace.truncated else "wall"
            dataset = tracks.episode_dataset(
                trace.positions,
                trace.modes,
                self.names,
                fps=1 / DT,
                attrs={"episode": episode, "condition": self.condition, "ended": ended, "steps": trace.length},
            )
            tracks.write(dataset, self.folder / f"episode-{episode:0{width}d}.nc")
