"""docs/pursuit-law.md's sweep table from results/pursuit-law/sweep-summary.json, which holds the
summaries `pursuit-bench law SWEEP --episodes 5` wrote for the reproduction sweep's hierarchical
and flat runs:

    python scripts/law_tables.py --collect sweeps/repro1000 sweeps/repro1000-flat   # writes the file
    python scripts/law_tables.py                                                    # prints the table
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pursuit_bench.io.files import atomic_write_text

SUMMARY = Path(__file__).resolve().parent.parent / "results" / "pursuit-law" / "sweep-summary.json"
SHOWN = ("parallel", "pn", "mixed", "pp", "none")


def _interval(entry: dict) -> str:
    if entry["mean"] is None:
        return "-"
    ci = entry["ci"]
    return f"{entry['mean']:.2f}" + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--collect", nargs="*", type=Path, help="sweep folders whose law.json to collect")
    args = parser.parse_args()
    if args.collect:
        merged: dict = {}
        for sweep in args.collect:
            for condition, kinds in json.loads((sweep / "law.json").read_text())["summary"].items():
                merged.setdefault(condition, {}).update(kinds)
        atomic_write_text(SUMMARY, json.dumps(merged, indent=1) + "\n")
    summary = json.loads(SUMMARY.read_text())
    print(
        "| condition | predators | phase | segments | share chosen: parallel / pn / mixed / pp / none "
        "| pn's N | mixed's N, K |"
    )
    print("|---|---|---|---:|---|---|---|")
    for condition, kinds in sorted(summary.items()):
        for kind in ("hierarchical", "flat"):
            if kind not in kinds:
                continue
            for phase in ("chase", "stalk"):
                entry = kinds[kind][phase]
                if not entry["attacks"]:
                    continue
                shares = " / ".join(f"{entry['share'][law]['mean']:.0%}" for law in SHOWN)
                gains = entry["gains"]
                mixed = f"{_interval(gains['mixed.N'])}; {_interval(gains['mixed.K'])}"
                print(
                    f"| {condition} | {kind} | {phase} | {entry['attacks']} | {shares} | "
                    f"{_interval(gains['pn.N'])} | {mixed} |"
                )


if __name__ == "__main__":
    main()
