"""How long the command line takes to refuse bad input, beside ``pursuit-bench --help`` (the
interpreter and click: the floor any command pays), in one run: a busy run folder, a folder
holding another run, a missing run for ``eval`` and ``report``, a folder that is no sweep for
``pool``. Each figure is the median of ``--repeats`` runs of the command as a process of its own.
The README's claim is that a refusal needing no torch comes before torch is imported: well under
a second on an idle machine.

    python benchmarks/bench_refusals.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pursuit_bench.io.files import locked


def seconds(args: list[str], repeats: int, expect: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "pursuit_bench.cli.main", *args], capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if done.returncode != expect:
            raise SystemExit(f"{args}: exit {done.returncode}, expected {expect}: {done.stderr.strip()}")
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    repeats = parser.parse_args().repeats
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "run"
        tiny = ["--episodes", "2", "--no-record", "--num-envs", "2"]
        command = [sys.executable, "-m", "pursuit_bench.cli.main", "train", "--condition", "1p-low", "--out", str(run)]
        subprocess.run([*command, *tiny], check=True, capture_output=True)
        cases = {
            "--help (the floor)": (["--help"], 0),
            "train into a folder holding another run": (["train", "--condition", "1p-high", "--out", str(run)], 2),
            "eval a missing run": (["eval", str(Path(tmp) / "missing")], 2),
            "report a missing folder": (["report", str(Path(tmp) / "missing")], 2),
            "pool on a folder that is no sweep": (["pool", str(run), "--out", str(Path(tmp) / "pool")], 2),
        }
        figures = {name: seconds(args, repeats, code) for name, (args, code) in cases.items()}
        with locked(run):  # held here: the commands meet a busy folder
            figures["eval a busy run"] = seconds(["eval", str(run)], repeats, 2)
            figures["train --resume a busy run"] = seconds(["train", "--out", str(run), "--resume"], repeats, 2)
    floor = figures["--help (the floor)"]
    print(f"| refusal | median seconds ({repeats} runs) | × --help |\n|---|---:|---:|")
    for name, value in figures.items():
        print(f"| {name} | {value:.2f} | {value / floor:.2f} |")


if __name__ == "__main__":
    main()
