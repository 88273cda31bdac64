"""The authors' trained agents in their own environment (docs/authors-agents.md, REPRODUCTION.md):
the table and the ranges REPRODUCTION.md quotes, from results/authors-agents/measurements.json.

    python docs/gen/authors_agents.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "results" / "authors-agents" / "measurements.json"


def load() -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = json.loads(RESULTS.read_text())["rows"]
    return rows


def markdown(rows: list[dict[str, Any]]) -> str:
    lines = [
        "| condition | prey | capture | prey left the arena | predator left | time-out | mean length |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['condition']} | {r['prey']} | {r['capture_percent']} % | {r['prey_left_percent']} % "
            f"| {r['predator_left_percent']} % | {r['time_out_percent']} % | {r['mean_length']} |"
        )
    return "\n".join(lines) + "\n"


def _span(values: list[int]) -> str:
    low, high = min(values), max(values)
    return f"{low} %" if low == high else f"{low}–{high} %"


def summary(rows: list[dict[str, Any]]) -> str:
    """REPRODUCTION.md's sentence on their prey: wall exits and captures greedy (by number of
    predators), captures at ε = 0.1."""
    greedy = [r for r in rows if r["prey"] == "greedy"]
    caught = {n: _span([r["capture_percent"] for r in greedy if r["condition"].startswith(n)]) for n in ("1", "2", "3")}
    noisy = [r["capture_percent"] for r in rows if r["prey"] != "greedy"]
    return (
        f"their greedy prey leaves the arena in {_span([r['prey_left_percent'] for r in greedy])} of episodes and "
        f"is caught in {caught['1']} (1 predator), {caught['2']} (2) and {caught['3']} (3); at ε = 0.1 it is "
        f"caught in {_span(noisy)}."
    )


if __name__ == "__main__":
    table = load()
    print(markdown(table))
    print(summary(table))
