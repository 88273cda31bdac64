"""Keep what REPRODUCTION.md cites of `pursuit-bench analyze` (Fig. 3 of the shipped agents, and
P(chase | distance) and chase onsets over a sweep) compactly in the repository: each
``analysis.json`` without its per-state arrays (distances, modes, embeddings), full precision.

    pursuit-bench analyze --pretrained 2p-low-individual --out runs/fig3-2p-low-individual
    pursuit-bench analyze --pretrained 2p-high-individual --out runs/fig3-2p-high-individual
    pursuit-bench analyze sweeps/repro-analysis --episodes 100
    python scripts/export_analysis.py runs/fig3-2p-low-individual runs/fig3-2p-high-individual \\
        sweeps/repro-analysis --out results/analysis
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

#: Per-state arrays the compact copy drops (the figures are drawn from them, not the claims):
#: every state's distance and mode, and the embedded states' t-SNE coordinates.
PER_STATE = ("distance", "mode", "embedding")


def compact(analysis: dict[str, Any]) -> dict[str, Any]:
    """``analysis`` without the per-state arrays of its predators."""
    out = dict(analysis)
    if isinstance(out.get("predators"), dict):
        out["predators"] = {
            name: {k: v for k, v in entry.items() if k not in PER_STATE} for name, entry in out["predators"].items()
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", type=Path, nargs="+", help="Folders holding an analysis.json.")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for folder in args.folders:
        analysis = json.loads((folder / "analysis.json").read_text())
        name = folder.name
        (args.out / f"{name}.json").write_text(json.dumps(compact(analysis), indent=1) + "\n")
        print(f"{args.out / name}.json")


if __name__ == "__main__":
    main()
