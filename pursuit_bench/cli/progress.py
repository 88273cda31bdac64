"""Progress of a long command: on a terminal, a bar; anywhere else (a log file, a cluster job),
a line every so many episodes or seconds, whichever comes first, so that a log shows how far a
run got and how it was doing.
"""

from __future__ import annotations

import collections
import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

import click


class Progress:
    """``update(done)`` as episodes finish; ``describe()`` gives the figures to show; ``eta``
    adds the time left at the rate so far to each log line."""

    def __init__(
        self,
        label: str,
        total: int,
        done: int,
        describe: Callable[[], str],
        *,
        every_episodes: int = 100,
        every_seconds: float = 60.0,
        file: TextIO | None = None,
        eta: bool = False,
    ) -> None:
        self.label, self.total, self.describe, self.eta = label, total, describe, eta
        self.every_episodes, self.every_seconds = every_episodes, every_seconds
        self.file = file or sys.stderr
        self._bar: Any = None
        if self.file.isatty():
            self._bar = click.progressbar(
                length=total, label=label, file=self.file, item_show_func=lambda item: item
            ).__enter__()
            self._bar.update(done)
        self._done = done
        self._start, self._start_done = time.monotonic(), done
        self._last_time, self._last_done = self._start, done
        self._history: collections.deque[tuple[float, int]] = collections.deque([(self._start, done)])

    #: No ETA before this share of what is left at the start is done: episodes grow longer as the
    #: agents learn (a prey that survives), so the first episodes' rate promises far too much.
    ETA_AFTER = 0.1

    def _eta(self) -> str:
        """The time left at the rate of the most recent tenth of the work (not the average since
        the start, which early short episodes flatter), or when one will be given."""
        work = self.total - self._start_done
        if self._done - self._start_done < self.ETA_AFTER * work:
            return f"after {self.ETA_AFTER:.0%}"
        (t0, d0), (now, _) = self._history[0], self._history[-1]  # the window's start (see _line)
        rate = (self._done - d0) / max(now - t0, 1e-9)
        return time.strftime("%H:%M:%S", time.gmtime((self.total - self._done) / rate)) if rate > 0 else "?"

    def update(self, done: int) -> None:
        if self._bar is not None:
            self._bar.update(done - self._done, current_item=self.describe())
            self._done = done
            return
        self._done = done
        now = time.monotonic()
        if done - self._last_done >= self.every_episodes or now - self._last_time >= self.every_seconds:
            self._line(now)

    def _line(self, now: float) -> None:
        rate = (self._done - self._start_done) / max(now - self._start, 1e-9)
        self._history.append((now, self._done))
        window = self.ETA_AFTER * (self.total - self._start_done)
        while len(self._history) > 2 and self._done - self._history[0][1] > window:
            self._history.popleft()  # kept: the lines within the last tenth of the work, or the one before
        eta = ""
        if self.eta:  # by episodes: the ETA of one run (a sweep's describe() gives its own)
            eta = f" | ETA {self._eta()}"
        click.echo(
            f"{self.label}: episode {self._done}/{self.total} ({self._done / self.total:.0%}) | "
            f"{rate:.1f} episodes/s{eta} | {self.describe()}",
            file=self.file,
        )
        self._last_time, self._last_done = now, self._done

    def close(self) -> None:
        if self._bar is not None:
            self._bar.__exit__(None, None, None)
        elif self._done != self._last_done:
            self._line(time.monotonic())
