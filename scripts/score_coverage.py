"""How often the score's 95 % interval (``pursuit_bench.study.score.crossed_interval``: members and
episodes both random) holds the true mean, on simulated (members × episodes) tables with a member
effect, an episode effect shared by every member (the same episodes) and noise; 2000 tables per
cell, seeded. Prints the table docs/leaderboard.md quotes.

    python scripts/score_coverage.py
"""

from __future__ import annotations

import numpy as np
from scipy.special import expit

from pursuit_bench.study.score import coverage

DRAWS = 2000
MEMBERS = (2, 4, 6, 13)
EPISODES = (20, 100)


def normal(rng: np.random.Generator, m: int, e: int) -> np.ndarray:
    """Normal member (sd 0.3) and episode (sd 0.3) effects, normal noise (sd 0.5); mean 0."""
    return rng.normal(0, 0.3, (m, 1)) + rng.normal(0, 0.3, (1, e)) + rng.normal(0, 0.5, (m, e))


def capture(rng: np.random.Generator, m: int, e: int) -> np.ndarray:
    """Like the game's returns: caught (1) or not with a logit-normal chance (member and episode
    effects sd 1 on the logit scale), minus a cost uniform in [0, 0.3]."""
    p = expit(rng.normal(0, 1, (m, 1)) + rng.normal(0, 1, (1, e)))
    return (rng.random((m, e)) < p) * 1.0 - 0.3 * rng.random((m, e))


def members_dominate(rng: np.random.Generator, m: int, e: int) -> np.ndarray:
    """Members far apart (sd 1: a scripted prey beside learned ones), small episode effect (sd 0.2), noise sd 0.3."""
    return rng.normal(0, 1.0, (m, 1)) + rng.normal(0, 0.2, (1, e)) + rng.normal(0, 0.3, (m, e))


#: (label, draw, true mean); the capture model's: E[expit(N(0, 2))] = 0.5 by symmetry, minus the mean cost 0.15.
MODELS = (("normal", normal, 0.0), ("capture-like", capture, 0.5 - 0.15), ("members dominate", members_dominate, 0.0))


def main() -> None:
    print("| members | episodes | " + " | ".join(label for label, _, _ in MODELS) + " |")
    print("|---:|---:|" + "---:|" * len(MODELS))
    for m in MEMBERS:
        for e in EPISODES:
            cells = [coverage(draw, truth, m, e, DRAWS, seed=1000 * m + e) for _, draw, truth in MODELS]
            print(f"| {m} | {e} | " + " | ".join(f"{c:.1%}" for c in cells) + " |")


if __name__ == "__main__":
    main()
