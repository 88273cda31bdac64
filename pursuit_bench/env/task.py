"""The paper's task over a batch of arenas: actions to accelerations, observations, rewards and
episode end. No physics here (see ``world``).

Array conventions: the agent axis is ``predator_0 … predator_{n-1}, prey_0`` (the prey last);
positions and velocities are ``(B, n_agents, 2)``; predator modes ``(B, n_predators)`` (0 stalk,
1 chase); direction indices ``(B, n_agents)`` in ``0 … 11``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np

from pursuit_bench.env.conditions import TaskConfig
from pursuit_bench.env.obstacles import range_readings
from pursuit_bench.env.world import HALF_SIZE, RADIUS, Contacts

#: Number of movement directions, every 30° relative to the line of sight (paper 2.4).
N_DIRECTIONS = 12
#: Angle between consecutive direction indices, radians. Index k points at ``-k · 30°`` from the
#: line of sight (authors' code ``get_abs_u``): k = 0 straight at the target, k = 6 away from it.
DIRECTION_STEP = 2 * np.pi / N_DIRECTIONS
#: Acceleration magnitude of the prey (authors' code).
ACCEL_PREY = 3.0
#: Predator acceleration in chase mode: 120 % of the prey's (paper 3.1).
ACCEL_CHASE = 3.6
#: Predator acceleration in stalk mode: 60 % of the prey's (paper 3.1).
ACCEL_STALK = 1.8
STALK, CHASE = 0, 1
MODE_NAMES = ("stalk", "chase")
#: Start positions are drawn uniformly from ``[-START_HALF_SIZE, START_HALF_SIZE]²`` (paper 3.1).
START_HALF_SIZE = 0.5

#: ``exp(-i k 30°)``: multiplying a unit LOS (as a complex number) by it gives direction k.
ROTATIONS = np.exp(-1j * DIRECTION_STEP * np.arange(N_DIRECTIONS))

# A 2-D vector is one complex number x + iy here: rotating into an agent's LOS frame is a
# multiplication by the conjugate of its unit LOS. The per-step work is two small kernels
# compiled by numba (accelerations; then rewards, truncation and observations), plain loops
# over arenas and agents: one implementation for every batch size, fast at B = 1 (the single
# env) where numpy's per-call overhead would dominate.


def as_complex(xy: np.ndarray) -> np.ndarray:
    """View (..., 2) float64 as (...) complex128 (a copy only if ``xy`` is not contiguous)."""
    return np.ascontiguousarray(xy, dtype=np.float64).view(np.complex128)[..., 0]


def distances_to_prey(positions: np.ndarray) -> np.ndarray:
    """(B, n_agents) each predator's distance to the prey and the prey's to its nearest predator,
    from positions (B, n_agents, 2): what the envs report at a reset (a step's come from
    :func:`finish_step`)."""
    z = as_complex(positions)
    gaps = np.abs(z[:, :-1] - z[:, -1:])
    return np.concatenate([gaps, gaps.min(axis=1, keepdims=True)], axis=1)


def as_xy(z: np.ndarray) -> np.ndarray:
    """View (...) complex128 as (..., 2) float64."""
    z = np.asarray(z, dtype=np.complex128)
    return (z if z.flags.c_contiguous else z.copy())[..., None].view(np.float64)


def obs_size(n_agents: int, ranges: bool = False) -> int:
    """Length of one agent's observation: ``4 + 6 (n_agents - 1)`` = 10, 16, 22, and 12 more
    (the range readings) with ``ranges`` (a task with obstacles)."""
    return 6 * n_agents - 2 + (N_DIRECTIONS if ranges else 0)


@numba.njit(cache=True)
def _observe_kernel(z, w, obs, los):
    """Fill ``obs`` (B, n, 6n-2) float32 and ``los`` (B, n) complex from positions ``z`` and
    velocities ``w`` (B, n) complex."""
    batch, n = z.shape
    n_pred = n - 1
    order = np.empty(n_pred, np.int64)  # predators by increasing distance to the prey
    dist = np.empty(n_pred)
    for b in range(batch):
        prey = z[b, n_pred]
        for j in range(n_pred):
            dist[j] = abs(z[b, j] - prey)
            order[j] = j
        for a in range(1, n_pred):  # stable insertion sort: ties keep the lower index first
            key = order[a]
            c = a - 1
            while c >= 0 and dist[order[c]] > dist[key]:
                order[c + 1] = order[c]
                c -= 1
            order[c + 1] = key
        for i in range(n):
            d = (prey if i < n_pred else z[b, order[0]]) - z[b, i]
            m = abs(d)
            los[b, i] = d / m if m > 0 else 1.0 + 0.0j
        for i in range(n):
            to_los = los[b, i].conjugate()
            zi = z[b, i]
            wi = w[b, i] * to_los
            obs[b, i, 0], obs[b, i, 1] = zi.real, zi.imag
            obs[b, i, 2], obs[b, i, 3] = wi.real, wi.imag
            s = 4
            for q in range(n_pred):  # the n - 1 others, in observation order
                if i == n_pred:
                    j = order[q]
                elif q == 0:
                    j = n_pred
                else:
                    j = q - 1 if q - 1 < i else q
                zj = z[b, j]
                rel = (zj - zi) * to_los
                wj = w[b, j] * to_los
                obs[b, i, s], obs[b, i, s + 1] = zj.real, zj.imag
                obs[b, i, s + 2], obs[b, i, s + 3] = rel.real, rel.imag
                obs[b, i, s + 4], obs[b, i, s + 5] = wj.real, wj.imag
                s += 6


def observe(
    positions: np.ndarray, velocities: np.ndarray, obstacles: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Observations and the unit LOS of every agent (docs/spec.md, observations).

    Returns ``(obs, los)``: obs (B, n_agents, 6 n - 2) float32, for agent i ``[x, y, own velocity
    (u, v)]`` then, for each other agent, ``[x, y, relative position (u, v), velocity (u, v)]``,
    (u, v) being agent i's LOS frame (u towards its target, v to the left). The others come in
    this order: for a predator the prey, then the other predators by index; for the prey the
    predators by increasing distance (ties: the lower index). los (B, n_agents, 2): each
    predator's towards the prey, the prey's towards its nearest predator; along +x should two
    centres coincide. Given ``obstacles`` (B, K, 3), every observation ends with the agent's 12
    range readings (:func:`pursuit_bench.env.obstacles.range_readings`).
    """
    batch, n, _ = positions.shape
    obs = np.empty((batch, n, obs_size(n, obstacles is not None)), dtype=np.float32)
    los = np.empty((batch, n), dtype=np.complex128)
    z = as_complex(positions)
    _observe_kernel(z, as_complex(velocities), obs, los)
    if obstacles is not None:
        range_readings(z, los, obstacles, ROTATIONS, obs[..., obs_size(n) :])
    return obs, as_xy(los)


