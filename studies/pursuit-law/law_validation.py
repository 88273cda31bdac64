"""The pursuit-law method's validation (docs/pursuit-law.md), on synthetic attacks whose law is
known (:mod:`pursuit_bench.laws.synthetic_attacks`), every law fitted and one chosen by BIC
(:func:`pursuit_bench.laws.guidance.select`):

- ``validation``: each law in continuous time, five attacks per case over the whole attack (up
  to 4 s), and the misspecification control: laws flown as our predators fly (12 directions 30°
  apart, each held one 0.1 s step, the velocity lagging with the env's damping), which no fitted
  law holds. Writes results/pursuit-law/validation.json and docs/figures/law-profile.png (the
  whole-attack error over N: how well N is determined).
- ``confusion``: the selection by attack length: :data:`PER_CELL` held-out attacks (seeds from
  :data:`FIRST_SEED`) per true law and length, the first :data:`HISTORY` samples the history a
  delayed law reads (as our segments carry) and n samples after the onset, n in
  :data:`LENGTHS`. Writes results/pursuit-law/confusion.json.

Every selection is written in full: each law's gains, delay, censoring, error and criterion, the
floor and the laws under it. ``python docs/gen/law_tables.py`` prints the docs' tables from these
files.

    python studies/pursuit-law/law_validation.py                 # both parts, about 3 min on one core
    python studies/pursuit-law/law_validation.py --parts confusion
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.laws import guidance
from pursuit_bench.laws.synthetic_attacks import TrueLaw, attack

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "results" / "pursuit-law"
DT = 0.1
#: Attacks per validation case (seeds 0 … 4, the tests' too).
ATTACKS = 5
CASES = [
    TrueLaw("pp", k_gain=1.0),
    TrueLaw("pp", k_gain=3.0),
    TrueLaw("pp", k_gain=2.0, delay=0.1),
    TrueLaw("pn", n_gain=2.0),
    TrueLaw("pn", n_gain=3.0, delay=0.1),
    TrueLaw("pn", n_gain=5.0, delay=0.1),
    TrueLaw("pn", n_gain=5.0, delay=0.2),
    TrueLaw("mixed", n_gain=2.5, k_gain=2.0, delay=0.1),
    TrueLaw("mixed", n_gain=1.0, k_gain=3.0, delay=0.1),
    TrueLaw("parallel"),
    TrueLaw("parallel", delay=0.2),
    TrueLaw("none"),
]
#: The velocity's time constant under the env's damping: a quarter lost per 0.1 s step.
ENV_LAG = float(DT / np.log(4 / 3))
#: The misspecification control: a low-gain navigation (N 2, about the flat predators' fitted
#: gains) and the collision course (the hierarchical predator's lower layer), each flown as our
#: predators fly: 12 directions 30° apart around the line of sight, each held one step, the
#: velocity lagging with the env's damping.
MISSPECIFIED = [
    TrueLaw("pn", n_gain=2.0, directions=12, hold=DT, velocity_lag=ENV_LAG),
    TrueLaw("parallel", directions=12, hold=DT, velocity_lag=ENV_LAG),
]
#: Samples after the onset in the confusion matrix: the shipped predators' chases have 7 to 19
#: (results/pursuit-law/shipped-1p-low.json), and 35 is the validation's whole attack.
LENGTHS = (8, 12, 16, 20, 35)
#: Samples of history before the onset (pursuit_laws.MAX_DELAY: what our segments carry).
HISTORY = 5
#: Attacks per true law and length.
PER_CELL = 10
#: The confusion matrix's attacks are seeds from here on (held out from the tests' 0 … 4), the
#: first :data:`PER_CELL` that last long enough (an attack ends when the pursuer catches).
FIRST_SEED = 1000
CONFUSION = [
    TrueLaw("none"),
    TrueLaw("pp", k_gain=2.0, delay=0.1),
    TrueLaw("pn", n_gain=3.0, delay=0.1),
    TrueLaw("pn", n_gain=8.0, delay=0.1),
    TrueLaw("mixed", n_gain=2.5, k_gain=2.0, delay=0.1),
    TrueLaw("parallel"),
    *MISSPECIFIED,
]


def record(selection: guidance.Selection, seed: int) -> dict[str, Any]:
    """One selection in full: every law's fit, the chosen law, the floor and the laws under it."""
    return {
        "seed": seed,
        "chosen": selection.chosen.law,
        "samples": selection.chosen.samples,
        "floor": selection.floor,
        "under_floor": selection.under_floor,
        "fits": {
            law: {
                "gains": f.gains,
                "delay": f.delay,
                "censored": f.censored,
                "error": f.error,
                "criterion": f.criterion,
            }
            for law, f in selection.fits.items()
        },
        "relative_errors": selection.relative_errors,
    }


