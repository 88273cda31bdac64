"""Pursuit laws fitted to trajectories, as biologists fit them to falcons and hawks (Brighton,
Thomas & Taylor, PNAS 2017; Brighton & Taylor, Nat. Commun. 2019). Pure numpy (and scipy's
bounded optimisers).

A *law* gives the pursuer's turn rate ω (the rate of change of its heading θ):

- ``"pp"``, proportional pursuit: ω(t) = K δ(t − τ), δ the deviation angle from the pursuer's
  velocity to the line of sight to the target (K in 1/s);
- ``"pn"``, proportional navigation: ω(t) = N λ̇(t − τ), λ the line-of-sight angle (N unitless);
- ``"mixed"``: ω(t) = N λ̇(t − τ) + K δ(t − τ).

Conventions:

- Angles are in radians, counter-clockwise positive, from the x axis; θ(t) is the heading of
  the step from sample t to t + 1 (the chord), the velocity *at* sample t is taken midway
  between the chords on either side of it; δ = wrap(λ − that heading) and
  λ̇ = wrap(λ(t) − λ(t − dt)) / dt, wrapped to (−π, π]. A positive δ or λ̇ turns the pursuer
  counter-clockwise.
- Speed is taken from the data: the pursuer's measured speed over step t, |p(t+1) − p(t)| / dt,
  is the simulated pursuer's speed over step t; only the heading is the law's.
- :func:`simulate` starts at the measured first position and heading and integrates by Euler
  steps: p(t+1) = p(t) + dt s(t) u(θ(t)), θ(t+1) = θ(t) + dt ω(t). The line of sight runs from
  the *simulated* pursuer to the *measured* target. With a delay of d steps, the first d
  headings are the measured ones (the law has nothing to act on before the start), and from then
  on ω(t) uses the simulated state d steps earlier. λ̇ at the first position is 0 (there is no
  earlier line of sight). A simulation restarted at step s (``window``) starts from the measured
  position and heading there and reads the measured state before s while the delayed law needs it.
- The error is the mean distance between simulated and measured positions; r² is that of the
  positions, 1 − Σ|p_sim − p|² / Σ|p − p̄|².

Fitting (:func:`fit`): the simulation is restarted from the measured position and heading every
``WINDOW`` steps (1 s), so that an error in one heading does not grow over the whole pursuit;
for each delay of 0 … ``max_delay`` steps, the gains are first regressed
(the measured turn rate on the delayed δ and λ̇, least squares: robust where a whole-trajectory
simulation is ill-conditioned, as proportional navigation's can be at 10 Hz), then refined on a
coarse grid around that start and by a bounded optimiser (L-BFGS-B) on the simulation error;
the delay and gains with the smallest error win.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

LAWS = ("pp", "pn", "mixed")
#: Bounds of the fitted gains: K (1/s) and N (unitless).
GAIN_BOUNDS = {"K": (0.0, 30.0), "N": (0.0, 15.0)}
#: Steps after which :func:`fit` restarts its simulations from the measured state (1 s at 10 Hz).
WINDOW = 10
#: Gains each law uses.
LAW_GAINS = {"pp": ("K",), "pn": ("N",), "mixed": ("N", "K")}


@dataclass(frozen=True)
class LawFit:
    """One law fitted to one pursuit."""

    law: str
    """``"pp"``, ``"pn"`` or ``"mixed"``."""
    gains: dict[str, float]
    """``{"K": …}``, ``{"N": …}`` or both."""
    delay: float
    """The sensorimotor delay τ in seconds (a multiple of dt)."""
    error: float
    """Mean distance between simulated and measured positions."""
    r2: float
    """r² of the positions."""
    simulated: np.ndarray = field(repr=False, compare=False)
    """(T, 2) the trajectory the fitted law produces."""


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def _checked(pursuer: np.ndarray, target: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    pursuer, target = np.asarray(pursuer, dtype=float), np.asarray(target, dtype=float)
    if pursuer.ndim != 2 or pursuer.shape[1] != 2 or pursuer.shape != target.shape:
        raise ValueError(f"pursuer {pursuer.shape} and target {target.shape}: expected two (T, 2) arrays")
    if len(pursuer) < 5:
        raise ValueError(f"a pursuit of {len(pursuer)} positions: expected at least 5")
    if not (np.isfinite(pursuer).all() and np.isfinite(target).all()):
        raise ValueError("positions hold NaN or infinite values: expected finite numbers")
    if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt={dt!r}: expected a time step > 0 in seconds")
    steps = np.linalg.norm(np.diff(pursuer, axis=0), axis=1)
    if steps.sum() < 1e-9 or steps[0] < 1e-12:
        raise ValueError("the pursuer does not move (or not on its first step): no heading to start from")
    return pursuer, target


def _delay_steps(delay: float, dt: float) -> int:
    steps = round(delay / dt)
    if delay < 0 or abs(steps * dt - delay) > 1e-6 * max(dt, 1.0):
        raise ValueError(f"delay={delay!r}: expected a multiple of dt={dt} that is >= 0")
    return int(steps)


def _simulate_many(
    n_gain: np.ndarray,
    k_gain: np.ndarray,
    d: int,
    pursuer: np.ndarray,
    target: np.ndarray,
    dt: float,
    window: int | None = None,
) -> np.ndarray:
    """(G, T, 2) trajectories for G gain pairs (N, K) at once (the law is N λ̇ + K δ); with a
    ``window``, restarted from the measured position and heading every ``window`` steps."""
    if window is not None and window < len(pursuer) - 1:
        pieces = []
        for start in range(0, len(pursuer) - 1, window):
            stop = min(start + window, len(pursuer) - 1)
            lo = max(start - d - 1, 0)  # the measured past the delayed law reads at the restart
            piece = _simulate_window(n_gain, k_gain, d, pursuer[lo : stop + 1], target[lo : stop + 1], dt, start - lo)
            pieces.append(piece[:, start - lo + 1 :])
        return np.concatenate([np.broadcast_to(pursuer[0], (len(n_gain), 1, 2)), *pieces], axis=1)
    return _simulate_window(n_gain, k_gain, d, pursuer, target, dt, 0)


def _simulate_window(
    n_gain: np.ndarray, k_gain: np.ndarray, d: int, pursuer: np.ndarray, target: np.ndarray, dt: float, known: int
) -> np.ndarray:
    """The simulation from position ``known`` on; positions and headings before it are the
    measured ones, which the delayed law reads until the simulated state is old enough."""
    g, t_len = len(n_gain), len(pursuer)
    velocity = np.diff(pursuer, axis=0) / dt
    speed = np.linalg.norm(velocity, axis=1)
    measured_heading = np.arctan2(velocity[:, 1], velocity[:, 0])
    positions = np.empty((g, t_len, 2))
    positions[:, : known + 1] = pursuer[: known + 1]
    heading = np.empty((g, t_len - 1))
    los = np.empty((g, t_len - 1))
    heading[:, : known + 1] = measured_heading[: known + 1]
    for t in range(t_len - 1):
        delta = target[t] - positions[:, t]
        los[:, t] = np.arctan2(delta[:, 1], delta[:, 0])
        if t > known:
            i = t - 1 - d  # the state the turn from t-1 to t acts on (measured before ``known``)
            if i < 0:
                heading[:, t] = measured_heading[t]
            else:
                los_rate = _wrap(los[:, i] - los[:, i - 1]) / dt if i > 0 else np.zeros(g)
                # the velocity at sample i lies between the chords before and after it
                at_sample = heading[:, i] - _wrap(heading[:, i] - heading[:, i - 1]) / 2 if i > 0 else heading[:, i]
                deviation = _wrap(los[:, i] - at_sample)
                heading[:, t] = heading[:, t - 1] + dt * (n_gain * los_rate + k_gain * deviation)
        if t < known:
            continue
        step = dt * speed[t]
        positions[:, t + 1, 0] = positions[:, t, 0] + step * np.cos(heading[:, t])
        positions[:, t + 1, 1] = positions[:, t, 1] + step * np.sin(heading[:, t])
    return positions


def _gain_pair(law: str, gains: dict[str, float]) -> tuple[float, float]:
    if law not in LAWS:
        raise ValueError(f"law={law!r}: expected one of {', '.join(LAWS)}")
    needed = set(LAW_GAINS[law])
    if set(gains) != needed:
        raise ValueError(f"gains {sorted(gains)} for law {law!r}: expected {sorted(needed)}")
    return float(gains.get("N", 0.0)), float(gains.get("K", 0.0))


def simulate(
    law: str,
    gains: dict[str, float],
    delay: float,
    pursuer: np.ndarray,
    target: np.ndarray,
    dt: float,
    window: int | None = None,
) -> np.ndarray:
    """The (T, 2) trajectory ``law`` with these ``gains`` and ``delay`` (seconds) produces from
    the pursuer's first position and heading, with its measured speed at each step, against the
    target's measured path (see the module's conventions). With a ``window`` (steps), the
    simulation restarts from the measured position and heading every ``window`` steps (the
    line of sight before the restart is the measured one)."""
    pursuer, target = _checked(pursuer, target, dt)
    n_gain, k_gain = _gain_pair(law, gains)
    d = _delay_steps(delay, dt)
    return _simulate_many(np.array([n_gain]), np.array([k_gain]), d, pursuer, target, dt, window)[0]


def _errors(simulated: np.ndarray, pursuer: np.ndarray) -> np.ndarray:
    return np.linalg.norm(simulated - pursuer, axis=-1)[..., 1:].mean(axis=-1)


def _r2(simulated: np.ndarray, pursuer: np.ndarray) -> float:
    total = float(((pursuer - pursuer.mean(axis=0)) ** 2).sum())
    residual = float(((simulated - pursuer) ** 2).sum())
    return 1.0 - residual / total if total > 0 else float("nan")


def _regressed(law: str, d: int, pursuer: np.ndarray, target: np.ndarray, dt: float) -> np.ndarray:
    """Gains from least squares of the measured turn rate on the delayed δ and λ̇ (a start)."""
    velocity = np.diff(pursuer, axis=0) / dt
    heading = np.unwrap(np.arctan2(velocity[:, 1], velocity[:, 0]))
    los = np.arctan2(*(target - pursuer).T[::-1])[:-1]
    turn = np.diff(heading) / dt  # ω(t), t = 0 … T-3
    los_rate = np.concatenate([[0.0], _wrap(np.diff(los)) / dt])
    at_sample = np.concatenate([heading[:1], (heading[1:] + heading[:-1]) / 2])
    deviation = _wrap(los - at_sample)
    rows = np.arange(d, len(turn))
    columns = {"N": los_rate[rows - d], "K": deviation[rows - d]}
    names = LAW_GAINS[law]
    if len(rows) < len(names):
        return np.array([np.mean(GAIN_BOUNDS[n]) for n in names])
    design = np.stack([columns[n] for n in names], axis=1)
    solution, *_ = np.linalg.lstsq(design, turn[rows], rcond=None)
    return np.array([np.clip(v, *GAIN_BOUNDS[n]) for v, n in zip(solution, names, strict=True)])


def _fit_delay(
    law: str, d: int, pursuer: np.ndarray, target: np.ndarray, dt: float, window: int | None
) -> tuple[np.ndarray, float]:
    names = LAW_GAINS[law]
    bounds = [GAIN_BOUNDS[n] for n in names]

    def pairs(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        values = np.atleast_2d(values)
        by_name = {n: values[:, j] for j, n in enumerate(names)}
        zero = np.zeros(len(values))
        return by_name.get("N", zero), by_name.get("K", zero)

    def errors(values: np.ndarray) -> np.ndarray:
        return _errors(_simulate_many(*pairs(values), d, pursuer, target, dt, window), pursuer)

    start = _regressed(law, d, pursuer, target, dt)
    axes = [np.unique(np.concatenate([np.linspace(lo, hi, 9), [s]])) for (lo, hi), s in zip(bounds, start, strict=True)]
    grid = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
    candidates = np.concatenate([grid, start[None]])
    coarse = errors(candidates)
    best = candidates[int(np.argmin(coarse))]
    refined = optimize.minimize(lambda v: float(errors(v)[0]), best, method="L-BFGS-B", bounds=bounds)
    if refined.fun < coarse.min():
        return np.asarray(refined.x), float(refined.fun)
    return best, float(coarse.min())


def fit(
    pursuer: np.ndarray, target: np.ndarray, dt: float, law: str, max_delay: int = 5, window: int | None = WINDOW
) -> LawFit:
    """Fit ``law`` to one pursuit: ``pursuer`` and ``target`` (T, 2) positions sampled every
    ``dt`` seconds; delays of 0 … ``max_delay`` steps are tried. The error is that of the
    simulation restarted from the measured state every ``window`` steps (None: one simulation
    of the whole pursuit, which noise in the first heading makes ill-conditioned for
    proportional navigation at 10 Hz: docs/pursuit-law.md). ValueError for too short or
    degenerate input (T < 5, a pursuer that does not move, NaNs)."""
    pursuer, target = _checked(pursuer, target, dt)
    if law not in LAWS:
        raise ValueError(f"law={law!r}: expected one of {', '.join(LAWS)}")
    max_delay = min(int(max_delay), len(pursuer) - 3)
    best: tuple[float, int, np.ndarray] | None = None
    for d in range(max_delay + 1):
        values, error = _fit_delay(law, d, pursuer, target, dt, window)
        if best is None or error < best[0] - 1e-12:
            best = (error, d, values)
    assert best is not None
    error, d, values = best
    gains = {n: float(v) for n, v in zip(LAW_GAINS[law], values, strict=True)}
    simulated = simulate(law, gains, d * dt, pursuer, target, dt, window)
    return LawFit(law, gains, d * dt, float(error), _r2(simulated, pursuer), simulated)


def fit_all(
    pursuer: np.ndarray, target: np.ndarray, dt: float, max_delay: int = 5, window: int | None = WINDOW
) -> dict[str, LawFit]:
    """Every law fitted to one pursuit, by name."""
    return {law: fit(pursuer, target, dt, law, max_delay, window) for law in LAWS}


def winner(fits: dict[str, LawFit], margin: float = 0.3) -> str:
    """The law that describes a pursuit best: the single law (pp or pn) with the smaller error,
    unless the mixed law, which holds both and has a gain more, cuts that error by more than
    ``margin`` (relative): a gain more always fits noise, and at 10 Hz the mismatch between a
    continuous pursuit and its discrete simulation, a few per cent (docs/pursuit-law.md)."""
    single = min(("pp", "pn"), key=lambda law: fits[law].error)
    if "mixed" in fits and fits["mixed"].error < (1 - margin) * fits[single].error:
        return "mixed"
    return single
