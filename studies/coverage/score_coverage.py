"""How often the score's 95 % interval (``pursuit_bench.benchmark.score.crossed_interval``: members and
episodes both random) holds the true mean, on simulated (members × episodes) tables with a member
effect, an episode effect shared by every member (the same episodes) and noise; 2000 tables per
cell, seeded; then the aggregate's bootstrap interval in one simulated setting. Prints what
docs/leaderboard.md quotes.

    python studies/coverage/score_coverage.py
"""

from __future__ import annotations

import numpy as np
from scipy.special import expit

from pursuit_bench.benchmark.score import aggregate, coverage, iqm

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


def aggregate_coverage(datasets: int = 150, resamples: int = 400) -> float:
    """How often the aggregate's stratified-bootstrap interval holds the true IQM of normalized
    scores spread from 0.6 to 1.1 over 10 conditions; per condition 4 members × 20 episodes,
    random at −1 and the reference at +0.5, member and episode effects (sd 0.15) shared by the
    agent and both anchors (the same members and episodes), noise sd 0.3."""
    rng = np.random.default_rng(5)
    truth_scores = np.linspace(0.6, 1.1, 10)
    held = 0
    for k in range(datasets):
        cells = {}
        for j, mu in enumerate(truth_scores):
            shared = rng.normal(0, 0.15, (4, 1)) + rng.normal(0, 0.15, (1, 20))
            r, h, a = (level + shared + rng.normal(0, 0.3, (4, 20)) for level in (-1.0, 0.5, -1.0 + 1.5 * mu))
            cells[f"c{j}"] = (a, r, h)
        low, high = aggregate(cells, seed=k, resamples=resamples)["ci"]
        held += low <= iqm(truth_scores) <= high
    return held / datasets


def main() -> None:
    print("| members | episodes | " + " | ".join(label for label, _, _ in MODELS) + " |")
    print("|---:|---:|" + "---:|" * len(MODELS))
    for m in MEMBERS:
        for e in EPISODES:
            cells = [coverage(draw, truth, m, e, DRAWS, seed=1000 * m + e) for _, draw, truth in MODELS]
            print(f"| {m} | {e} | " + " | ".join(f"{c:.1%}" for c in cells) + " |")
    print(f"\naggregate's interval, one simulated setting (150 datasets): {aggregate_coverage():.1%}")


if __name__ == "__main__":
    main()