def validation() -> dict[str, Any]:
    cases = []
    for true in CASES + MISSPECIFIED:
        attacks = [record(guidance.select(*attack(true, seed), DT), seed) for seed in range(ATTACKS)]
        cases.append({"true": asdict(true), "attacks": attacks})
        print(f"validation: {true}: {[a['chosen'] for a in attacks]}", flush=True)
    return {"dt": DT, "attacks_per_case": ATTACKS, "cases": cases}


def confusion() -> dict[str, Any]:
    rows = []
    for true in CONFUSION:
        cells: dict[str, Any] = {}
        for n in LENGTHS:
            found: list[dict[str, Any]] = []
            skipped: list[int] = []
            seed = FIRST_SEED
            while len(found) < PER_CELL:
                if seed >= FIRST_SEED + 50 * PER_CELL:
                    raise RuntimeError(f"{true}: fewer than {PER_CELL} attacks of {n} samples in 500 seeds")
                pursuer, target = attack(true, seed, DT, duration=(HISTORY + n) * DT)
                if len(pursuer) == HISTORY + n + 1:
                    found.append(record(guidance.select(pursuer, target, DT, HISTORY, HISTORY), seed))
                else:
                    skipped.append(seed)
                seed += 1
            cells[str(n)] = {"attacks": found, "skipped_seeds": skipped}
            print(f"confusion: {true}, n {n}: {[a['chosen'] for a in found]}", flush=True)
        rows.append({"true": asdict(true), "cells": cells})
    return {
        "dt": DT,
        "history": HISTORY,
        "lengths": list(LENGTHS),
        "per_cell": PER_CELL,
        "first_seed": FIRST_SEED,
        "rows": rows,
    }


def profile_png(path: Path) -> None:
    """The whole-attack error over N for proportional navigation, at the true delay, with the
    initial heading fitted (the model) and with the first chord's direction (no such parameter),
    for three synthetic attacks: N = 3 at 0.1 s and N = 5 at 0.1 s and 0.2 s."""
    gains = np.linspace(0.0, 15.0, 301)
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharey=False)
    for ax, true in zip(
        axes, (TrueLaw("pn", 3.0, 0, 0.1), TrueLaw("pn", 5.0, 0, 0.1), TrueLaw("pn", 5.0, 0, 0.2)), strict=True
    ):
        for seed, color in zip(range(3), ("#4c72b0", "#dd8452", "#55a868"), strict=True):
            pursuer, target = attack(true, seed)
            fitted = guidance.fit(pursuer, target, DT, "pn")
            chord = guidance.profile(pursuer, target, DT, gains, true.delay, 5, None)
            own = guidance.profile(pursuer, target, DT, gains, true.delay, 5, fitted.heading)
            ax.plot(gains, own, color=color, lw=1.4, label=f"attack {seed + 1}: φ₀ fitted")
            ax.plot(gains, chord, color=color, lw=0.9, ls=":", label=f"attack {seed + 1}: φ₀ from one chord")
        ax.axvline(true.n_gain, color="black", lw=0.8)
        ax.set_yscale("log")
        ax.set_xlabel("N", fontsize=8)
        ax.set_ylabel("RMS error after the start", fontsize=8)
        ax.set_title(f"made with N {true.n_gain:g}, τ {true.delay:g} s", fontsize=9)
        ax.tick_params(labelsize=7)
    axes[0].legend(fontsize=6)
    fig.suptitle(
        "Proportional navigation simulated over the whole attack: the error against N (true N: black line)", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--parts", nargs="+", choices=("validation", "confusion"), default=["validation", "confusion"])
    args = parser.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    if "validation" in args.parts:
        atomic_write_text(RESULTS / "validation.json", json.dumps(validation(), indent=1) + "\n")
        profile_png(ROOT / "docs" / "figures" / "law-profile.png")
    if "confusion" in args.parts:
        atomic_write_text(RESULTS / "confusion.json", json.dumps(confusion(), indent=1) + "\n")
    print("written: results/pursuit-law/; the docs' tables: python docs/gen/law_tables.py")


if __name__ == "__main__":
    main()
