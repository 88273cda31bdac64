"""What a new user hit in round five (issue 67): the training ETA while episodes lengthen, on the
log and on a terminal's bar."""

import io
import re

import pytest

from pursuit_bench.cli import progress


def _seconds(text: str) -> int:
    h, m, s = text.split(":")
    return 3600 * int(h) + 60 * int(m) + int(s)


def test_the_eta_of_a_run_whose_episodes_lengthen_is_a_marked_lower_bound_with_how_far_off(monkeypatch) -> None:
    """Episodes that lengthen steadily (the last ten times the first): no rate foresees the
    slowing, so every ETA is short of the time that is left. Each says so (``≥``, a lower bound)
    and by how much the estimates have been off so far, which grows no larger than the truth."""
    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    log = io.StringIO()
    total = 1000
    took = [0.005 * (1 + episode / 111) for episode in range(total)]  # seconds, from 5 ms to 50 ms
    bar = progress.Progress("train", total, 0, lambda: "", every_episodes=50, file=log, eta=True)
    for done in range(1, total + 1):
        clock[0] += took[done - 1]
        bar.update(done)
    found = 0
    for line in log.getvalue().splitlines():
        done = int(line.split("episode ")[1].split("/")[0])
        eta = line.split("| ETA ")[1]
        if done < 200 or done == total:
            continue
        found += 1
        match = re.match(
            r"≥ (\d\d:\d\d:\d\d) \(a lower bound while episodes lengthen: so far they took up to "
            r"([\d.]+)× the time it said\)",
            eta,
        )
        assert match, line
        left = sum(took[done:])
        assert _seconds(match[1]) <= left, line  # a lower bound indeed
        assert 1.1 < float(match[2]) < left / _seconds(match[1]) + 1, line  # off, and by no more than it is
    assert found == 16


def test_a_steady_run_s_eta_is_plain() -> None:
    clock = [0.0]
    log = io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(progress.time, "monotonic", lambda: clock[0])
        bar = progress.Progress("train", 1000, 0, lambda: "", every_episodes=100, file=log, eta=True)
        for done in range(1, 1001):
            clock[0] += 0.1
            bar.update(done)
    etas = [line.split("| ETA ")[1].split(" |")[0] for line in log.getvalue().splitlines()]
    assert not any("≥" in e for e in etas), etas  # never marked
    for done, eta in zip(range(100, 1000, 100), etas, strict=False):
        assert abs(_seconds(eta) - (1000 - done) * 0.1) <= 1, (done, eta)


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_bar_on_a_terminal_shows_this_eta_not_click_s(monkeypatch) -> None:
    """On a terminal the bar carries the same ETA as the log (click's own, the average since the
    start, read 00:00:00 at 17 % of a run with 40 s to go)."""
    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    screen = _Terminal()
    bar = progress.Progress("train", 1000, 0, lambda: "return +0.1", file=screen, eta=True)
    for done in range(1, 401):
        clock[0] += 0.001 if done <= 150 else 0.1  # learning starts at 150: episodes take 100 times longer
        bar.update(done)
    bar.close()
    shown = screen.getvalue()
    assert "ETA after 10% | return +0.1" in shown
    last = shown.split("\r")[-2] if shown.endswith("\n") else shown.split("\r")[-1]
    assert "ETA ≥ " in last and "so far they took up to" in last and "return +0.1" in last, last
    assert not re.search(r"  \d\d:\d\d:\d\d", last), last  # click's own ETA is not shown
