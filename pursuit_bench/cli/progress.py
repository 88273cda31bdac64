"""Progress of a long command: on a terminal, a bar; anywhere else (a log file, a cluster job),
a line every so many episodes or seconds, whichever comes first, so that a log shows how far a
run got and how it was doing.
"""

from __future__ import annotations

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
        eta = ""
        if self.eta and rate > 0:  # by episodes: the ETA of one run (a sweep's describe() gives its own)
            eta = f" | ETA {time.strftime('%H:%M:%S', time.gmtime((self.total - self._done) / rate))}"
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
