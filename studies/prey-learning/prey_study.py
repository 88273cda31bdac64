"""The prey-learning study of docs/learning.md: each variant a sweep of 1p-high against a fixed
always-stalk predator (the prey the only learner), three seeds, then a figure and a table.

    python studies/prey-learning/prey_study.py run STUDY_DIR [VARIANT ...]   # the sweeps (resumable)
    python studies/prey-learning/prey_study.py figure STUDY_DIR OUT.png      # curves and the table

Each variant is a name and the sweep options it adds to the quick preset (VARIANTS below).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

VARIANTS = {
    "quick": [],
    "lr3e-4-t1000": ["--learning-rate", "3e-4", "--target-update-every", "1000"],
    "lr1e-4-t2000": ["--learning-rate", "1e-4", "--target-update-every", "2000"],
    "lr3e-5-t2000": ["--learning-rate", "3e-5", "--target-update-every", "2000"],
    "wall": ["--wall-features"],
    "wall-lr1e-4": ["--wall-features", "--learning-rate", "1e-4", "--target-update-every", "2000"],
    "wall-lr3e-5": ["--wall-features", "--learning-rate", "3e-5", "--target-update-every", "2000"],
}
SWEEP = ["sweep", "--conditions", "1p-high", "--seeds", "3", "--predators", "always_stalk", "--episodes", "1500"]
SWEEP += ["--eval-episodes", "300", "--workers", "1", "--no-record", "--log-every", "500"]
BLOCK = 100


def run(study: Path, names: list[str]) -> None:
    for name in names or list(VARIANTS):
        out = study / f"stalk-{name}"
        subprocess.run(["pursuit-bench", *SWEEP, "--out", str(out), *VARIANTS[name]], check=True)
        for folder in sorted((out / "runs").iterdir()):  # the learned prey, greedy, beside FleeingPrey
            if not (folder / "eval-check.json").exists():
                command = ["pursuit-bench", "eval", str(folder), "--episodes", "300", "--no-record", "--tag", "check"]
                subprocess.run(command, check=True, capture_output=True)


def figure(study: Path, png: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 4))
    header = "| variant | seeds | prey return, last 300 episodes | survives | greedy prey: return / walls"
    print(header + " | FleeingPrey: return |")
    print("|---|---:|---:|---:|---|---:|")
    for i, name in enumerate(VARIANTS):
        runs = sorted((study / f"stalk-{name}" / "runs").glob("*"))
        rows = [[json.loads(line) for line in (r / "metrics.jsonl").read_text().splitlines()] for r in runs]
        rows = [r for r in rows if len(r) >= 1500]
        if not rows:
            continue
        returns = np.array([[row["return/prey_0"] for row in r[:1500]] for r in rows]).reshape(len(rows), -1, BLOCK)
        curve = returns.mean(axis=2)
        x = (np.arange(curve.shape[1]) + 0.5) * BLOCK
        ax.plot(x, curve.mean(axis=0), label=name, color=plt.get_cmap("tab10")(i))
        ax.fill_between(x, curve.min(axis=0), curve.max(axis=0), color=plt.get_cmap("tab10")(i), alpha=0.12, lw=0)
        last = np.array([[row["return/prey_0"] for row in r[1200:1500]] for r in rows])
        survived = np.mean([[row["length"] == 300 for row in r[1200:1500]] for r in rows])
        checks = [
            json.loads((r / "eval-check.json").read_text())["prey_check"]
            for r in runs
            if (r / "eval-check.json").exists()
        ]
        greedy = " ".join(
            f"{c['learned_greedy']['return']:+.2f}/{c['learned_greedy']['left_area']:.0%}" for c in checks
        )
        fleeing = np.mean([c["fleeing_prey"]["return"] for c in checks]) if checks else float("nan")
        print(f"| {name} | {len(rows)} | {last.mean():+.2f} | {survived:.0%} | {greedy} | {fleeing:+.2f} |")
    ax.set_xlabel("episode")
    ax.set_ylabel(f"prey return (mean of {BLOCK}-episode blocks)")
    ax.set_title("1p-high, prey learning against always-stalk: mean of 3 seeds (band: min–max)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=90)


if __name__ == "__main__":
    command, study = sys.argv[1], Path(sys.argv[2])
    if command == "run":
        run(study, sys.argv[3:])
    else:
        figure(study, Path(sys.argv[3]))
