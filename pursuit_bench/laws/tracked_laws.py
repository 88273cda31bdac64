"""Pursuit laws fitted to tracked animals (``pursuit-bench law --tracks FILE``): a movement poses
dataset's pursuer and target, on the env's 10 Hz (resampled where the data are sampled
otherwise), cut at the tracking's gaps into attacks, each fitted as :mod:`pursuit_laws` fits an
agent's (the five laws of :mod:`guidance`, one chosen by BIC).

**Where an individual is.** Its ``centroid`` keypoint where the dataset has one, else the mean
of its keypoints at each time (NaN where any is missing).

**Resampling.** Data sampled at another rate are interpolated linearly onto a 0.1 s grid from
the first sample; a grid time between two samples of which one is missing is missing itself.

**Gaps and pieces.** Times where the pursuer's or the target's position is missing split the
track; every stretch without a gap is cut into pieces of at most :data:`PIECE` samples (4 s, the
synthetic attacks' length: a simulation from initial conditions over a long track says more
about chaos than about steering), each with :data:`pursuit_laws.MAX_DELAY` samples of history
before its onset, kept when :data:`pursuit_laws.MIN_STEPS` follow it and the pursuer moves."""

from __future__ import annotations

from typing import Any

import numpy as np

from pursuit_bench.env.world import DT
from pursuit_bench.laws import pursuit_laws

#: The longest piece of a stretch fitted as one attack, in samples after its onset (4 s).
PIECE = 40


def positions(dataset: Any, individual: str) -> np.ndarray:
    """(T, 2) where ``individual`` is at each time (see the module's text); ValueError naming the
    individuals there are for an unknown one."""
    names = [str(i) for i in dataset["individuals"].values]
    if individual not in names:
        raise ValueError(f"no individual {individual!r} in the dataset; it holds {', '.join(names)}")
    position = dataset["position"].sel(individuals=individual)
    if "keypoints" in position.dims:
        keypoints = [str(k) for k in position["keypoints"].values]
        position = position.sel(keypoints="centroid") if "centroid" in keypoints else position.mean("keypoints")
    return np.asarray(position.transpose("time", "space").values[:, :2], dtype=float)


def times(dataset: Any) -> np.ndarray:
    """The dataset's sample times in seconds (its ``time`` coordinate, frames over ``fps`` when
    they are frames); ValueError when there is no time axis to fit along."""
    if "time" not in dataset.dims or dataset.sizes["time"] < 2:
        raise ValueError("the dataset has no time axis with two samples or more")
    values = np.asarray(dataset["time"].values, dtype=float)
    if dataset.attrs.get("time_unit") == "frames":
        fps = dataset.attrs.get("fps")
        if not fps:
            raise ValueError("its time is in frames and it has no fps to make seconds of them")
        values = values / float(fps)
    if np.any(np.diff(values) <= 0):
        raise ValueError("its times do not increase")
    return values


def resampled(track: np.ndarray, at: np.ndarray, dt: float = DT) -> np.ndarray:
    """``track`` (T, 2) sampled at times ``at``, interpolated linearly onto a grid of step ``dt``
    from ``at[0]``; a grid time inside an interval with a missing end is missing."""
    grid = at[0] + dt * np.arange(int(np.floor((at[-1] - at[0]) / dt + 1e-9)) + 1)
    right = np.clip(np.searchsorted(at, grid, side="left"), 1, len(at) - 1)
    left = right - 1
    exact = np.isclose(at[right], grid, rtol=0, atol=1e-9)
    left = np.where(exact, right, left)
    weight = np.where(exact, 0.0, (grid - at[left]) / np.where(exact, 1.0, at[right] - at[left]))
    out = (1 - weight)[:, None] * track[left] + weight[:, None] * track[right]
    missing = np.isnan(track).any(axis=1)
    out[missing[left] | (missing[right] & (weight > 0))] = np.nan
    return out


def stretches(pursuer: np.ndarray, target: np.ndarray) -> list[tuple[int, int]]:
    """The (first, last) samples of every run where both positions are known."""
    known = ~(np.isnan(pursuer).any(axis=1) | np.isnan(target).any(axis=1))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], known.astype(np.int8), [0]])))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def attacks(pursuer: np.ndarray, target: np.ndarray) -> tuple[list[pursuit_laws.Segment], list[tuple[int, int]]]:
    """The pieces fitted (as chase segments of episode 0) and the stretches they come from."""
    found = []
    runs = stretches(pursuer, target)
    history = pursuit_laws.MAX_DELAY
    for first, last in runs:
        for onset in range(first + history, last + 1, PIECE):
            stop = min(onset + PIECE, last)
            p, q = pursuer[onset - history : stop + 1], target[onset - history : stop + 1]
            path = np.linalg.norm(np.diff(p[history:], axis=0), axis=1).sum()
            if stop - onset >= pursuit_laws.MIN_STEPS and path >= pursuit_laws.MIN_PATH:
                found.append(pursuit_laws.Segment(p, q, history, "chase", 0, onset, pursuer, target))
    return found, runs


def fit_tracks(dataset: Any, pursuer: str, target: str, seed: int = 0) -> dict[str, Any]:
    """law --tracks's result: the laws fitted to every piece of ``pursuer`` chasing ``target``,
    with what was done to the data (resampling, the gaps' split)."""
    if dataset.sizes.get("individuals", 0) < 2:
        raise ValueError("the dataset holds one individual: a pursuer and a target are needed")
    if pursuer == target:
        raise ValueError(f"--pursuer and --target are both {pursuer!r}")
    at = times(dataset)
    p, q = positions(dataset, pursuer), positions(dataset, target)
    for name, track in ((pursuer, p), (target, q)):
        if np.isnan(track).all():
            raise ValueError(f"{name}'s track is missing at every time (all NaN)")
    steps = np.diff(at)
    regular = bool(np.allclose(steps, DT, rtol=0, atol=1e-6))
    if not regular:
        p, q = resampled(p, at), resampled(q, at)
    found, runs = attacks(p, q)
    if not found:
        raise ValueError(
            f"no stretch without a gap is long enough to fit: {pursuit_laws.MAX_DELAY + pursuit_laws.MIN_STEPS + 1}"
            f" samples at 10 Hz are needed (the longest here: {max((b - a + 1 for a, b in runs), default=0)})"
        )
    fits = pursuit_laws.fit_segments(found, seed)["chase"]
    return {
        "pursuer": pursuer,
        "target": target,
        "samples": len(at),
        "sampled_every_s": float(np.median(steps)),
        "resampled_to_s": None if regular else DT,
        "stretches": [{"first": a, "last": b, "samples": b - a + 1} for a, b in runs],
        "pieces": len(found),
        "piece_samples": PIECE,
        "dt": DT,
        "criterion": "BIC",
        "attacks": fits,
    }
