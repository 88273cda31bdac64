"""The robustness study (docs/robustness.md): its tables and figure from the committed result.

    pursuit-bench robust sweeps/repro1000 sweeps/repro1000-flat --seeds 5 \\
        --conditions 1p-high,2p-high-individual,2p-low-shared,3p-high-shared --out sweeps/robust
    python studies/robustness/robustness_study.py --export sweeps/robust   # once: results/robustness/robust.json.gz
    python studies/robustness/robustness_study.py  # tables (printed) and docs/figures/robustness.png
    python studies/robustness/robustness_study.py --doc                    # the tables written into docs/robustness.md

The committed file holds every evaluation (per run and rung, and cross-play); the summaries and
the tests (``robustness.families``: each family corrected by Holm) are recomputed from them
(``robustness.resummarised``), not read back. In docs/robustness.md each table stands between
``<!-- generated: NAME ... -->`` and ``<!-- end generated: NAME -->``, NAME one of
``robustness.sections``; ``--doc`` rewrites what stands between, and
``tests/test_robustness.py`` checks that it is what this script gives.
"""

from __future__ import annotations

import argparse
import gzip
import json
import re
from pathlib import Path
from typing import Any

from pursuit_bench.analysis import robustness
from pursuit_bench.figures.plots import robust_png
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

ROOT = Path(__file__).resolve().parents[2]
RESULT = ROOT / "results" / "robustness" / "robust.json.gz"
FIGURE = ROOT / "docs" / "figures" / "robustness.png"
DOC = ROOT / "docs" / "robustness.md"
COMMAND = "python studies/robustness/robustness_study.py --doc"
#: A generated block of the doc: its name, then the table as :func:`robustness.sections` gives it.
BLOCK = re.compile(r"<!-- generated: (?P<name>[\w-]+) .*?-->\n(?P<body>.*?)<!-- end generated: (?P=name) -->", re.S)


def load() -> dict[str, Any]:
    """The committed study, its summaries and tests recomputed from its evaluations."""
    return robustness.resummarised(json.loads(gzip.decompress(RESULT.read_bytes())))


def tables(result: dict[str, Any]) -> str:
    """Every table of the study, as robust.md holds them."""
    return robustness.markdown(result)


def blocks(text: str) -> dict[str, str]:
    """The generated blocks of a doc, by name (ValueError where a name is given twice)."""
    found: dict[str, str] = {}
    for match in BLOCK.finditer(text):
        if match["name"] in found:
            raise ValueError(f"{DOC.name}: the generated block {match['name']!r} is given twice")
        found[match["name"]] = match["body"]
    return found


def written(text: str, result: dict[str, Any]) -> str:
    """``text`` with each generated block replaced by the table it names; ValueError unless the
    blocks are exactly :func:`robustness.sections`' names."""
    fresh = robustness.sections(result)
    if set(blocks(text)) != set(fresh):
        raise ValueError(f"{DOC.name}: generated blocks {sorted(blocks(text))}, expected {sorted(fresh)}")

    def block(match: re.Match[str]) -> str:
        name = match["name"]
        return f"<!-- generated: {name} by {COMMAND} -->\n{fresh[name]}<!-- end generated: {name} -->"

    return BLOCK.sub(block, text)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--export", type=Path, default=None, help="A robust output folder to commit (its robust.json).")
    parser.add_argument("--doc", action="store_true", help=f"Write the tables into {DOC.relative_to(ROOT)}.")
    args = parser.parse_args()
    if args.export is not None:
        raw = json.loads((args.export / "robust.json").read_text())
        atomic_write_bytes(RESULT, gzip.compress(json.dumps(raw, separators=(",", ":")).encode(), mtime=0))
        print(f"{RESULT}: {RESULT.stat().st_size / 1e3:.0f} kB")
        return
    result = load()
    if args.doc:
        atomic_write_text(DOC, written(DOC.read_text(), result))
        print(f"written: the tables of {DOC.relative_to(ROOT)}")
        return
    atomic_write_bytes(FIGURE, robust_png(result))
    print(tables(result))


if __name__ == "__main__":
    main()
