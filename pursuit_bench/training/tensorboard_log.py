"""Training's per-episode scalars as TensorBoard event files (``train --tensorboard DIR``), through
torch's own writer (:class:`torch.utils.tensorboard.SummaryWriter`, which needs the ``tensorboard``
package: the ``tensorboard`` extra).

Each episode's row of ``metrics.jsonl`` becomes one scalar per column at the episode's number as
the step: ``return/<agent>``, ``chase_fraction/<predator>``, ``loss/<learner>``, ``epsilon``,
``beta``, ``length`` and ``captured`` (1 or 0), so TensorBoard groups them by the part before the
slash. A resumed run retrains the episodes after its checkpoint: the writer purges the steps from
there, so each episode is shown once."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pursuit_bench.training.train import EpisodeRecord


class TensorBoardLog:
    """The event files of one run in ``folder`` (TensorBoard's log dir for it).

    ``episodes_done``: the episodes the run has behind it (its checkpoint's); events of later
    episodes, written before a process was stopped, are purged as the new ones come."""

    def __init__(self, folder: Path, episodes_done: int = 0) -> None:
        import tensorboard  # noqa: F401  # the writer's own message for a missing package is an ImportError
        from torch.utils.tensorboard import SummaryWriter

        self.folder = folder
        self._writer = SummaryWriter(log_dir=str(folder), purge_step=episodes_done + 1 if episodes_done else None)

    def write(self, record: EpisodeRecord) -> None:
        """One finished episode's scalars at its number."""
        for key, value in record.as_row().items():
            if key != "episode":
                self._writer.add_scalar(key, float(value), record.episode)

    def close(self) -> None:
        """Flush and close the event file."""
        self._writer.close()
