"""Check that the figures the README quotes for the main job are what the main job gives.

    bash scripts/demo.sh && .venv/bin/python scripts/check_readme.py

Reads ``runs/demo-pretrained/eval.json`` and ``runs/demo/eval.json`` (what ``scripts/demo.sh``
writes), writes the sentences the README must contain, and exits 1 naming any it lacks. Run it
whenever the main job, the shipped agents or the presets change.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def signed(value: float) -> str:
    """``+0.27`` / ``−0.25`` (a typographic minus, as the README writes it)."""
    return f"{value:+.2f}".replace("-", "−")


def expected() -> list[str]:
    shipped = json.loads((ROOT / "runs/demo-pretrained/eval.json").read_text())["panels"]
    trained = json.loads((ROOT / "runs/demo/eval.json").read_text())["panels"][0]

    def joined(key: str) -> str:
        return " / ".join(signed(p[key]) for p in shipped)

    return [
        f"{joined('trained')} against always-chase's {joined('always_chase')} and "
        f"always-stalk's {joined('always_stalk')}",
        f"{signed(trained['trained'])} against {signed(trained['always_chase'])} for always-chase and "
        f"{signed(trained['always_stalk'])} for always-stalk",
    ]


def main() -> int:
    readme = " ".join((ROOT / "README.md").read_text().split())  # line breaks as spaces
    missing = [sentence for sentence in expected() if sentence not in readme]
    for sentence in missing:
        print(f"README.md lacks: {sentence!r}", file=sys.stderr)
    if not missing:
        print("README.md quotes the main job's figures as scripts/demo.sh gives them")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
