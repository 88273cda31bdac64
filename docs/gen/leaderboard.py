"""docs/leaderboard.md's tables, regenerated from the committed score files: the rows listed in
results/score/rows.json (each a score.json under results/score/ and how its agent was trained),
written between the page's ``<!-- leaderboard:begin -->`` and ``<!-- leaderboard:end -->``
markers; the prose around them is the page's own. tests/test_score.py checks the page is what
this writes, byte for byte. A partial row (scored in fewer conditions than all of them, or with
fewer episodes per member than the leaderboard's) is marked † and listed after the full ones,
its shortfall said under the table: its aggregate is over less, and no row is ranked.

    python docs/gen/leaderboard.py            # rewrite docs/leaderboard.md and pursuit_bench/benchmark/leaderboard.json
    python docs/gen/leaderboard.py --check    # exit 1 if either is not up to date
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from pursuit_bench.benchmark import score
from pursuit_bench.io.files import atomic_write_text

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "results" / "score"
PAGE = ROOT / "docs" / "leaderboard.md"
BEGIN, END = "<!-- leaderboard:begin -->", "<!-- leaderboard:end -->"
#: The leaderboard's episodes per member (the page's "How to submit a result").
EPISODES = score.LEADERBOARD_EPISODES
PARTIAL = "†"
shortfall = score.shortfall


def summary(results: Path = RESULTS) -> str:
    """pursuit_bench/benchmark/leaderboard.json: every row's name, settings and aggregate, which
    ``pursuit-bench score`` places a result among (:func:`pursuit_bench.benchmark.score.standing`)."""
    rows: list[dict[str, Any]] = json.loads((results / "rows.json").read_text())
    entries = [score.leaderboard_entry(row["who"], json.loads((results / row["file"]).read_text())) for row in rows]
    about = "written by docs/gen/leaderboard.py from results/score/rows.json with docs/leaderboard.md"
    lines = ",\n".join(f"  {json.dumps(entry, ensure_ascii=False)}" for entry in entries)  # a row a line
    return f'{{\n "about": {json.dumps(about)},\n "rows": [\n{lines}\n ]\n}}\n'


def tables(results: Path = RESULTS) -> str:
    """The leaderboard's tables, one per role, and the command behind each row."""
    rows: list[dict[str, Any]] = json.loads((results / "rows.json").read_text())
    out = [BEGIN, ""]
    commands = []
    for role in ("predator", "prey"):
        mine = [(row, json.loads((results / row["file"]).read_text())) for row in rows if row["role"] == role]
        if not mine:
            continue
        mine.sort(key=lambda pair: bool(shortfall(pair[1])))  # the full rows first, each part in the file's order
        conditions = sorted({c for _, r in mine for c in r["conditions"]}, key=list(score.CONDITIONS).index)
        populations = sorted({r["population"] for _, r in mine})
        provisional = " (provisional)" if any(r["provisional"] for _, r in mine) else ""
        out += [f"### {role.capitalize()} role", "", f"Against population {', '.join(populations)}{provisional}.", ""]
        out.append(score.leaderboard_header(conditions))
        partial = []
        for row, result in mine:
            normalized = {c: v["normalized"] for c, v in result["conditions"].items()}
            aggregate = score.aggregate_text(result["aggregate"])
            cells = ["–" if normalized.get(c) is None else score.fixed(normalized[c], ".2f") for c in conditions]
            who = row["who"]
            if lacks := shortfall(result):
                who = f"{who} {PARTIAL}"
                partial.append(f"- {row['who']}: {'; '.join(lacks)}")
            out.append(f"| {who} | {row['how']} | {row['budget']} | {aggregate} | " + " | ".join(cells) + " |")
            commands.append(f"- {row['who']} ({role}): `{row['command']}` → `results/score/{row['file']}`")
        out.append("")
        if partial:
            out += [
                f"{PARTIAL} **Partial**: scored in fewer than all {len(score.CONDITIONS)} conditions or with fewer "
                f"than {EPISODES} episodes per member. Partial rows come after the full ones and are not ranked "
                "with them: each aggregate is over what that row was scored on only.",
                "",
                *partial,
                "",
            ]
    out += ["The commands behind the rows (run from the repository's root):", "", *commands, "", END]
    return "\n".join(out)


def render(page: str, results: Path = RESULTS) -> str:
    """``page`` with its tables regenerated."""
    before, _, rest = page.partition(BEGIN)
    _, _, after = rest.partition(END)
    return before + tables(results) + after


def main() -> None:
    page = PAGE.read_text()
    new, rows = render(page), summary()
    if "--check" in sys.argv:
        sys.exit(0 if new == page and score.LEADERBOARD.read_text() == rows else 1)
    atomic_write_text(PAGE, new)
    atomic_write_text(score.LEADERBOARD, rows)


if __name__ == "__main__":
    main()
