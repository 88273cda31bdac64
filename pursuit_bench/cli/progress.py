"""Progress of a long command, and stopping it cleanly on SIGINT or SIGTERM.

On a terminal, a bar; anywhere else (a log file, a cluster job), a line every so many
episodes or seconds, whichever comes first, so a log shows how far a run got and how it was
doing.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any, TextIO

import click

#: Exit status of a command stopped by a signal: 128 + its number (130 for SIGINT, 143 for SIGTERM).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Stopped(Exception):
    """A SIGINT or SIGTERM arrived (raised only where the caller asked for it)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


class SignalCatcher:
    """While active, SIGINT and SIGTERM are caught. ``raise_at_once=False`` only records them
    (``signum``) for a loop to check between steps, so that nothing is cut in the middle;
    ``True`` raises :class:`Stopped` where the program is."""

    def __init__(self, raise_at_once: bool) -> None:
        self.raise_at_once = raise_at_once
        self.signum: int | None = None

    def _handle(self, signum: int, frame: Any) -> None:
        if self.signum is None:
            self.signum = signum
            if self.raise_at_once:
                raise Stopped(signum)

    @contextlib.contextmanager
    def active(self) -> Iterator[SignalCatcher]:
        previous = {s: signal.signal(s, self._handle) for s in STOP_SIGNALS}
        try:
            yield self
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)


class Progress:
    """``update(done)`` as episodes finish; ``describe()`` gives the figures to show."""

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
    ) -> None:
        self.label, self.total, self.describe = label, total, describe
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
        click.echo(
            f"{self.label}: episode {self._done}/{self.total} ({self._done / self.total:.0%}) | "
            f"{rate:.1f} episodes/s | {self.describe()}",
            file=self.file,
        )
        self._last_time, self._last_done = now, self._done

    def close(self) -> None:
        if self._bar is not None:
            self._bar.__exit__(None, None, None)
        elif self._done != self._last_done:
            self._line(time.monotonic())
