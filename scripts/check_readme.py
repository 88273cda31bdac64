"""Check that the figures the README quotes for the main job are what the main job gives.

    bash scripts/demo.sh && .venv/bin/python scripts/check_readme.py

The shipped agents' figures (``runs/demo-pretrained/eval.json``) must be in the README exactly:
evaluating shipped weights repeats on any machine. The short training run's figures
(``runs/demo/eval.json``) repeat bit for bit on one machine but not across machines, so the
README gives them as the spread over seeds 0–4 measured here (``results/readme/main-job.json``,
written by ``--record-seeds``), and this script checks that the README quotes that spread and
that the main job's seed-0 figures lie inside it. The README's answer (its table and the
sentences that quote its counts) is recomputed from the committed results (``results/pool/``,
``results/reproduction/``). Exits 1 naming any sentence the README lacks.

    python scripts/check_readme.py --record-seeds MAINJOB/seed*   # run folders of seeds 0-4
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ROOT / "results" / "readme" / "main-job.json"
VARIANTS = ("trained", "always_chase", "always_stalk")


def signed(value: float) -> str:
    """``+0.27`` / ``−0.25`` (a typographic minus, as the README writes it)."""
    return f"{value:+.2f}".replace("-", "−")


def shipped_sentence(result: dict[str, Any]) -> str:
    """What the README says of the shipped agents' evaluation (``eval --pretrained``)."""
    panels = result["panels"]

    def joined(key: str) -> str:
        return " / ".join(signed(p[key]) for p in panels)

    return (
        f"{joined('trained')} against always-chase's {joined('always_chase')} and "
        f"always-stalk's {joined('always_stalk')}"
    )


def spread_sentence(seeds: dict[str, Any]) -> str:
    """What the README says of the short training run over seeds 0–4."""

    def span(key: str) -> str:
        values = [s[key] for s in seeds["seeds"]]
        return f"{signed(min(values))} to {signed(max(values))}"

    return (
        f"the hierarchical predator scores {span('trained')}, always-chase {span('always_chase')} and "
        f"always-stalk {span('always_stalk')}"
    )


def outside(trained: dict[str, Any], seeds: dict[str, Any]) -> list[str]:
    """The main job's figures that lie outside the recorded spread over seeds (empty if none)."""
    out = []
    for key in VARIANTS:
        values = [s[key] for s in seeds["seeds"]]
        if not min(values) <= trained[key] <= max(values):
            out.append(f"{key} {trained[key]:+.3f} outside [{min(values):+.3f}, {max(values):+.3f}]")
    return out


#: The answer's table: its rows' labels, and what each row counts (``pool.summarise``'s panels at
#: the last budget, or the reproduction's verdicts against the fixed modes).
ANSWER_ROWS = (
    ("hierarchical − flat: return against the pool at {last:,} episodes (**primary**)", "return"),
    ("hierarchical − flat: margin over the fixed modes at {last:,} episodes", "margin"),
    ("hierarchical − flat: margin averaged over {first}–{last:,} episodes (head start)", "learning_speed"),
    ("learned stalk/chase switch − better fixed mode at {last:,} episodes (both steer by the rule)", "fixed_modes"),
)
POOL = ROOT / "results" / "pool" / "pool.json"
REPRODUCTION = ROOT / "results" / "reproduction"


def answer() -> dict[str, Any]:
    """The counts the README's answer quotes, from the committed results: per row of its table
    (panels, rule ahead, equivalent, not resolved, rule behind), the panels the pool did not
    compare, and 1p-high's runs that fall below the better fixed mode (pool margin < 0) or
    above every run of the other kind."""
    from pursuit_bench.study import pool, report

    summary = pool.summarise(pool.load(POOL))
    last = summary["budgets"][-1]
    rows: dict[str, tuple[int, ...]] = {}
    for _, key in ANSWER_ROWS[:3]:
        counts = summary["learning_speed"]["counts"] if key == "learning_speed" else last[key]["counts"]
        rows[key] = (sum(counts.values()), *(counts[v] for v in ("rule helps", "equivalent", "not resolved")))
        rows[key] += (counts["flat better"],)
    table = report.panel_table(report.collect(REPRODUCTION))
    report.judge(table)
    verdicts = [t["verdict"] for t in table if "verdict" in t]
    order = ("better", "equivalent", "not resolved", "worse")
    rows["fixed_modes"] = (len(verdicts), *(verdicts.count(v) for v in order))
    panel = next(p for p in last["margin"]["panels"] if p["condition"] == "1p-high")
    return {
        "rows": rows,
        "budgets": {"first": summary["budgets"][0]["episodes"], "last": last["episodes"]},
        "panels": len(verdicts),
        "split": {
            kind: {
                "runs": len(panel[kind]),
                "below": sum(v < 0 for v in panel[kind]),
                "above": sum(v > max(panel[other]) for v in panel[kind]),
            }
            for kind, other in (("hierarchical", "flat"), ("flat", "hierarchical"))
        },
    }


