"""Biological pursuit rules as pure functions of predator observations (batched over any leading
axes). A predator observation starts ``[x, y, own velocity (u, v), prey x, prey y, prey relative
position (u, v), prey velocity (u, v), …]`` in the predator's line-of-sight (LOS) frame.

- :func:`parallel_navigation`: the paper's rule (section 2.4) choosing the direction that keeps the
  absolute target direction φ most nearly constant.
- :func:`pure_pursuit`: always straight at the prey (k = 0), for comparison.
- :func:`constant_bearing_angle`: the classic constant-bearing course
  ``β = arcsin(|v_t| sin α / |v_p|)`` (Ghose et al. 2006), which parallel navigation approximates.
- :func:`avoid`: obstacle avoidance on the range readings (a task with obstacles): keep the
  chosen direction unless something solid is closer than :data:`SAFETY_DISTANCE` along it, then
  take the nearest free direction. :func:`navigate` is the lower layer of the hierarchical
  predator and of the scripted baselines: parallel navigation, with or without avoidance.
"""

from __future__ import annotations

import numba
import numpy as np

from pursuit_bench.env.obstacles import RANGE_CAP
from pursuit_bench.env.task import ACCEL_CHASE, ACCEL_STALK, CHASE, DIRECTION_STEP, N_DIRECTIONS
from pursuit_bench.env.world import DAMPING, DT

#: Directions on the approaching side, within ±90° of the LOS (paper 2.4).
APPROACH_DIRECTIONS = np.array([9, 10, 11, 0, 1, 2, 3])
#: Two predicted changes of φ closer than this (radians) count as a tie.
TIE_TOLERANCE = 1e-12
#: A direction is blocked for :func:`avoid` when its range reading is below this: a little less
#: than two steps at a predator's top speed (0.144 per step).
SAFETY_DISTANCE = 0.25

_OWN_VEL = slice(2, 4)
_PREY_REL = slice(6, 8)
_PREY_VEL = slice(8, 10)
_ANGLES = -DIRECTION_STEP * APPROACH_DIRECTIONS
_DIRS = np.stack([np.cos(_ANGLES), np.sin(_ANGLES)], axis=-1)  # (7, 2) in the LOS frame
_PHYSICS = (CHASE, ACCEL_STALK, ACCEL_CHASE, DAMPING, DT)


def parallel_navigation(observations: np.ndarray, modes: np.ndarray | int) -> np.ndarray:
    """Direction index per predator observation for the given mode(s) (0 stalk, 1 chase).

    Among ``k ∈ {9, 10, 11, 0, 1, 2, 3}`` pick the one whose predicted next step changes the
    absolute target direction least, ``argmin |wrap(φ' - φ)|``: the predator's next position from
    the world's dynamics, the prey's from its current velocity. Ties go to the smaller predicted
    distance. Works in the LOS frame, where φ is the angle of the prey's relative position.
    """
    obs = np.asarray(observations)
    if obs.dtype not in (np.float32, np.float64):
        obs = obs.astype(np.float64)
    shape = obs.shape[:-1]
    modes = np.asarray(modes, dtype=np.int64)
    if modes.shape != shape:
        modes = np.broadcast_to(modes, shape)
    rows = obs.reshape(-1, obs.shape[-1])
    directions = _parallel_navigation(rows, modes.reshape(-1), _DIRS, APPROACH_DIRECTIONS, *_PHYSICS).reshape(shape)
    return directions[()] if not shape else directions  # one observation: a scalar, as numpy indexing gives


@numba.njit(cache=True)
def _parallel_navigation(obs, modes, dirs, approach, chase, accel_stalk, accel_chase, damping, dt):
    """:func:`parallel_navigation` row by row (compiled: the rule runs for every predator of every
    arena at every step), in float64 whatever the observations' type. The physics comes in as
    arguments: numba's cache would keep constants of other modules as they were compiled.

    The angles (``arctan2``) are computed only for the directions :func:`_candidates` keeps, and
    the distances only for the ties: the same choice, from the same numbers, as computing them
    for every direction."""
    out = np.empty(obs.shape[0], dtype=np.int64)
    n = len(approach)
    lxs, lys, change, pseudo = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    considered = np.empty(n, dtype=np.bool_)
    for r in range(obs.shape[0]):
        accel = accel_chase if modes[r] == chase else accel_stalk
        px, py = np.float64(obs[r, _PREY_REL.start]), np.float64(obs[r, _PREY_REL.start + 1])
        nx = px + np.float64(obs[r, _PREY_VEL.start]) * dt
        ny = py + np.float64(obs[r, _PREY_VEL.start + 1]) * dt
        vx, vy = np.float64(obs[r, _OWN_VEL.start]), np.float64(obs[r, _OWN_VEL.start + 1])
        for k in range(n):  # the line of sight after the step in direction k
            lxs[k] = nx - ((1.0 - damping) * vx + accel * dt * dirs[k, 0]) * dt
            lys[k] = ny - ((1.0 - damping) * vy + accel * dt * dirs[k, 1]) * dt
        _candidates(px, py, lxs, lys, pseudo, considered)
        phi = np.arctan2(py, px)
        best_change, choice, best_distance = np.inf, 0, np.inf
        for k in range(n):
            if considered[k]:
                change[k] = abs(_python_mod(np.arctan2(lys[k], lxs[k]) - phi + np.pi, 2 * np.pi) - np.pi)
                best_change = min(best_change, change[k])
        for k in range(n):  # ties (within TIE_TOLERANCE) to the smaller distance, then the first
            if considered[k] and change[k] <= best_change + TIE_TOLERANCE:
                distance = np.hypot(lxs[k], lys[k])
                if distance < best_distance:
                    best_distance, choice = distance, k
        out[r] = approach[choice]
    return out


