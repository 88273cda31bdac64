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
    adds the time left at the recent rate to each log line (and to the bar, in place of click's)."""

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
        if self.file.isatty():  # with an ETA, ours in the bar's text: click's own is the average since the start
            self._bar = click.progressbar(
                length=total, label=label, file=self.file, item_show_func=lambda item: item, show_eta=not eta
            ).__enter__()
            self._bar.update(done)
        self._done = done
        self._start, self._start_done = time.monotonic(), done
        self._last_time, self._last_done = self._start, done
        #: (time, episodes done) from the first episode finished on: the time before it (imports,
        #: compiling the kernels) is no episode's. Thinned to about 50 points a window; two windows kept.
        self._points: collections.deque[tuple[float, int]] = collections.deque()
        #: (time, episodes done, episodes a second) of the estimates given, as the points: kept to
        #: say how far they have been off (:meth:`_off`).
        self._estimates: collections.deque[tuple[float, int, float]] = collections.deque()

    #: No ETA before this share of what is left at the start is done; the rate is that of the
    #: most recent such share of the work (the window).
    ETA_AFTER = 0.1
    #: The ETA is a floor (``≥``) when the window's rate is below this share of the window before's.
    SLOWING = 0.9

    @property
    def _window(self) -> float:
        return max(self.ETA_AFTER * (self.total - self._start_done), 1.0)

    def _rate_to(self, end: tuple[float, int]) -> tuple[float, tuple[float, int]] | None:
        """Episodes a second over the window that ends at ``end`` (from the last point a window or
        more before it, else the first point), and where that window starts; None without one."""
        t1, d1 = end
        start = next((p for p in reversed(self._points) if p[1] <= d1 - self._window), self._points[0])
        if start[1] >= d1:
            return None
        return (d1 - start[1]) / max(t1 - start[0], 1e-9), start

    def _rate(self) -> tuple[float, tuple[float, int]] | None:
        """The rate the ETA goes by now (the most recent window's) and where its window starts;
        None before a tenth of the work is done or without one."""
        if self._done - self._start_done < self.ETA_AFTER * (self.total - self._start_done) or not self._points:
            return None
        recent = self._rate_to(self._points[-1])
        return None if recent is None or recent[0] <= 0 else recent

    def _off(self, now: float) -> float:
        """How many times the time the estimates kept said the episodes since would take those
        episodes have taken, at most (1 with none far enough back to judge): above 1, the ETA has
        been too short."""
        ratios = [
            (now - t) * rate / (self._done - d) for t, d, rate in self._estimates if self._done - d >= self._window / 5
        ]
        return max(ratios, default=1.0)

    def _eta(self, now: float) -> str:
        """What is left at the rate of the most recent tenth of the work (not the average since the
        start, which the start-up and the early short episodes distort). While episodes lengthen (as
        the agents learn, or once learning starts) no rate foresees it: then the ETA is marked a
        lower bound (``≥``), when the window's rate is below that of the window before or when the
        estimates of the last two windows have proved short, with the most they have been off; or
        when one will be given."""
        if self._done - self._start_done < self.ETA_AFTER * (self.total - self._start_done):
            return f"after {self.ETA_AFTER:.0%}"
        recent = self._rate()
        if recent is None:
            return "?"
        rate, start = recent
        left = time.strftime("%H:%M:%S", time.gmtime((self.total - self._done) / rate))
        before = self._rate_to(start)
        off = self._off(now)
        if off > 1 / self.SLOWING:
            lower = "a lower bound while episodes lengthen"
            return f"≥ {left} ({lower}: so far they took up to {off:.1f}× the time it said)"
        if before is not None and rate < self.SLOWING * before[0]:
            return f"≥ {left} (a lower bound while episodes lengthen)"
        return left

    def update(self, done: int) -> None:
        now, previous = time.monotonic(), self._done
        self._done = done
        if self.eta and (not self._points or done - self._points[-1][1] >= self._window / 50):
            self._points.append((now, done))
            while len(self._points) > 2 and done - self._points[1][1] >= 2 * self._window:
                self._points.popleft()  # kept: two windows back, and the point before
            if (recent := self._rate()) is not None:
                self._estimates.append((now, done, recent[0]))
            while self._estimates and done - self._estimates[0][1] >= 2 * self._window:
                self._estimates.popleft()
        if self._bar is not None:
            text = f"ETA {self._eta(now)} | {self.describe()}" if self.eta else self.describe()
            self._bar.update(done - previous, current_item=text)
            return
        if done - self._last_done >= self.every_episodes or now - self._last_time >= self.every_seconds:
            self._line(now)

    def _line(self, now: float) -> None:
        rate = (self._done - self._start_done) / max(now - self._start, 1e-9)
        eta = ""
        if self.eta:  # by episodes: the ETA of one run (a sweep's describe() gives its own)
            eta = f" | ETA {self._eta(now)}"
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
