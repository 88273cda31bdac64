"""Stopping cleanly on SIGINT or SIGTERM (what a terminal's Ctrl-C, ``timeout``, Slurm,
Kubernetes and Ray send): a loop checks a flag between steps, or a :class:`Stopped` exception
is raised where the program is."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator
from typing import Any

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

    def check(self) -> None:
        """Raise :class:`Stopped` if a signal has arrived: a safe point of the caller's choosing."""
        if self.signum is not None:
            raise Stopped(self.signum)

    @contextlib.contextmanager
    def active(self) -> Iterator[SignalCatcher]:
        """Catch the signals while the block runs; then the handlers it found (or those the
        block set) are back."""
        previous = {s: signal.signal(s, self._handle) for s in STOP_SIGNALS}
        try:
            yield self
        finally:
            for s, handler in previous.items():
                if signal.getsignal(s) == self._handle:  # the block may have set its own
                    signal.signal(s, handler)
