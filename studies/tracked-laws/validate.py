"""Validation of ``law --tracks`` on tracks with a known answer (issue 66): synthetic pursuers
following each law (``laws/synthetic_attacks.py``) against a weaving target, written as
movement poses datasets the way a tracker would give them (30 Hz, Gaussian tracking noise on
both animals, and a gap of 0.2 s where the tracker lost both in the attacks flagged for one
(half) that last over 2 s: 16 of the 50), read back and
fitted by ``pursuit-bench law --tracks``'s own path (``tracked_laws.fit_tracks``, which resamples
to 10 Hz and splits at gaps). The confusion matrix counts each piece's chosen law against the
true one.

    python studies/tracked-laws/validate.py --out studies/tracked-laws/validation.json
"""

from __future__ import annotations

import argparse
import json
import tempfile
import warnings
from pathlib import Path

import numpy as np

from pursuit_bench.io import tracks
from pursuit_bench.laws import guidance, synthetic_attacks, tracked_laws

TRUE = {
    "none": synthetic_attacks.TrueLaw("none"),
    "pp": synthetic_attacks.TrueLaw("pp", k_gain=3.0),
    "pn": synthetic_attacks.TrueLaw("pn", n_gain=3.0, delay=0.1),
    "mixed": synthetic_attacks.TrueLaw("mixed", n_gain=2.5, k_gain=2.0, delay=0.1),
    "parallel": synthetic_attacks.TrueLaw("parallel"),
}
FPS, NOISE, SEEDS = 30.0, 0.003, 10


def tracked(true: synthetic_attacks.TrueLaw, seed: int, gap: bool) -> np.ndarray:
    """(time, space, 1, 2) positions of a pursuer and a target as a tracker gives them."""
    pursuer, target = synthetic_attacks.attack(true, seed, dt=1 / FPS, duration=4.0, noise=0.0)
    rng = np.random.default_rng(10_000 + seed)
    both = np.stack([pursuer, target], axis=-1) + rng.normal(scale=NOISE, size=(len(pursuer), 2, 2))
    if gap and len(both) > 60:  # 0.2 s lost in the middle of the attack
        middle = len(both) // 2
        both[middle : middle + round(0.2 * FPS)] = np.nan
    return both[:, :, None, :]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True)
    out = parser.parse_args().out
    from movement.io import load_poses

    warnings.filterwarnings("ignore", message="numpy.ndarray size changed")
    confusion = {t: dict.fromkeys(guidance.LAWS, 0) for t in TRUE}
    attacks = []
    with tempfile.TemporaryDirectory() as work:
        for name, true in TRUE.items():
            for seed in range(SEEDS):
                gap = seed % 2 == 1
                dataset = load_poses.from_numpy(
                    tracked(true, seed, gap), individual_names=["hawk", "pigeon"], keypoint_names=["centroid"],
                    fps=FPS, source_software="synthetic",
                )  # fmt: skip
                path = Path(work) / f"{name}-{seed}.nc"
                tracks.write(dataset, path)
                try:
                    result = tracked_laws.fit_tracks(tracks.read(path), "hawk", "pigeon")
                except ValueError as error:  # an attack caught too soon, or cut too short by its gap
                    attacks.append({"true": name, "seed": seed, "gap": gap, "refused": str(error)})
                    continue
                for chosen in result["attacks"]["chosen"]:
                    confusion[name][chosen] += 1
                attacks.append(
                    {"true": name, "seed": seed, "gap": gap, "stretches": len(result["stretches"]),
                     "chosen": result["attacks"]["chosen"]}
                )  # fmt: skip
    document = {
        "command": "python studies/tracked-laws/validate.py --out studies/tracked-laws/validation.json",
        "fps": FPS,
        "noise": NOISE,
        "seeds": SEEDS,
        "true_laws": {k: {"law": v.law, "N": v.n_gain, "K": v.k_gain, "delay": v.delay} for k, v in TRUE.items()},
        "confusion": confusion,
        "attacks": attacks,
    }
    out.write_text(json.dumps(document, indent=2) + "\n")
    print(confusion_table(confusion))


def confusion_table(confusion: dict[str, dict[str, int]]) -> str:
    """The confusion matrix as docs/pursuit-law.md prints it (true law by row, chosen by column)."""
    lines = ["| true \\ chosen | " + " | ".join(guidance.LAWS) + " |", "|---|" + "---:|" * len(guidance.LAWS)]
    lines += [
        f"| {name} | " + " | ".join(str(row[law]) for law in guidance.LAWS) + " |" for name, row in confusion.items()
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
