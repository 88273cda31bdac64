"""Pursuit laws fitted to attacks, as biologists fit them to falcons and hawks (Brighton, Thomas
& Taylor, PNAS 2017; Brighton & Taylor, Nat. Commun. 2019): each law simulated over the whole
attack from its initial conditions, against the target's measured path at the pursuer's measured
speed, and the laws compared by a stated criterion. numpy and numba (the simulation kernel).

A *law* gives the pursuer's heading φ (the direction of its velocity):

- ``"none"``: straight on, φ constant: the null every law must beat (parameter: φ₀);
- ``"pp"``, proportional pursuit: φ̇(t) = K δ(t − τ), δ the deviation angle from the velocity
  to the line of sight (K in 1/s; parameters K, τ, φ₀);
- ``"pn"``, proportional navigation: φ̇(t) = N λ̇(t − τ), λ the line-of-sight angle
  (N unitless; parameters N, τ, φ₀);
- ``"mixed"``: φ̇(t) = N λ̇(t − τ) + K δ(t − τ) (parameters N, K, τ, φ₀);
- ``"parallel"``, ideal parallel navigation: φ(t) = λ(t − τ) + arcsin(v⊥ / s), the collision
  course that keeps the line of sight's direction constant, v⊥ the target's measured velocity
  across the line of sight and s the pursuer's measured speed, both at t − τ (the argument
  clipped to ±1 when the target is too fast for a collision course; parameter τ). It is the
  limit N → ∞ of proportional navigation, which no bounded N represents.

Conventions: angles in radians, counter-clockwise from the x axis, wrapped to (−π, π] where
compared. The simulation (:func:`simulate`) runs in :data:`SUBSTEPS` sub-steps per sample (the
laws are continuous-time; at 10 Hz an Euler step of a whole sample lags a fast turn): the target
and the pursuer's measured positions are interpolated linearly between samples, the pursuer
moves at its measured speed over each sample interval (only the heading is the law's), and the
line of sight runs from the *simulated* pursuer to the *measured* target. Every law and every
delay starts at the same sample ``start`` (the attack's first sample) from the measured position
there and the initial heading φ₀ (fitted: one chord's direction is a noisy estimate, and
proportional navigation never corrects a heading error, docs/pursuit-law.md); before ``start``
the delayed laws read the *measured* states (the attack's history), so a longer delay buys no
measured heading. The error is counted over the samples after ``start`` only, the same for
every law and delay.

Model selection (:func:`select`): the Bayesian information criterion under a stated error
model: each simulated sample's position error is an independent isotropic Gaussian, its mean
square distance ``msd = RSS / n`` over the n samples after ``start`` estimating its variance,
floored at the square of the larger of :data:`PRECISION` and :data:`TOLERANCE` times the
distance the pursuer travels after ``start`` (below it errors are the positions' noise or the
simulation's own); ``BIC = n ln msd + k ln n`` with k each law's count of free parameters
(:data:`PARAMETERS`, the delay included). One observation per sample (not per coordinate) is
the conservative count: neighbouring samples' errors are correlated, so the data hold fewer
independent observations than samples, never more. Laws whose errors are both under the floor
tie but for k: the one with fewer parameters wins, and between equal k the first in
:data:`LAWS` (:attr:`Selection.under_floor`; on short attacks this decides many choices,
docs/pursuit-law.md). The fit's quality is its error relative to ``"none"``.

Gains are bounded (:data:`GAIN_BOUNDS`) and delays run over 0 … ``max_delay`` samples; a fit
whose optimum lies at a bound is *censored* there (:attr:`LawFit.censored`): reported as
``">15"``, never averaged with interior fits (a median that counts them:
:func:`pursuit_bench.laws.pursuit_laws.censored_median`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

LAWS = ("none", "pp", "pn", "mixed", "parallel")
#: Gains each law uses.
LAW_GAINS: dict[str, tuple[str, ...]] = {"none": (), "pp": ("K",), "pn": ("N",), "mixed": ("N", "K"), "parallel": ()}
#: Free parameters per law: its gains, the delay (not for ``"none"``) and the initial heading
#: (not for ``"parallel"``, which sets the heading from the first sample on).
PARAMETERS = {"none": 1, "pp": 3, "pn": 3, "mixed": 4, "parallel": 1}
#: Bounds of the fitted gains: K (1/s) and N (unitless).
GAIN_BOUNDS = {"K": (0.0, 30.0), "N": (0.0, 15.0)}
#: Sub-steps of the simulation per sample.
SUBSTEPS = 10
#: The positions' precision (arena units, 0.1 % of the arena's width): mean square errors
#: below its square are not told apart.
PRECISION = 0.002
#: The simulation's accuracy, relative to the distance the pursuer travels after the start:
#: errors below this fraction of it are not told apart (a continuous-time pursuit simulated at
#: :data:`SUBSTEPS` sub-steps per sample is reproduced to about this: docs/pursuit-law.md).
TOLERANCE = 0.003
#: How far the fitted initial heading may lie from the first chord's direction (radians).
HEADING_RANGE = 0.4
#: A gain within this fraction of its range from a bound is at that bound (censored).
AT_BOUND = 0.01
_LAW_CODES = {law: code for code, law in enumerate(LAWS)}
_ZOOM_ROUNDS = 5


@dataclass(frozen=True)
class LawFit:
    """One law fitted to one attack."""

    law: str
    """One of :data:`LAWS`."""
    gains: dict[str, float]
    """``{"K": …}``, ``{"N": …}``, both, or none."""
    delay: float
    """The sensorimotor delay τ in seconds (a multiple of dt; 0 for ``"none"``)."""
    heading: float
    """The fitted initial heading φ₀ (radians; for ``"parallel"`` the law's own first heading)."""
    censored: dict[str, str]
    """Each gain, or ``"delay"``, whose optimum lies at a bound: ``"lower"`` or ``"upper"``."""
    error: float
    """Root mean square distance between simulated and measured positions after ``start``."""
    criterion: float
    """BIC (see the module's text): lower is better."""
    samples: int
    """n: the samples the error is counted over."""
    start: int
    """The sample the simulation starts from."""
    simulated: np.ndarray = field(repr=False, compare=False)
    """(T, 2) the trajectory the fitted law produces (the measured positions up to ``start``)."""


@dataclass(frozen=True)
class Selection:
    """Every law fitted to one attack and the one the criterion chooses."""

    chosen: LawFit
    """The fit of the law with the lowest criterion."""
    fits: dict[str, LawFit]
    """Every law's fit, by name."""
    floor: float = float("nan")
    """The error (RMS distance) below which laws are not told apart (:data:`TOLERANCE`)."""

    @property
    def under_floor(self) -> list[str]:
        """The laws whose error is at or below :attr:`floor`: their criteria differ only by their
        counts of parameters, so among them the one with the fewest wins, and among equal counts
        the first in :data:`LAWS` (``"pp"`` before ``"pn"``): a choice the data do not make."""
        return [law for law, f in self.fits.items() if f.error <= self.floor]

    @property
    def criteria(self) -> dict[str, float]:
        """Every law's BIC."""
        return {law: f.criterion for law, f in self.fits.items()}

    @property
    def relative_errors(self) -> dict[str, float]:
        """Every law's error over that of ``"none"`` (1: no better than going straight on)."""
        none = self.fits["none"].error
        return {law: f.error / none if none > 0 else float("nan") for law, f in self.fits.items()}


def _wrap(angle: np.ndarray) -> np.ndarray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def _checked(pursuer: np.ndarray, target: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    pursuer, target = np.asarray(pursuer, dtype=float), np.asarray(target, dtype=float)
    if pursuer.ndim != 2 or pursuer.shape[1] != 2 or pursuer.shape != target.shape:
        raise ValueError(f"pursuer {pursuer.shape} and target {target.shape}: expected two (T, 2) arrays")
    if len(pursuer) < 5:
        raise ValueError(f"an attack of {len(pursuer)} positions: expected at least 5")
    if not (np.isfinite(pursuer).all() and np.isfinite(target).all()):
        raise ValueError("positions hold NaN or infinite values: expected finite numbers")
    if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt={dt!r}: expected a time step > 0 in seconds")
    steps = np.linalg.norm(np.diff(pursuer, axis=0), axis=1)
    if steps.sum() < 1e-9:
        raise ValueError("the pursuer does not move: no heading to start from")
    return pursuer, target


def _checked_start(start: int | None, max_delay: int, length: int) -> int:
    start = min(max_delay, length - 5) if start is None else start
    if not (isinstance(start, (int, np.integer)) and 0 <= start <= length - 5):
        raise ValueError(f"start={start!r}: expected a sample 0 … {length - 5} (at least 4 simulated steps after it)")
    return int(start)


def _prepared(pursuer: np.ndarray, target: np.ndarray, dt: float, max_delay: int, start: int | None) -> _Attack:
    """The checked attack at sub-step resolution, for :func:`fit` and :func:`select`."""
    pursuer, target = _checked(pursuer, target, dt)
    if not (isinstance(max_delay, (int, np.integer)) and max_delay >= 0):
        raise ValueError(f"max_delay={max_delay!r}: expected a number of samples >= 0")
    return _attack(pursuer, target, dt, _checked_start(start, int(max_delay), len(pursuer)))


def _delay_steps(delay: float, dt: float) -> int:
    steps = round(delay / dt)
    if delay < 0 or abs(steps * dt - delay) > 1e-6 * max(dt, 1.0):
        raise ValueError(f"delay={delay!r}: expected a multiple of dt={dt} that is >= 0")
    return int(steps)


@dataclass(frozen=True)
class _Attack:
    """The measured attack at sub-step resolution."""

    pursuer: np.ndarray  # (T, 2) samples
    start: int
    dt: float
    target: np.ndarray  # (U, 2) sub-steps, interpolated
    target_velocity: np.ndarray  # (U, 2): the chord velocity of the sample interval holding each sub-step
    speed: np.ndarray  # (U,): the pursuer's chord speed likewise
    los: np.ndarray  # (U,): the measured line of sight (the history the delayed laws read)
    heading: np.ndarray  # (U,): the measured chord heading
    first_heading: float  # the direction of the chord leaving ``start``


def _attack(pursuer: np.ndarray, target: np.ndarray, dt: float, start: int) -> _Attack:
    fraction = np.arange(SUBSTEPS) / SUBSTEPS

    def fine(samples: np.ndarray) -> np.ndarray:
        chords = np.diff(samples, axis=0)
        inner = samples[:-1, None, :] + fraction[None, :, None] * chords[:, None, :]
        return np.concatenate([inner.reshape(-1, samples.shape[1]), samples[-1:]])

    def per_interval(values: np.ndarray) -> np.ndarray:
        return np.concatenate([np.repeat(values, SUBSTEPS, axis=0), values[-1:]])

    chords = np.diff(pursuer, axis=0)
    headings = np.arctan2(chords[:, 1], chords[:, 0])
    moving = np.linalg.norm(chords, axis=1) > 1e-12
    if not moving[start:].any():
        raise ValueError("the pursuer does not move after the attack's start: no heading to start from")
    first = int(start + np.argmax(moving[start:]))
    pursuer_fine, target_fine = fine(pursuer), fine(target)
    los = np.arctan2(target_fine[:, 1] - pursuer_fine[:, 1], target_fine[:, 0] - pursuer_fine[:, 0])
    return _Attack(
        pursuer=pursuer,
        start=start,
        dt=dt,
        target=target_fine,
        target_velocity=per_interval(np.diff(target, axis=0) / dt),
        speed=per_interval(np.linalg.norm(chords, axis=1) / dt),
        los=los,
        heading=per_interval(headings),
        first_heading=float(headings[first]),
    )


@numba.njit(cache=True)
def _simulate_kernel(
    law: int,
    n_gain: np.ndarray,
    k_gain: np.ndarray,
    heading0: np.ndarray,
    lag: np.ndarray,
    start: int,
    substeps: int,
    h: float,
    origin: np.ndarray,
    target: np.ndarray,
    target_velocity: np.ndarray,
    speed: np.ndarray,
    los_history: np.ndarray,
    heading_history: np.ndarray,
    out: np.ndarray,
) -> None:
    """Each candidate's sample positions after ``start`` into ``out`` (G, T, 2); see the module."""
    n_fine = len(los_history)
    first = start * substeps
    los = np.empty(n_fine)
    heading = np.empty(n_fine)
    for g in range(len(n_gain)):
        los[: first + 1] = los_history[: first + 1]
        heading[:first] = heading_history[:first]
        x, y = origin[0], origin[1]
        for u in range(first, n_fine - 1):
            los[u] = np.arctan2(target[u, 1] - y, target[u, 0] - x)
            if law == 4:  # parallel: the collision course from the state lag sub-steps ago
                i = max(u - lag[g], 0)
                across = -target_velocity[i, 0] * np.sin(los[i]) + target_velocity[i, 1] * np.cos(los[i])
                ratio = across / speed[i] if speed[i] > 1e-12 else 0.0
                heading[u] = los[i] + np.arcsin(min(1.0, max(-1.0, ratio)))
            elif u == first:
                heading[u] = heading0[g]
            elif law == 0:
                heading[u] = heading[u - 1]
            else:  # the turn over sub-step u-1 → u acts on the state lag sub-steps before u-1
                i = max(u - 1 - lag[g], 0)  # before the first sample: its state, the line of sight still
                rate = (los[i] - los[i - 1] + np.pi) % (2 * np.pi) - np.pi if i > 0 else 0.0
                deviation = (los[i] - heading[i] + np.pi) % (2 * np.pi) - np.pi
                heading[u] = heading[u - 1] + h * (n_gain[g] * rate / h + k_gain[g] * deviation)
            # over the sub-step the heading keeps turning: move at its extrapolated midpoint
            moving = heading[u] + 0.5 * (heading[u] - heading[u - 1]) if u > first else heading[u]
            x += h * speed[u] * np.cos(moving)
            y += h * speed[u] * np.sin(moving)
            if (u + 1) % substeps == 0:
                out[g, (u + 1) // substeps, 0] = x
                out[g, (u + 1) // substeps, 1] = y


def _run(law: str, values: np.ndarray, attack: _Attack) -> np.ndarray:
    """(G, T, 2) trajectories for G candidates ``values`` (G, 4): N, K, φ₀, delay in samples."""
    values = np.atleast_2d(values)
    out = np.empty((len(values), len(attack.pursuer), 2))
    out[:, : attack.start + 1] = attack.pursuer[: attack.start + 1]
    _simulate_kernel(
        _LAW_CODES[law],
        np.ascontiguousarray(values[:, 0]),
        np.ascontiguousarray(values[:, 1]),
        np.ascontiguousarray(values[:, 2]),
        np.ascontiguousarray(values[:, 3]).astype(np.int64) * SUBSTEPS,
        attack.start,
        SUBSTEPS,
        attack.dt / SUBSTEPS,
        attack.pursuer[attack.start],
        attack.target,
        attack.target_velocity,
        attack.speed,
        attack.los,
        attack.heading,
        out,
    )
    return out


def _square_errors(simulated: np.ndarray, attack: _Attack) -> np.ndarray:
    """Each candidate's (G, T, 2) summed squared distance after ``start``, in one fixed order (numpy's
    vectorised sums round by the memory's alignment, which varies from run to run, and the fit
    picks among near-ties)."""
    return _square_errors_kernel(simulated, attack.pursuer, attack.start)


@numba.njit(cache=True)
def _square_errors_kernel(simulated: np.ndarray, measured: np.ndarray, start: int) -> np.ndarray:
    total = np.zeros(len(simulated))
    for g in range(len(simulated)):
        for t in range(start + 1, len(measured)):
            total[g] += (simulated[g, t, 0] - measured[t, 0]) ** 2 + (simulated[g, t, 1] - measured[t, 1]) ** 2
    return total


def _gain_values(law: str, gains: dict[str, float]) -> tuple[float, float]:
    if law not in LAWS:
        raise ValueError(f"law={law!r}: expected one of {', '.join(LAWS)}")
    needed = set(LAW_GAINS[law])
    if set(gains) != needed:
        raise ValueError(f"gains {sorted(gains)} for law {law!r}: expected {sorted(needed) or 'none'}")
    return float(gains.get("N", 0.0)), float(gains.get("K", 0.0))


def simulate(
    law: str,
    gains: dict[str, float],
    delay: float,
    pursuer: np.ndarray,
    target: np.ndarray,
    dt: float,
    start: int = 0,
    heading: float | None = None,
) -> np.ndarray:
    """The (T, 2) trajectory ``law`` with these ``gains`` and ``delay`` (seconds) produces from
    the measured position at sample ``start`` and the initial ``heading`` (default: the
    direction of the chord leaving ``start``), at the pursuer's measured speed, against the
    target's measured path (see the module's conventions); positions up to ``start`` are the
    measured ones."""
    pursuer, target = _checked(pursuer, target, dt)
    n_gain, k_gain = _gain_values(law, gains)
    start = _checked_start(start, 0, len(pursuer))
    attack = _attack(pursuer, target, dt, start)
    heading = attack.first_heading if heading is None else float(heading)
    return _run(law, np.array([n_gain, k_gain, heading, _delay_steps(delay, dt)]), attack)[0]


def _floor(attack: _Attack) -> float:
    """The error below which laws are not told apart (see :data:`TOLERANCE`)."""
    path = float(np.linalg.norm(np.diff(attack.pursuer[attack.start :], axis=0), axis=1).sum())
    return max(PRECISION, TOLERANCE * path)


def _criterion(square_error: float, samples: int, law: str, floor: float) -> float:
    msd = max(square_error / samples, floor**2)
    return float(samples * np.log(msd) + PARAMETERS[law] * np.log(samples))


def _grid(law: str, attack: _Attack, max_delay: int) -> np.ndarray:
    """The coarse candidates: 9 values per gain, 5 initial headings, every delay."""
    names = LAW_GAINS[law]
    axes = {n: np.linspace(*GAIN_BOUNDS[n], 9) for n in names}
    n_axis = axes.get("N", np.zeros(1))
    k_axis = axes.get("K", np.zeros(1))
    headings = attack.first_heading + (
        np.linspace(-HEADING_RANGE, HEADING_RANGE, 5) if law != "parallel" else np.zeros(1)
    )
    delays = np.arange(max_delay + 1) if law != "none" else np.zeros(1)
    mesh = np.meshgrid(n_axis, k_axis, headings, delays, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def _fit_values(
    law: str, attack: _Attack, max_delay: int, extra: tuple[np.ndarray, ...] = ()
) -> tuple[np.ndarray, float]:
    """The best candidate (N, K, φ₀, delay) and its sum of squared errors: a coarse grid, then,
    for the best candidate of each delay (and each of ``extra``: for the mixed law, the best
    fits of the laws it holds), grids that halve around it round by round."""
    names = LAW_GAINS[law]
    free = [c for c, n in ((0, "N"), (1, "K")) if n in names] + ([2] if law != "parallel" else [])
    low = np.array([GAIN_BOUNDS["N"][0], GAIN_BOUNDS["K"][0], attack.first_heading - HEADING_RANGE])
    high = np.array([GAIN_BOUNDS["N"][1], GAIN_BOUNDS["K"][1], attack.first_heading + HEADING_RANGE])
    grid = _grid(law, attack, max_delay)
    delays = np.unique(grid[:, 3])
    regressed = np.concatenate([_regressed(law, attack, int(d)) for d in delays]) if names else grid[:0]
    candidates = np.concatenate([grid, regressed])
    errors = _square_errors(_run(law, candidates, attack), attack)
    step = np.array([GAIN_BOUNDS["N"][1] / 8, GAIN_BOUNDS["K"][1] / 8, HEADING_RANGE / 2])
    # two starts per delay: the grid's best and the regression's best
    best, best_errors = [], []
    for pool in (np.arange(len(grid)), len(grid) + np.arange(len(regressed))):
        for d in delays:
            chosen = pool[candidates[pool, 3] == d]
            if len(chosen):
                best.append(candidates[chosen[np.argmin(errors[chosen])]].copy())
                best_errors.append(float(errors[chosen].min()))
    if extra:
        starts = np.stack(extra)
        best += list(starts)
        best_errors += [float(e) for e in _square_errors(_run(law, starts, attack), attack)]
    if free:
        offsets = np.stack([m.ravel() for m in np.meshgrid(*[np.linspace(-1, 1, 5)] * len(free), indexing="ij")], 1)
        for _ in range(_ZOOM_ROUNDS):
            step = step / 2
            rounds = []
            for centre in best:
                around = np.repeat(centre[None], len(offsets), axis=0)
                around[:, free] = np.clip(centre[free] + offsets * step[free], low[free], high[free])
                rounds.append(around)
            batch = np.concatenate(rounds)
            batch_errors = _square_errors(_run(law, batch, attack), attack).reshape(len(best), len(offsets))
            for j in range(len(best)):
                if batch_errors[j].min() < best_errors[j]:
                    best[j] = rounds[j][int(np.argmin(batch_errors[j]))]
                    best_errors[j] = float(batch_errors[j].min())
    j = int(np.argmin(best_errors))
    return best[j], best_errors[j]


def _regressed(law: str, attack: _Attack, d: int) -> np.ndarray:
    """Starting candidates for delay ``d``: the gains from least squares of the measured turn
    rate on the delayed measured λ̇ and δ (over the whole attack, its history included), clipped
    to their bounds, with 5 initial headings."""
    pursuer = attack.pursuer
    target = attack.target[::SUBSTEPS]
    chords = np.diff(pursuer, axis=0)
    heading = np.unwrap(np.arctan2(chords[:, 1], chords[:, 0]))
    los = np.arctan2(target[:, 1] - pursuer[:, 1], target[:, 0] - pursuer[:, 0])[1:-1]
    turn = np.diff(heading) / attack.dt  # at samples 1 … T-2
    los_rate = np.concatenate([[0.0], _wrap(np.diff(los)) / attack.dt])
    deviation = _wrap(los - (heading[1:] + heading[:-1]) / 2)
    rows = np.arange(d, len(turn))
    names = LAW_GAINS[law]
    values = np.zeros(4)
    values[3] = d
    if len(rows) >= len(names):
        columns = {"N": los_rate[rows - d], "K": deviation[rows - d]}
        design = np.stack([columns[n] for n in names], axis=1)
        solution, *_ = np.linalg.lstsq(design, turn[rows], rcond=None)
        for value, name in zip(solution, names, strict=True):
            values[0 if name == "N" else 1] = np.clip(value, *GAIN_BOUNDS[name])
    starts = np.repeat(values[None], 5, axis=0)
    starts[:, 2] = attack.first_heading + np.linspace(-HEADING_RANGE, HEADING_RANGE, 5)
    return starts


def _censored(law: str, values: np.ndarray, max_delay: int) -> dict[str, str]:
    censored = {}
    for column, name in ((0, "N"), (1, "K")):
        if name in LAW_GAINS[law]:
            lo, hi = GAIN_BOUNDS[name]
            if values[column] <= lo + AT_BOUND * (hi - lo):
                censored[name] = "lower"
            elif values[column] >= hi - AT_BOUND * (hi - lo):
                censored[name] = "upper"
    if law != "none" and max_delay > 0 and round(values[3]) >= max_delay:
        censored["delay"] = "upper"
    return censored


def fit(
    pursuer: np.ndarray, target: np.ndarray, dt: float, law: str, max_delay: int = 5, start: int | None = None
) -> LawFit:
    """Fit ``law`` to one attack: ``pursuer`` and ``target`` (T, 2) positions sampled every
    ``dt`` seconds, the simulation starting at sample ``start`` (default ``max_delay``: the
    samples before it are the history the delayed laws read); delays of 0 … ``max_delay``
    samples are tried, all from the same start. ValueError for too short or degenerate input
    (fewer than 4 simulated steps, a pursuer that does not move, NaNs)."""
    if law not in LAWS:
        raise ValueError(f"law={law!r}: expected one of {', '.join(LAWS)}")
    attack = _prepared(pursuer, target, dt, max_delay, start)
    held = tuple(_fit_values(single, attack, int(max_delay))[0] for single in ("pp", "pn")) if law == "mixed" else ()
    return _law_fit(law, attack, int(max_delay), held)


def _law_fit(law: str, attack: _Attack, max_delay: int, extra: tuple[np.ndarray, ...] = ()) -> LawFit:
    values, square_error = _fit_values(law, attack, max_delay, extra)
    dt, start = attack.dt, attack.start
    samples = len(attack.pursuer) - 1 - start
    return LawFit(
        law=law,
        gains={n: float(values[0 if n == "N" else 1]) for n in LAW_GAINS[law]},
        delay=float(round(values[3]) * dt),
        heading=float(values[2]),
        censored=_censored(law, values, max_delay),
        error=float(np.sqrt(square_error / samples)),
        criterion=_criterion(square_error, samples, law, _floor(attack)),
        samples=samples,
        start=start,
        simulated=_run(law, values, attack)[0],
    )


def select(
    pursuer: np.ndarray,
    target: np.ndarray,
    dt: float,
    max_delay: int = 5,
    start: int | None = None,
    laws: tuple[str, ...] = LAWS,
) -> Selection:
    """Every law in ``laws`` fitted to one attack (:func:`fit`) and the one with the lowest
    criterion chosen; ``"none"`` is always among them (the errors are relative to it)."""
    unknown = [law for law in laws if law not in LAWS]
    if unknown:
        raise ValueError(f"laws {unknown}: expected some of {', '.join(LAWS)}")
    if "mixed" in laws:  # the mixed fit starts from the fits of the laws it holds too
        laws = (*(law for law in laws if law != "mixed"), "pp", "pn", "mixed")
    attack = _prepared(pursuer, target, dt, max_delay, start)
    fits: dict[str, LawFit] = {}
    for law in dict.fromkeys(("none", *laws)):
        held = tuple(_values(fits[single], attack) for single in ("pp", "pn")) if law == "mixed" else ()
        fits[law] = _law_fit(law, attack, int(max_delay), held)
    ordered = {law: fits[law] for law in LAWS if law in fits}
    return Selection(min(ordered.values(), key=lambda f: f.criterion), ordered, _floor(attack))


def _values(fitted: LawFit, attack: _Attack) -> np.ndarray:
    """A fit as the simulation's candidate row (N, K, φ₀, delay in samples)."""
    delay = round(fitted.delay / attack.dt)
    return np.array([fitted.gains.get("N", 0.0), fitted.gains.get("K", 0.0), fitted.heading, delay])


def profile(
    pursuer: np.ndarray,
    target: np.ndarray,
    dt: float,
    gains: np.ndarray,
    delay: float,
    start: int,
    heading: float | None,
) -> np.ndarray:
    """The error (RMS distance after ``start``) of proportional navigation over an array of
    ``gains`` N, at one delay and initial heading (default: the first chord's): how well a
    whole-attack simulation determines N (docs/pursuit-law.md)."""
    pursuer, target = _checked(pursuer, target, dt)
    start = _checked_start(start, 0, len(pursuer))
    attack = _attack(pursuer, target, dt, start)
    gains = np.asarray(gains, dtype=float)
    values = np.zeros((len(gains), 4))
    values[:, 0] = gains
    values[:, 2] = attack.first_heading if heading is None else heading
    values[:, 3] = _delay_steps(delay, dt)
    return np.sqrt(_square_errors(_run("pn", values, attack), attack) / (len(pursuer) - 1 - start))


def gain_text(fitted: LawFit, name: str) -> str:
    """A gain as a reader should see it: its value, or its bound when censored there
    (``">15"``, ``"<0"``)."""
    side = fitted.censored.get(name)
    if name == "delay":
        return f">={fitted.delay:g} s" if side else f"{fitted.delay:g} s"
    lo, hi = GAIN_BOUNDS[name]
    return f">{hi:g}" if side == "upper" else f"<{lo:g}" if side == "lower" else f"{fitted.gains[name]:.2f}"
