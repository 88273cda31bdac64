"""How often a study's 95 % intervals hold the truth when the runs are shaped like its own: for
each judged panel and comparison of a study's primary measure (the pool return at the last
budget), runs are drawn with replacement from each kind's committed runs, as many as it has,
4000 times; the truth of that world is the difference of the committed means, and the check is
how often Welch's interval (`stats.welch_difference`, the report's) holds it. The same for
the robustness ladders' paired t-intervals (residual − hierarchical change of margin, seeds
resampled as pairs). Where a kind's runs split (some fail, some excel), this is the coverage at
that split, not at a normal one (docs/statistics.md's tables simulate shapes chosen beforehand).

The world is the committed runs themselves, so its tails are no longer than the data's: a
coverage well below 95 % here is a warning, one near 95 % is not a guarantee.

    python studies/coverage/study_coverage.py results/residual-study --out results/residual-study/interval-coverage.md

Seeded by each row's own name: the same table every time for the same runs, and a row keeps its
value when other settings are added.
"""

from __future__ import annotations

import argparse
import sys
import zlib
from pathlib import Path

import numpy as np

from pursuit_bench import stats
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.reports import rule_report, rule_study

DRAWS = 4000


def _seed(*names: object) -> int:
    """A row's seed from its names (stable across runs and Python processes)."""
    return zlib.crc32("|".join(map(str, names)).encode())


def welch_coverage(first: np.ndarray, second: np.ndarray, seed: int) -> float:
    """Welch's interval's coverage of ``mean(first) - mean(second)`` for samples drawn with
    replacement from ``first`` and ``second`` at their own sizes."""
    rng = np.random.default_rng(seed)
    truth = float(first.mean() - second.mean())
    held = 0
    for _ in range(DRAWS):
        a = rng.choice(first, size=len(first), replace=True)
        b = rng.choice(second, size=len(second), replace=True)
        low, high = stats.welch_difference(a, b)["ci"]
        held += low - stats.TIE <= truth <= high + stats.TIE
    return held / DRAWS


def paired_coverage(differences: np.ndarray, seed: int) -> float:
    """The paired t-interval's coverage of the mean of ``differences`` (seeds resampled)."""
    rng = np.random.default_rng(seed)
    truth = float(differences.mean())
    held = 0
    for _ in range(DRAWS):
        low, high = stats.t_interval(rng.choice(differences, size=len(differences), replace=True))  # type: ignore[misc]
        held += low - stats.TIE <= truth <= high + stats.TIE
    return held / DRAWS


def tables(where: Path) -> str:
    """The markdown tables for the study folder ``where`` (its judged settings only)."""
    study = rule_report.study_of(where, where.name)
    runs = rule_report.complete_settings(rule_study.read_runs(where / "runs"), study.kinds, study.seed_rule)[0]
    final = rule_report.budgets(runs)[-1]
    rows = rule_report.rows_of(
        runs,
        lambda r, p: rule_study.pooled(r["pool"][final], p)["return"],
        kinds=study.kinds,
        pairs=study.pairs,
    )
    lines = [
        f"Primary measure (pool return at {final} episodes), Welch's 95 % interval, {DRAWS} draws a row:",
        "",
        "| setting | predator | comparison | runs a kind | failed runs (first, second) | coverage |",
        "|---|---|---|---:|---:|---:|",
    ]
    for row in rows:
        first, second = row["pair"]
        a, b = np.array(row[first]), np.array(row[second])
        failed = [
            sum(rule_study.failed(r, row["predator"]) for r in runs if rule_report.setting_of(r) == row["condition"]
                and r["kind"] == kind)
            for kind in (first, second)
        ]  # fmt: skip
        held = welch_coverage(a, b, seed=_seed(row["condition"], row["predator"], first, second))
        lines.append(
            f"| {row['condition']} | {row['predator']} | {first} − {second} | {len(a)}/{len(b)} "
            f"| {failed[0]}, {failed[1]} | {held:.1%} |"
        )
    families = rule_report.ladders(runs) if any("ladders" in r for r in runs) else {}
    if families:
        lines += [
            "",
            "Robustness ladders, residual − hierarchical change of margin, paired t 95 % interval, "
            f"{DRAWS} draws a row:",
            "",
            "| ladder | setting | rung | seeds | coverage |",
            "|---|---|---:|---:|---:|",
        ]
        for ladder, family in families.items():
            for cell in family["cells"]:
                level = f"{ladder}={cell['rung']:g}"
                pairs: dict[int, dict[str, float]] = {}
                for r in runs:
                    if rule_report.setting_of(r) == cell["setting"] and r["kind"] in ("residual", "hierarchical"):
                        change = r["ladders"][level]["margin"] - r["ladders"]["none"]["margin"]
                        pairs.setdefault(r["seed"], {})[r["kind"]] = change
                d = np.array([p["residual"] - p["hierarchical"] for _, p in sorted(pairs.items()) if len(p) == 2])
                held = paired_coverage(d, seed=_seed(ladder, cell["setting"], cell["rung"]))
                lines.append(f"| {ladder} | {cell['setting']} | {cell['rung']:g} | {len(d)} | {held:.1%} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", type=Path, help="A study's folder (runs/*.json.gz and its <name>.json).")
    parser.add_argument("--out", type=Path, help="Also write the tables here (markdown).")
    args = parser.parse_args()
    try:
        text = tables(args.study)
    except ValueError as error:
        sys.exit(f"{args.study}: {error}")
    print(text, end="")
    if args.out is not None:
        atomic_write_text(args.out, f"`python studies/coverage/study_coverage.py {args.study}`\n\n{text}")


if __name__ == "__main__":
    main()
