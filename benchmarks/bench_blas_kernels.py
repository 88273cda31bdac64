"""What the OpenBLAS pin costs on this CPU: one run's training at the ``reproduction`` preset with
OpenBLAS's Haswell kernels (the package's pin, ``OPENBLAS_CORETYPE=Haswell``: the same bits on
every x86 CPU since 2013) against another of its kernel sets (``--other``; the default, SkylakeX, is
what OpenBLAS picks by itself on a CPU with AVX-512), in one run of the benchmark, repeats
interleaved.

    python benchmarks/bench_blas_kernels.py [--repeats 5] [--steps 1500] [--other SkylakeX]

Prints, for 1p-high and 3p-high-shared, each setting's transitions/s (medians of ``--repeats``,
one worker process each, timed by its CPU time, every thread pool at one thread) and the ratio,
and the kernels each loaded OpenBLAS reported (threadpoolctl), so that a setting the CPU cannot
run (OpenBLAS then falls back) shows. The pin stays whatever this prints: it keeps a run's bits the
same across machines (docs/departures.md, "Reproducibility across machines").
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_speed import ONE_THREAD, measure  # noqa: E402  (its worker's one-run rate, timed by CPU time)

#: ``python -c KERNELS``: the kernels every loaded OpenBLAS reports once the compiled update's is loaded.
KERNELS = r"""
import json
import pursuit_bench.agents.fused
from threadpoolctl import threadpool_info
print(json.dumps(sorted({i["architecture"] for i in threadpool_info() if i["internal_api"] == "openblas"})))
"""


def rate(coretype: str, condition: str, steps: int) -> float:
    """One run's transitions/s with OpenBLAS's ``coretype`` kernels (``bench_speed``'s worker)."""
    os.environ["OPENBLAS_CORETYPE"] = coretype  # the worker inherits it
    answer = measure(ROOT, "train", condition, "1", str(steps))
    assert isinstance(answer, float)
    return answer


def kernels(coretype: str) -> list[str]:
    env = {**os.environ, **ONE_THREAD, "OPENBLAS_CORETYPE": coretype}
    done = subprocess.run([sys.executable, "-c", KERNELS], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1500, help="env steps timed per measurement")
    parser.add_argument("--other", default="SkylakeX", help="the OpenBLAS kernels measured beside Haswell")
    args = parser.parse_args()
    settings = ("Haswell", args.other)
    print(f"one run alone, reproduction preset, 32 arenas; medians of {args.repeats}, CPU time, one thread")
    print(f"\n| condition | {settings[0]} (transitions/s) | {settings[1]} | {settings[1]} / {settings[0]} |")
    print("|---|---:|---:|---:|")
    for condition in ("1p-high", "3p-high-shared"):
        rates: dict[str, list[float]] = {s: [] for s in settings}
        for _ in range(args.repeats):
            for setting in settings:
                rates[setting].append(rate(setting, condition, args.steps))
        pinned, other = (statistics.median(rates[s]) for s in settings)
        print(f"| {condition} | {pinned:,.0f} | {other:,.0f} | {other / pinned:.2f}x |")
    print()
    for setting in settings:
        print(f"OPENBLAS_CORETYPE={setting}: the loaded OpenBLAS libraries report {', '.join(kernels(setting))}")


if __name__ == "__main__":
    main()