def answer_table(counts: dict[str, Any]) -> str:
    """The README's table of the answer, from ``answer()``."""
    header = ("panels", "rule ahead", "equivalent (±0.05)", "not resolved", "rule behind")
    lines = [
        "| comparison, per panel | " + " | ".join(header) + " |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {label.format(**counts['budgets'])} | " + " | ".join(map(str, counts["rows"][key])) + " |"
        for label, key in ANSWER_ROWS
    ]
    return "\n".join(lines)


def answer_sentences(counts: dict[str, Any]) -> list[str]:
    """The README's sentences that quote the answer's counts."""
    ret, speed, flat = counts["rows"]["return"], counts["rows"]["learning_speed"], counts["split"]["flat"]
    hierarchical = counts["split"]["hierarchical"]
    return [
        f"the rule helps in {ret[1]} of the {ret[0]} panels compared so far and the flat learner in {ret[4]}; "
        f"{ret[3]} are not resolved, and {counts['panels'] - ret[0]} panels",
        f"ahead in {speed[1]} of the {speed[0]} panels and behind in {'none' if speed[4] == 0 else speed[4]}",
        f"in 1p-high, {flat['below']} of its {flat['runs']} runs fall below the better fixed mode ("
        + ("no hierarchical run does" if hierarchical["below"] == 0 else f"{hierarchical['below']} hierarchical do")
        + f") and {flat['above']} beat every hierarchical run",
    ]


def readme() -> str:
    return " ".join((ROOT / "README.md").read_text().split())  # line breaks as spaces


def record_seeds(folders: list[Path]) -> None:
    """Write results/readme/main-job.json from the runs of the main job's training on several seeds."""
    rows = []
    for folder in folders:
        config = json.loads((folder / "config.json").read_text())["train"]
        panel = json.loads((folder / "eval.json").read_text())["panels"][0]
        rows.append({"seed": config["seed"], **{key: panel[key] for key in VARIANTS}})
    payload = {
        "command": "scripts/demo.sh's training and evaluation, --seed S",
        "seeds": sorted(rows, key=lambda r: r["seed"]),
    }
    SEEDS.parent.mkdir(parents=True, exist_ok=True)
    SEEDS.write_text(json.dumps(payload, indent=2) + "\n")
    print(f"{SEEDS}: {len(rows)} seeds")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record-seeds", type=Path, nargs="+", default=None, help="Run folders of seeds 0–4.")
    args = parser.parse_args()
    if args.record_seeds:
        record_seeds(args.record_seeds)
        return 0
    seeds = json.loads(SEEDS.read_text())
    shipped = json.loads((ROOT / "runs/demo-pretrained/eval.json").read_text())
    trained = json.loads((ROOT / "runs/demo/eval.json").read_text())["panels"][0]
    text = readme()
    counts = answer()
    quoted = (shipped_sentence(shipped), spread_sentence(seeds), *answer_sentences(counts))
    problems = [f"README.md lacks: {s!r}" for s in quoted if s not in text]
    if answer_table(counts) not in (ROOT / "README.md").read_text():
        problems.append(f"README.md lacks the answer's table:\n{answer_table(counts)}")
    problems += [f"runs/demo/eval.json: {line}" for line in outside(trained, seeds)]
    for problem in problems:
        print(problem, file=sys.stderr)
    if not problems:
        print("README.md quotes the shipped agents' figures exactly and the training run inside its spread over seeds")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