#: :func:`_candidates` keeps the directions whose pseudo-angle is within this of the smallest.
CANDIDATE_MARGIN = 1e-9
#: ... when each direction's scale (``c + s`` or ``s - c`` below) lies between these (else it keeps
#: every direction): the products may then underflow, by at most 5e-324, far below the scale's
#: 1e-16 that the bound allows.
_CANDIDATE_RANGE = (1e-250, 1e250)


@numba.njit(cache=True)
def _candidates(px, py, lxs, lys, pseudo, considered):
    """Mark in ``considered`` the directions k that can be the rule's choice: those whose
    predicted line of sight ``(lxs[k], lys[k])`` is within :data:`CANDIDATE_MARGIN` of the
    smallest *pseudo-angle* to the current one ``(px, py)``; ``pseudo`` is scratch space.

    The pseudo-angle ``s / (c + s)`` (``c ≥ 0``), ``1 - c / (s - c)`` (``c < 0``), with ``c`` the
    dot and ``s`` the absolute cross product, grows with the angle θ between the two at a rate
    between 1/2 and 1 and is computed to a few 1e-16 (no cancellation: ``c + s`` and ``s - c``
    are at least ``|l| |p|``). The rule's change of φ is θ to about 2e-15 (four roundings near
    2π). So a direction whose change is within :data:`TIE_TOLERANCE` of the smallest has a
    pseudo-angle within about 1e-12 of the smallest, far inside the margin: every direction the
    rule's choice depends on is kept (usually the only one kept is the choice). Where the products
    are zero, tiny, huge or not numbers, every direction is kept (the rule as written out)."""
    lowest = np.inf
    for k in range(len(lxs)):
        c = lxs[k] * px + lys[k] * py
        s = abs(lxs[k] * py - lys[k] * px)
        scale = c + s if c >= 0 else s - c
        if not (_CANDIDATE_RANGE[0] < scale < _CANDIDATE_RANGE[1]):
            considered[:] = True
            return
        pseudo[k] = s / scale if c >= 0 else 1.0 - c / scale
        lowest = min(lowest, pseudo[k])
    for k in range(len(lxs)):
        considered[k] = pseudo[k] <= lowest + CANDIDATE_MARGIN


@numba.njit(cache=True)
def _python_mod(x, period):
    """Python's ``x % period`` for ``period > 0``, the same bits, without a call to ``fmod`` for
    ``x`` in ``(-period, 2 period)`` but ±0 (where the rule's angles lie): there ``fmod`` is ``x``
    or the exact ``x - period``, and Python adds ``period`` to a negative remainder; elsewhere
    (±0, NaN, infinities, the rest) ``%`` itself."""
    if 0.0 < x < period:
        return x
    if period <= x < 2.0 * period:
        return x - period
    if -period < x < 0.0:
        return x + period
    return x % period


def pure_pursuit(observations: np.ndarray) -> np.ndarray:
    """Always straight at the prey: direction index 0 for every observation."""
    return np.zeros(np.asarray(observations).shape[:-1], dtype=np.int64)


def constant_bearing_angle(target_speed: float, pursuer_speed: float, alpha: float) -> float:
    """Course angle β relative to the LOS that keeps the bearing to a constant-velocity target
    constant: ``β = arcsin(|v_t| sin α / |v_p|)``. ``alpha`` is the angle between the target's
    velocity and the vector from the target to the pursuer (radians). Returns NaN where no such
    course exists (``|v_t sin α| > |v_p|``)."""
    if pursuer_speed <= 0:
        raise ValueError(f"pursuer_speed={pursuer_speed!r}: expected a speed > 0")
    ratio = abs(target_speed) * np.sin(alpha) / pursuer_speed
    return float(np.arcsin(ratio)) if abs(ratio) <= 1 else float("nan")


def avoid(directions: np.ndarray, ranges: np.ndarray, safety: float = SAFETY_DISTANCE) -> np.ndarray:
    """Obstacle avoidance: each direction index (...) kept when its range reading (``ranges``
    (..., 12), the observation's last 12 entries in a task with obstacles) is at least
    ``safety``; otherwise the free direction (reading >= ``safety``) fewest 30° steps away from
    it, ties to the longer reading, then to the lower index; with none free, the direction with
    the longest reading. A free direction is always taken when there is one."""
    directions = np.asarray(directions)
    ranges = np.asarray(ranges, dtype=np.float64)
    turn = np.abs(np.arange(N_DIRECTIONS) - directions[..., None]) % N_DIRECTIONS
    turn = np.minimum(turn, N_DIRECTIONS - turn)
    free = ranges >= safety
    cost = np.where(free, turn - 0.5 * np.clip(ranges, 0.0, RANGE_CAP) / RANGE_CAP, np.inf)
    return np.where(free.any(axis=-1), np.argmin(cost, axis=-1), np.argmax(ranges, axis=-1))


def navigate(observations: np.ndarray, modes: np.ndarray | int, *, avoidance: bool = False) -> np.ndarray:
    """The lower layer: :func:`parallel_navigation`, then with ``avoidance`` :func:`avoid` on the
    observations' range readings (their last 12 entries: only in a task with obstacles)."""
    return around_obstacles(parallel_navigation(observations, modes), observations, avoidance)


def around_obstacles(directions: np.ndarray, observations: np.ndarray, avoidance: bool) -> np.ndarray:
    """``directions`` as they are, or with ``avoidance`` through :func:`avoid` on the
    observations' range readings (their last 12 entries: only in a task with obstacles)."""
    return avoid(directions, np.asarray(observations)[..., -N_DIRECTIONS:]) if avoidance else directions
