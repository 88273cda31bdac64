"""What the studies' drivers share (studies/rule-value, residual-value, budget): the progress
log, the build a study runs on (the commit and a fingerprint of the package's code, refused while
the package has uncommitted code), the check that a work folder's runs are one build's, the
stop flag SIGTERM and SIGINT raise, and a sweep of training runs driven to its end or to a stop.

A driver imports it with this folder, which holds it alone, on ``sys.path`` (the studies' own
folder would not do: its sub-folders would shadow packages of those names, ``coverage``)::

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))
    import driver

It imports nothing of the package at its top: a driver may run on a pinned build (its package
first on ``PYTHONPATH``), and what it imports from the package, here included, is that build's.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import resource
import signal
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any


def log(work: Path, line: str) -> None:
    """Print ``line`` stamped with the UTC time and append it to ``work/progress.log``."""
    stamped = f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M:%S} {line}"
    print(stamped, flush=True)
    with (work / "progress.log").open("a") as file:
        file.write(stamped + "\n")


def git(root: Path, *args: str) -> str:
    """``git ARGS`` in ``root``: its standard output (CalledProcessError if it fails)."""
    return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True, check=True).stdout


def committed_package(root: Path) -> tuple[str, str]:
    """The commit of the checkout ``root`` and git's listing of its package (``ls-files -s``: a
    line per file with its blob's hash). SystemExit if the package has uncommitted .py changes:
    no run is trained or judged by code that no commit holds."""
    status = git(root, "status", "--porcelain", "--", "pursuit_bench")
    changed = [line for line in status.splitlines() if line.endswith(".py")]
    if changed:
        raise SystemExit(
            f"{root}: the package has uncommitted code changes ({changed[0].strip()} …): commit them first"
        )
    return git(root, "rev-parse", "HEAD").strip(), git(root, "ls-files", "-s", "--", "pursuit_bench")


def code_fingerprint(listed: str) -> str:
    """The fingerprint of a package's tracked .py files from :func:`committed_package`'s listing:
    unchanged by committing results or weights, changed by any edit of its code."""
    return hashlib.sha256("\n".join(x for x in listed.splitlines() if x.endswith(".py")).encode()).hexdigest()[:16]


def check_started(work: Path, current: dict[str, str], advice: str = "not mixed") -> None:
    """``work/study.json``: written with ``current`` (a build: ``commit``, ``code``) at a work
    folder's first start, then required to hold the same ``code``: SystemExit otherwise, with
    ``advice`` (what to do), so that a folder's runs are never trained by two builds."""
    path = work / "study.json"
    if not path.exists():
        path.write_text(json.dumps(current, indent=2) + "\n")
        return
    started = json.loads(path.read_text())
    if started["code"] != current["code"]:
        raise SystemExit(
            f"{path}: the study started with other code (commit {started['commit'][:10]}, fingerprint "
            f"{started['code']}); now {current['commit'][:10]} ({current['code']}): {advice}"
        )


def stop_flag(work: Path) -> list[bool]:
    """A flag (``flag[0]``) that SIGTERM and SIGINT set from now on (the first said in the log),
    for a driver to stop at its next safe point; the sweep's workers checkpoint and stop as they
    see it."""
    flag = [False]

    def heard(signum: int, frame: Any) -> None:
        first, flag[0] = not flag[0], True
        if first:
            log(work, f"signal {signum}: stopping at the next safe point (checkpoints kept)")

    signal.signal(signal.SIGTERM, heard)
    signal.signal(signal.SIGINT, heard)
    return flag


def child_cpu() -> float:
    """CPU seconds of this process's ended children (a sweep's workers, once joined)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def sweep(
    work: Path,
    folder: Path,
    plan: Any,
    workers: int,
    stop: list[bool],
    *,
    finished: Callable[[str], None] | None = None,
    progress_every: int | None = None,
    episodes: dict[str, int] | None = None,
) -> bool:
    """Train ``plan``'s runs (a ``SweepPlan``) in ``folder`` on ``workers`` processes, resuming
    what is there, until all are done or ``stop[0]``; whether all are done. Logs each run as it
    ends and calls ``finished(name)`` then; with ``progress_every``, a line per run at its first
    episode and every that many episodes, and ``episodes`` (if given) keeps each run's last
    episode heard of."""
    from pursuit_bench.training.sweep import open_sweep, run_sweep

    note = open_sweep(folder, plan)
    if note:
        log(work, note)
    episodes = {} if episodes is None else episodes

    def heard(kind: str, name: str, value: Any) -> None:
        if kind == "done":
            log(work, f"trained {name}")
            if finished is not None:
                finished(name)
        elif kind == "episode" and progress_every:
            if not episodes.get(name):
                log(work, f"{name}: training from episode {value}")
            elif value % progress_every == 0:
                log(work, f"{name}: {value} episodes")
            episodes[name] = value

    return run_sweep(folder, plan, workers=workers, record=False, on_message=heard, should_stop=lambda: stop[0])
