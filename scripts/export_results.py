"""Write a sweep's results compactly into the repository (``results/<name>/``), from which
``pursuit-bench report`` makes every table and figure of REPRODUCTION.md again without the run
folders (``tests/test_reproduction.py`` checks it).

    python scripts/export_results.py sweeps/repro1000 sweeps/repro1000-flat \\
        --out results/reproduction --command "pursuit-bench sweep ..."

Per run: its evaluations (final and kept checkpoints) with every episode's return and the prey
checks, its learning curve in 100 blocks, its configuration; gzip-compressed JSON.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pursuit_bench.reports import reproduction as report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sweeps", type=Path, nargs="+", help="Sweep folders (their evaluated runs).")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--command", action="append", default=[], help="A command that made the sweeps.")
    args = parser.parse_args()
    results = [r for sweep in args.sweeps for r in report.collect(sweep)]
    plans = {str(s): json.loads((s / "sweep.json").read_text())["plan"] for s in args.sweeps}
    size = report.export(results, args.out, {"commands": args.command, "plans": plans})
    print(f"{len(results)} runs, {size / 1e6:.2f} MB in {args.out}")


if __name__ == "__main__":
    main()
