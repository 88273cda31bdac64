"""The robustness study (docs/robustness.md): its tables and figure from the committed result.

    pursuit-bench robust sweeps/repro1000 sweeps/repro1000-flat --seeds 5 \\
        --conditions 1p-high,2p-high-individual,2p-low-shared,3p-high-shared --out sweeps/robust
    python scripts/robustness_study.py --export sweeps/robust   # once: results/robustness/robust.json.gz
    python scripts/robustness_study.py                          # tables (printed) and docs/figures/robustness.png

The committed file holds every evaluation (per run and rung, and cross-play); the summaries are
recomputed from them (``robustness.resummarised``), not read back.
"""

from __future__ import annotations

import argparse
import gzip
import json
from pathlib import Path
from typing import Any

from pursuit_bench.io.files import atomic_write_bytes
from pursuit_bench.study import robustness
from pursuit_bench.study.plots import robust_png

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / "results" / "robustness" / "robust.json.gz"
FIGURE = ROOT / "docs" / "figures" / "robustness.png"


def load() -> dict[str, Any]:
    """The committed study, its summaries recomputed from its evaluations."""
    return robustness.resummarised(json.loads(gzip.decompress(RESULT.read_bytes())))


def tables(result: dict[str, Any]) -> str:
    return robustness.markdown(result) + "\n" + robustness.chase_markdown(result)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--export", type=Path, default=None, help="A robust output folder to commit (its robust.json).")
    args = parser.parse_args()
    if args.export is not None:
        raw = json.loads((args.export / "robust.json").read_text())
        atomic_write_bytes(RESULT, gzip.compress(json.dumps(raw, separators=(",", ":")).encode(), mtime=0))
        print(f"{RESULT}: {RESULT.stat().st_size / 1e3:.0f} kB")
        return
    result = load()
    atomic_write_bytes(FIGURE, robust_png(result))
    print(tables(result))


if __name__ == "__main__":
    main()
