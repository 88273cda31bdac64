"""Check that the figures the README quotes for the main job are what the main job gives.

    bash scripts/demo.sh && .venv/bin/python scripts/check_readme.py

The shipped agents' figures (``runs/demo-pretrained/eval.json``) must be in the README exactly:
evaluating shipped weights repeats on any machine. The short training run's figures
(``runs/demo/eval.json``) repeat bit for bit on one machine but not across machines, so the
README gives them as the spread over seeds 0–4 measured here (``results/readme/main-job.json``,
written by ``--record-seeds``), and this script checks that the README quotes that spread and
that the main job's seed-0 figures lie inside it. Exits 1 naming any sentence the README lacks.

    python scripts/check_readme.py --record-seeds /work/mainjob/seed*   # after training seeds 0-4
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
    problems = [f"README.md lacks: {s!r}" for s in (shipped_sentence(shipped), spread_sentence(seeds)) if s not in text]
    problems += [f"runs/demo/eval.json: {line}" for line in outside(trained, seeds)]
    for problem in problems:
        print(problem, file=sys.stderr)
    if not problems:
        print("README.md quotes the shipped agents' figures exactly and the training run inside its spread over seeds")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
