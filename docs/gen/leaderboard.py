"""docs/leaderboard.md's tables, regenerated from the committed score files: the rows listed in
results/score/rows.json (each a score.json under results/score/ and how its agent was trained),
written between the page's ``<!-- leaderboard:begin -->`` and ``<!-- leaderboard:end -->``
markers, and the MARL rows (issue 65, studies/marl/PLAN.md: results/marl/, a score.json per
learner, condition and seed) between ``<!-- marl:begin -->`` and ``<!-- marl:end -->``, with
the protocol's comparisons once every row is in; the prose around them is the page's own.
tests/test_score.py checks the page is what this writes, byte for byte. A partial row (scored in
fewer conditions than all of them, or with fewer episodes per member than the leaderboard's) is
marked † and listed after the full ones, its shortfall said under the table: its aggregate is
over less, and no row is ranked.

    python docs/gen/leaderboard.py            # rewrite docs/leaderboard.md and pursuit_bench/benchmark/leaderboard.json
    python docs/gen/leaderboard.py --check    # exit 1 if either is not up to date
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

from pursuit_bench import stats
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
MARL = ROOT / "results" / "marl"
MARL_BEGIN, MARL_END = "<!-- marl:begin -->", "<!-- marl:end -->"
#: The MARL rows' learners (studies/marl/run.py's names) as the table names them: BenchMARL's
#: three, then ours, which each of theirs is compared with.
THEIRS = {"ippo": "IPPO (BenchMARL)", "mappo": "MAPPO (BenchMARL)", "iql": "IQL (BenchMARL)"}
OURS = {"flat": "flat DQN (ours)", "hierarchical": "hierarchical (ours)"}
MARL_CONDITIONS = ("1p-high", "2p-low-shared", "3p-high-individual")
MARL_SEEDS = (0, 1, 2)


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


def marl_scores(folder: Path = MARL) -> dict[tuple[str, str], dict[int, tuple[float, list[float]]]]:
    """Per (learner, condition), each scored seed's normalized score and its interval (the
    score file's aggregate over its one condition: members and episodes resampled)."""
    out: dict[tuple[str, str], dict[int, tuple[float, list[float]]]] = {}
    for learner in [*THEIRS, *OURS]:
        for condition in MARL_CONDITIONS:
            for seed in MARL_SEEDS:
                path = folder / f"{condition}-{learner}-seed{seed}.score.json"
                if path.is_file():
                    result = json.loads(path.read_text())
                    value = result["conditions"][condition]["normalized"]
                    out.setdefault((learner, condition), {})[seed] = (value, result["aggregate"]["ci"])
    return out


def marl_comparisons(scores: dict[tuple[str, str], dict[int, tuple[float, list[float]]]]) -> list[dict[str, Any]]:
    """The protocol's family (PLAN.md, "The comparison rows"): each of BenchMARL's learners minus
    each of ours in each condition, Welch over the seeds, Holm over all of them. A condition's
    comparisons are made once every seed of every learner there is in; Holm is over the whole
    family, each comparison not yet made counted at p = 1, so that every adjusted p is at least
    what the whole family will give it (nothing rejected early is taken back when the rest land)."""
    pairs = [(t, o, c) for c in MARL_CONDITIONS for t in THEIRS for o in OURS]
    ready = {
        c for c in MARL_CONDITIONS if all(len(scores.get((k, c), {})) == len(MARL_SEEDS) for k in [*THEIRS, *OURS])
    }
    rows = []
    for theirs, ours, condition in pairs:
        if condition not in ready:
            continue
        a = [scores[theirs, condition][s][0] for s in MARL_SEEDS]
        b = [scores[ours, condition][s][0] for s in MARL_SEEDS]
        rows.append({"theirs": theirs, "ours": ours, "condition": condition, **stats.welch_difference(a, b)})
    padded = [r["p"] for r in rows] + [1.0] * (len(pairs) - len(rows))
    for row, adjusted in zip(rows, stats.holm(padded), strict=False):
        row["p_holm"] = float(adjusted)
    return rows


def marl_tables(folder: Path = MARL) -> str:
    """The MARL rows: each learner's normalized score per seed with its interval and the mean
    over the seeds in, per condition; then the comparisons (or what they wait for)."""
    scores = marl_scores(folder)
    names = {**THEIRS, **OURS}
    out = [MARL_BEGIN, "", "| learner | seed | " + " | ".join(MARL_CONDITIONS) + " |", "|---|---|" + "---:|" * 3]
    missing = 0
    for learner, name in names.items():
        for seed in MARL_SEEDS:
            cells = []
            for condition in MARL_CONDITIONS:
                got = scores.get((learner, condition), {}).get(seed)
                missing += got is None
                cells.append("–" if got is None else f"{got[0]:.2f} [{got[1][0]:.2f}, {got[1][1]:.2f}]")
            out.append(f"| {name} | {seed} | " + " | ".join(cells) + " |")
        means = []
        for condition in MARL_CONDITIONS:
            got = scores.get((learner, condition), {})
            mean = sum(v for v, _ in got.values()) / len(got) if got else None
            means.append(
                "–"
                if mean is None
                else f"**{mean:.2f}**" + (f" ({len(got)} of {len(MARL_SEEDS)})" if len(got) < len(MARL_SEEDS) else "")
            )
        out.append(f"| {name} | mean | " + " | ".join(means) + " |")
    out.append("")
    comparisons = marl_comparisons(scores)
    family = len(THEIRS) * len(OURS) * len(MARL_CONDITIONS)
    if missing:
        waiting = [c for c in MARL_CONDITIONS if c not in {r["condition"] for r in comparisons}]
        out += [
            f"{missing} of {len(names) * len(MARL_CONDITIONS) * len(MARL_SEEDS)} rows still to come. The comparisons "
            f"(each BenchMARL learner minus each of ours, per condition: Welch over the three seeds, Holm over the "
            f"{family}) of {', '.join(waiting)} are made once their rows are all in"
            + (
                f"; those below are the {len(comparisons)} made so far, each p adjusted over all {family} with "
                "the ones not yet made counted at 1 (so at least what the whole family will give it)."
                if comparisons
                else "."
            ),
            "",
        ]
    if comparisons:
        out += [
            "| condition | learner | minus | difference [95 % CI] | Welch df | p (Holm) |",
            "|---|---|---|---:|---:|---:|",
        ]
        for row in comparisons:
            low, high = row["ci"]
            df = "–" if math.isnan(row["df"]) else f"{row['df']:.1f}"  # no spread in either group
            out.append(
                f"| {row['condition']} | {THEIRS[row['theirs']]} | {OURS[row['ours']]} | {row['mean']:+.2f} "
                f"[{low:+.2f}, {high:+.2f}] | {df} | {row['p_holm']:.3f} |"
            )
        out.append("")
    out.append(MARL_END)
    return "\n".join(out)


def render(page: str, results: Path = RESULTS, marl: Path = MARL) -> str:
    """``page`` with its tables regenerated."""
    before, _, rest = page.partition(BEGIN)
    _, _, after = rest.partition(END)
    page = before + tables(results) + after
    if MARL_BEGIN in page:
        before, _, rest = page.partition(MARL_BEGIN)
        _, _, after = rest.partition(MARL_END)
        page = before + marl_tables(marl) + after
    return page


def main() -> None:
    page = PAGE.read_text()
    new, rows = render(page), summary()
    if "--check" in sys.argv:
        sys.exit(0 if new == page and score.LEADERBOARD.read_text() == rows else 1)
    atomic_write_text(PAGE, new)
    atomic_write_text(score.LEADERBOARD, rows)


if __name__ == "__main__":
    main()
