"""The first evaluation from a fresh install, with numba's cache cold and then warm (issue 50
item 13): ``pursuit-bench eval --pretrained 1p-high`` timed from the command line, the first time
with an empty ``NUMBA_CACHE_DIR`` (every kernel compiles, as after a fresh install) and then
``--repeats`` times with the cache it left (every kernel loads).

    python benchmarks/bench_first_eval.py [--episodes 1000] [--repeats 2] [--out FILE]

Prints the seconds of each, and with ``--out`` writes them as JSON. Every kernel of the package
is compiled with ``cache=True``; this measures what that saves.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def timed_eval(cache: Path, scratch: Path, episodes: int) -> float:
    """Wall seconds of one ``pursuit-bench eval --pretrained 1p-high`` with numba's cache in ``cache``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": str(ROOT)}
    command = [sys.executable, "-m", "pursuit_bench.cli.main", "eval", "--pretrained", "1p-high"]
    command += ["--episodes", str(episodes), "--no-record", "--out", str(scratch / "out")]
    start = time.perf_counter()
    subprocess.run(command, env=env, cwd=scratch, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=1000, help="evaluation episodes per variant")
    parser.add_argument("--repeats", type=int, default=2, help="evaluations with the warm cache")
    parser.add_argument("--out", type=Path, help="write the seconds here as JSON")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        scratch = Path(folder)
        cache = scratch / "numba-cache"
        cold = timed_eval(cache, scratch, args.episodes)
        warm = [timed_eval(cache, scratch, args.episodes) for _ in range(args.repeats)]
    result = {"episodes": args.episodes, "cold_cache_s": cold, "warm_cache_s": warm}
    print(
        f"first evaluation, {args.episodes} episodes a variant: {cold:.1f} s with numba's cache cold, "
        f"{', '.join(f'{w:.1f}' for w in warm)} s warm"
    )
    if args.out is not None:
        args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
