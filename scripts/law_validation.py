"""The pursuit-law method's validation (docs/pursuit-law.md): synthetic attacks by each law in
continuous time, sampled at 10 Hz with 0.001 of position noise, five per case; every law fitted,
one chosen by BIC. Writes results/pursuit-law/validation.json (every fit, full precision) and
docs/figures/law-profile.png (the whole-attack error over N: how well N is determined), and
prints the docs' table.

    python scripts/law_validation.py            # about 30 s
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.study import guidance
from pursuit_bench.study.synthetic_attacks import TrueLaw, attack

ROOT = Path(__file__).resolve().parent.parent
DT = 0.1
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


def made_with(true: TrueLaw) -> str:
    gains = [f"N {true.n_gain:g}" for _ in [0] if "N" in guidance.LAW_GAINS[true.law]]
    gains += [f"K {true.k_gain:g}" for _ in [0] if "K" in guidance.LAW_GAINS[true.law]]
    delay = [f"τ {true.delay:g} s"] if true.law != "none" else []
    return ", ".join(gains + delay) or "-"


def main() -> None:
    rows = []
    for true in CASES:
        attacks = []
        for seed in range(5):
            selection = guidance.select(*attack(true, seed), DT)
            own = selection.fits[true.law]
            attacks.append(
                {
                    "seed": seed,
                    "chosen": selection.chosen.law,
                    "samples": own.samples,
                    "gains": own.gains,
                    "delay": own.delay,
                    "censored": own.censored,
                    "criteria": selection.criteria,
                    "relative_errors": selection.relative_errors,
                }
            )
        rows.append({"true": asdict(true), "attacks": attacks})
    out = ROOT / "results" / "pursuit-law"
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "validation.json", json.dumps({"cases": rows}, indent=1) + "\n")
    print("| law | made with | chosen as itself | its fitted gains (5 attacks) | delays (s) | error relative to none |")
    print("|---|---|---:|---|---|---:|")
    for row in rows:
        true = TrueLaw(**row["true"])
        own = [a["chosen"] for a in row["attacks"]]
        hits = sum(c == true.law for c in own)
        others = sorted({c for c in own if c != true.law})
        gains = "; ".join(
            ", ".join(f"{k} {v:.2f}" for k, v in a["gains"].items()) for a in row["attacks"] if a["gains"]
        )
        delays = ", ".join(f"{a['delay']:g}" for a in row["attacks"])
        relative = np.median([a["relative_errors"][true.law] for a in row["attacks"]])
        chosen = f"{hits} of 5" + (f" (else {', '.join(others)})" if others else "")
        print(f"| {true.law} | {made_with(true)} | {chosen} | {gains or '-'} | {delays} | {relative:.3f} |")
    profile_png(ROOT / "docs" / "figures" / "law-profile.png")


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


if __name__ == "__main__":
    main()
