"""Many evaluations, each kept in its own file as it finishes, spread over worker processes: what
``pursuit-bench robust`` and ``pursuit-bench pool`` run. A rerun reads the kept files whose stamp
(episodes, seed, …) matches and does only the rest, so an interrupted study goes on where it
stopped; every file is written whole (:func:`~pursuit_bench.io.files.atomic_write_text`).
"""

from __future__ import annotations

import concurrent.futures
import json
import multiprocessing
from collections.abc import Callable
from pathlib import Path
from typing import Any


def file_name(key: str) -> str:
    """A job's key as a file name (``|`` and ``=`` are kept out of names)."""
    return key.replace("|", "__").replace("=", "-")


def run_jobs(
    jobs: list[tuple[str, tuple[Any, ...]]],
    work: Callable[..., dict[str, Any]],
    parts: Path,
    stamp: dict[str, Any],
    *,
    workers: int = 1,
    progress: Callable[[int, int], None] = lambda done, total: None,
) -> dict[str, dict[str, Any]]:
    """``work(*args)`` for every ``(key, args)`` of ``jobs``, each result kept in
    ``parts/<key>.json`` with ``stamp``; results already kept with the same stamp are read, not
    redone. ``work`` must be a module-level function (workers are spawned). Returns the results
    by key."""
    from pursuit_bench.io.files import atomic_write_text

    done: dict[str, dict[str, Any]] = {}
    for key, _ in jobs:
        path = parts / f"{file_name(key)}.json"
        if path.exists():
            saved = json.loads(path.read_text())
            if all(saved.get(k) == v for k, v in stamp.items()):
                done[key] = saved["result"]
    todo = [(key, args) for key, args in jobs if key not in done]
    progress(len(done), len(jobs))

    def keep(key: str, result: dict[str, Any]) -> None:
        parts.mkdir(parents=True, exist_ok=True)  # made with the first result: a failed start leaves no folder
        atomic_write_text(parts / f"{file_name(key)}.json", json.dumps({**stamp, "result": result}) + "\n")
        done[key] = result
        progress(len(done), len(jobs))

    if workers == 1 or len(todo) <= 1:
        for key, args in todo:
            keep(key, work(*args))
    elif todo:  # a pool that notices a worker dying (BrokenProcessPool) rather than waiting on it
        context = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(min(workers, len(todo)), mp_context=context) as pool:
            futures = {pool.submit(work, *args): key for key, args in todo}
            try:
                for future in concurrent.futures.as_completed(futures):
                    keep(futures[future], future.result())
            except BaseException:  # a failed evaluation: what finished is kept, nothing more is started
                pool.shutdown(wait=True, cancel_futures=True)
                raise
    return done
