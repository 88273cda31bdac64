"""The leaderboard's flat and residual predator rows: one run of each kind in each 1-predator
condition (its prey learning beside it, as every learned run here), at the ``reproduction``
preset, 15,000 episodes, seed 0, and the agent modules that play them (``flat(condition=…)``,
``residual(condition=…)``: the run's predator of the condition it is asked to play). The shipped
agents, which the hierarchical row plays, are one run of each condition too (the median seed).

    python studies/leaderboard/learned_leaderboard.py        # trains runs/leaderboard/<kind>-<condition>/
    pursuit-bench score studies.leaderboard.learned_leaderboard:flat --role predator --conditions 1p-high,1p-low …

The run folders are generated files (not in git): the command above makes them again, bit for bit
on one machine.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path
from typing import Any

FOLDER = Path("runs/leaderboard")
CONDITIONS = ("1p-high", "1p-low")
KINDS = ("flat", "residual")
EPISODES = 15_000
SEED = 0


def _predator(kind: str, condition: str) -> Any:
    from pursuit_bench.training.runs import load_agents

    folder = FOLDER / f"{kind}-{condition}"
    if not (folder / "checkpoint.pt").is_file():
        raise FileNotFoundError(f"{folder}: no {kind} run for {condition}; train it first (python {__file__})")
    return load_agents(folder)["predator_0"]


def flat(condition: str) -> Any:
    """The flat predator trained in ``condition`` (the score command passes the condition it plays)."""
    return _predator("flat", condition)


def residual(condition: str) -> Any:
    """The residual predator trained in ``condition``."""
    return _predator("residual", condition)


def main() -> None:
    FOLDER.mkdir(parents=True, exist_ok=True)
    for kind in KINDS:
        for condition in CONDITIONS:
            start = time.monotonic()
            out = FOLDER / f"{kind}-{condition}"
            command = [
                *(sys.executable, "-c", "from pursuit_bench.cli.entry import main; main()", "train"),
                *("--condition", condition, "--predator", kind, "--preset", "reproduction"),
                *("--episodes", str(EPISODES), "--seed", str(SEED), "--no-record", "--out", str(out), "--force"),
            ]
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
            print(f"{kind} {condition}: {EPISODES} episodes in {time.monotonic() - start:.0f} s -> {out}")


if __name__ == "__main__":
    main()