def observations(positions: np.ndarray, velocities: np.ndarray) -> np.ndarray:
    """(B, n_agents, 6 n - 2) float32 observations; see :func:`observe`."""
    return observe(positions, velocities)[0]


def line_of_sight(positions: np.ndarray) -> np.ndarray:
    """(B, n_agents, 2) unit LOS; see :func:`observe`."""
    return observe(positions, np.zeros_like(positions))[1]


def rotate_by_direction(los: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """World-frame unit vectors at ``-k · 30°`` from each LOS; ``los`` (..., 2), ``directions`` (...)."""
    return as_xy(as_complex(los) * ROTATIONS[directions])


@numba.njit(cache=True)
def _accelerations_kernel(los, modes, directions, rotations, out):
    batch, n = los.shape
    for b in range(batch):
        for i in range(n):
            if i == n - 1:
                magnitude = ACCEL_PREY
            else:
                magnitude = ACCEL_CHASE if modes[b, i] == CHASE else ACCEL_STALK
            out[b, i] = los[b, i] * rotations[directions[b, i]] * magnitude


def accelerations(los: np.ndarray, modes: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(B, n_agents, 2) world-frame accelerations from the unit LOS (B, n_agents, 2), the
    predators' modes (B, n_predators) and every agent's direction index (B, n_agents)."""
    out = np.empty(directions.shape, dtype=np.complex128)
    _accelerations_kernel(as_complex(los), modes, directions, ROTATIONS, out)
    return as_xy(out)


#: A predator's continuous action norm above which it is in chase mode (the stalk level).
CHASE_NORM = ACCEL_STALK / ACCEL_CHASE
#: The norm of the continuous action equal to a predator's discrete mode (stalk, chase).
MODE_NORMS = np.array([CHASE_NORM, 1.0])


def continuous_accelerations(los: np.ndarray, actions: np.ndarray, n_predators: int) -> tuple[np.ndarray, np.ndarray]:
    """World-frame accelerations (B, n_agents, 2) and the predators' modes (B, n_predators) from
    continuous actions (B, n_agents, 2) in each agent's line-of-sight frame (x along the line of
    sight, y to its left): norms above 1 scaled to 1, times the agent's maximum; a predator
    chases in a step whose norm exceeds the stalk level (:data:`CHASE_NORM`)."""
    z = as_complex(actions)
    norm = np.abs(z)
    z = np.where(norm > 1.0 + 1e-9, z / np.maximum(norm, 1e-300), z)
    out = np.empty(z.shape, dtype=np.complex128)
    _continuous_kernel(as_complex(los), z, n_predators, out)  # the discrete kernel's arithmetic, bit for bit
    modes = (np.abs(z[:, :n_predators]) > CHASE_NORM + 1e-9).astype(np.int64)
    return as_xy(out), modes


@numba.njit(cache=True)
def _continuous_kernel(los, z, n_predators, out):
    batch, n = z.shape
    for b in range(batch):
        for i in range(n):
            magnitude = ACCEL_CHASE if i < n_predators else ACCEL_PREY
            out[b, i] = los[b, i] * z[b, i] * magnitude


def discrete_as_continuous(modes: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The continuous actions (B, n_agents, 2) equal to discrete ones: predators' modes
    (B, n_predators) and every agent's direction (B, n_agents)."""
    n_predators = modes.shape[1]
    level = np.ones(directions.shape)
    level[:, :n_predators] = MODE_NORMS[modes]
    return as_xy(ROTATIONS[directions] * level)


@dataclass
class Outcome:
    """Rewards and episode end of one step, per arena."""

    rewards: np.ndarray
    """(B, n_agents) float64."""
    terminated: np.ndarray
    """(B,) bool: a capture, or (wall rule ``terminate``) an agent left the area."""
    captured: np.ndarray
    """(B,) bool: some predator overlaps the prey."""


@numba.njit(cache=True)
def _outcome_kernel(wall, prey, modes, chase_cost, shared, walls_end, rewards, terminated, captured):
    batch, n = wall.shape
    n_pred = n - 1
    for b in range(batch):
        caught = False
        for i in range(n_pred):
            caught = caught or prey[b, i]
        any_wall = wall[b, n_pred]
        for i in range(n_pred):
            r = (1.0 if caught else 0.0) if shared else (1.0 if prey[b, i] else 0.0)
            r -= 1.0 if wall[b, i] else 0.0
            r -= chase_cost if modes[b, i] == CHASE else 0.0
            rewards[b, i] = r
            any_wall = any_wall or wall[b, i]
        rewards[b, n_pred] = 0.0 - (1.0 if caught else 0.0) - (1.0 if wall[b, n_pred] else 0.0)
        captured[b] = caught
        terminated[b] = caught or (walls_end and any_wall)


@numba.njit(cache=True)
def _finish_kernel(wall, prey, modes, chase_cost, shared, walls_end, steps, max_steps, z, w, n_obs):
    """Rewards, terminated, truncated, captured, observations (with ``n_obs`` columns: room for
    the range readings, filled by the caller), LOS and distances to the prey of one step's end."""
    batch, n = z.shape
    rewards = np.empty((batch, n))
    terminated = np.empty(batch, dtype=np.bool_)
    truncated = np.empty(batch, dtype=np.bool_)
    captured = np.empty(batch, dtype=np.bool_)
    obs = np.empty((batch, n, n_obs), dtype=np.float32)
    los = np.empty((batch, n), dtype=np.complex128)
    distance = np.empty((batch, n))
    _outcome_kernel(wall, prey, modes, chase_cost, shared, walls_end, rewards, terminated, captured)
    _observe_kernel(z, w, obs, los)
    n_pred = n - 1
    for b in range(batch):
        truncated[b] = steps[b] >= max_steps and not terminated[b]
        nearest = np.inf
        for i in range(n_pred):
            distance[b, i] = abs(z[b, i] - z[b, n_pred])
            nearest = min(nearest, distance[b, i])
        distance[b, n_pred] = nearest
    return rewards, terminated, truncated, captured, obs, los, distance


def _reward_rules(
    config: TaskConfig, contacts: Contacts, modes: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, bool, bool]:
    """The reward-table kernel's inputs: contacts, modes and the condition's rules."""
    shared, walls_end = config.reward_sharing == "shared", config.wall_rule == "terminate"
    return contacts.wall, contacts.prey, modes, float(config.chase_cost), shared, walls_end


@dataclass
class Finish:
    """Everything a step ends with, per arena: :class:`Outcome`, truncation, observations."""

    outcome: Outcome
    truncated: np.ndarray
    """(B,) bool: the step limit was reached without termination."""
    observations: np.ndarray
    """(B, n_agents, 6n-2) float32."""
    los: np.ndarray
    """(B, n_agents, 2) unit LOS at the new positions."""
    distance_to_prey: np.ndarray
    """(B, n_agents): each predator's distance to the prey; the prey's to its nearest predator."""


def finish_step(
    config: TaskConfig,
    contacts: Contacts,
    modes: np.ndarray,
    steps: np.ndarray,
    positions: np.ndarray,
    velocities: np.ndarray,
    obstacles: np.ndarray | None = None,
) -> Finish:
    """:func:`outcome`, truncation after ``config.max_steps`` and :func:`observe` (with the range
    readings given ``obstacles``), in one call."""
    n = positions.shape[1]
    z = as_complex(positions)
    rewards, terminated, truncated, captured, obs, los, distance = _finish_kernel(
        *_reward_rules(config, contacts, modes),
        steps,
        config.max_steps,
        z,
        as_complex(velocities),
        obs_size(n, obstacles is not None),
    )
    if obstacles is not None:
        range_readings(z, los, obstacles, ROTATIONS, obs[..., obs_size(n) :])
    return Finish(
        outcome=Outcome(rewards=rewards, terminated=terminated, captured=captured),
        truncated=truncated,
        observations=obs,
        los=as_xy(los),
        distance_to_prey=distance,
    )


def outcome(config: TaskConfig, contacts: Contacts, modes: np.ndarray) -> Outcome:
    """the spec's (docs/spec.md) reward table; events in one step add up. A capture gives +1 to every predator
    (``shared``) or to each predator touching the prey (``individual``) and -1 to the prey;
    touching a wall gives -1 to that agent; a step in chase mode costs ``chase_cost``. A capture
    terminates, and so does a wall contact under the ``terminate`` wall rule."""
    batch, n = contacts.wall.shape
    rewards = np.empty((batch, n))
    terminated = np.empty(batch, dtype=bool)
    captured = np.empty(batch, dtype=bool)
    _outcome_kernel(*_reward_rules(config, contacts, modes), rewards, terminated, captured)
    return Outcome(rewards=rewards, terminated=terminated, captured=captured)


@functools.cache
def _pairs(n_agents: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.triu_indices(n_agents, 1)``: every pair of agents once (made once per agent count)."""
    first, second = np.triu_indices(n_agents, 1)
    first.flags.writeable = second.flags.writeable = False
    return first, second


def start_layouts(rng: np.random.Generator, n_agents: int, count: int) -> np.ndarray:
    """Start layouts (k, n_agents, 2), uniform in ``[-0.5, 0.5]²`` (paper 3.1): ``count``
    layouts drawn at once from ``rng``, those in which two disks overlap dropped (dropping is our
    addition; the paper does not say), drawn again if none is left."""
    first, second = _pairs(n_agents)
    while True:
        layouts = rng.uniform(-START_HALF_SIZE, START_HALF_SIZE, size=(count, n_agents, 2))
        gaps = layouts[:, first] - layouts[:, second]
        apart = ((gaps * gaps).sum(axis=-1) >= (2 * RADIUS) ** 2).all(axis=-1)
        if apart.any():
            return layouts[apart]


def sample_start(rng: np.random.Generator, n_agents: int) -> np.ndarray:
    """(n_agents, 2) one start layout; see :func:`start_layouts`."""
    return start_layouts(rng, n_agents, 1)[0]


def check_positions(positions: object, shape: tuple[int, ...]) -> np.ndarray:
    """Validate user-given start positions: finite, of ``shape``, every disk inside the arena."""
    arr = np.asarray(positions, dtype=np.float64)
    if arr.shape != shape or not np.isfinite(arr).all():
        raise ValueError(f"positions: expected finite numbers of shape {shape}, got shape {arr.shape}")
    if (np.abs(arr) >= HALF_SIZE - RADIUS).any():
        raise ValueError(f"positions: every coordinate must lie strictly within ±{HALF_SIZE - RADIUS}")
    return arr
