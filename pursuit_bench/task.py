"""The paper's task as pure numpy over a batch of arenas: actions to accelerations, observations,
rewards and episode end. No physics here (see ``world``) and no Python loop over arenas.

Array conventions: the agent axis is ``predator_0 … predator_{n-1}, prey_0`` (the prey last);
positions and velocities are ``(B, n_agents, 2)``; predator modes ``(B, n_predators)`` (0 stalk,
1 chase); direction indices ``(B, n_agents)`` in ``0 … 11``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pursuit_bench.conditions import TaskConfig
from pursuit_bench.world import HALF_SIZE, RADIUS, Contacts

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

# Inside this module a 2-D vector is one complex number x + iy: rotating into an agent's LOS
# frame is a multiplication by the conjugate of its unit LOS, which keeps numpy calls few (the
# single env runs these functions at B = 1, where the number of calls sets the speed).


def as_complex(xy: np.ndarray) -> np.ndarray:
    """View (..., 2) float64 as (...) complex128 (a copy only if ``xy`` is not contiguous)."""
    return np.ascontiguousarray(xy, dtype=np.float64).view(np.complex128)[..., 0]


def as_xy(z: np.ndarray) -> np.ndarray:
    """View (...) complex128 as (..., 2) float64."""
    z = np.asarray(z, dtype=np.complex128)
    return (z if z.flags.c_contiguous else z.copy())[..., None].view(np.float64)


def obs_size(n_agents: int) -> int:
    """Length of one agent's observation: ``4 + 6 (n_agents - 1)`` = 10, 16, 22."""
    return 6 * n_agents - 2


def _unit(z: np.ndarray) -> np.ndarray:
    """Normalise; a zero vector becomes 1 (the +x axis)."""
    norm = np.abs(z)
    return np.where(norm > 0, z / np.where(norm > 0, norm, 1.0), 1.0)


def prey_order(positions: np.ndarray) -> np.ndarray:
    """(B, n_predators) predator indices by increasing distance to the prey (ties: lower index)."""
    z = as_complex(positions)
    return np.argsort(np.abs(z[:, :-1] - z[:, -1:]), axis=1, kind="stable")


def _line_of_sight(z: np.ndarray, order: np.ndarray) -> np.ndarray:
    """(B, n) complex unit LOS from complex positions and :func:`prey_order`."""
    los = np.empty_like(z)
    los[:, :-1] = z[:, -1:] - z[:, :-1]
    los[:, -1] = np.take_along_axis(z, order[:, :1], axis=1)[:, 0] - z[:, -1]
    return _unit(los)


def line_of_sight(positions: np.ndarray) -> np.ndarray:
    """(B, n_agents, 2) unit LOS: each predator towards the prey, the prey towards its nearest
    predator."""
    return as_xy(_line_of_sight(as_complex(positions), prey_order(positions)))


def rotate_by_direction(los: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """World-frame unit vectors at ``-k · 30°`` from each LOS; ``los`` (..., 2), ``directions`` (...)."""
    return as_xy(as_complex(los) * ROTATIONS[directions])


def acceleration_magnitudes(modes: np.ndarray) -> np.ndarray:
    """(B, n_agents) acceleration magnitudes from predator modes (B, n_predators)."""
    batch = modes.shape[0]
    return np.concatenate([np.where(modes == CHASE, ACCEL_CHASE, ACCEL_STALK), np.full((batch, 1), ACCEL_PREY)], axis=1)


def accelerations(los: np.ndarray, modes: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(B, n_agents, 2) world-frame accelerations from the unit LOS (B, n_agents, 2), the
    predators' modes and every agent's direction index."""
    return as_xy(as_complex(los) * ROTATIONS[directions] * acceleration_magnitudes(modes))


_PREDATOR_ORDERS: dict[int, np.ndarray] = {}


def others_order(order: np.ndarray) -> np.ndarray:
    """(B, n_agents, n_agents - 1) indices of the other agents in observation order, from
    :func:`prey_order`: for a predator the prey then the other predators by index; for the prey
    the predators by increasing distance."""
    batch, n_pred = order.shape
    if n_pred not in _PREDATOR_ORDERS:
        n = n_pred + 1
        _PREDATOR_ORDERS[n_pred] = np.array([[n - 1] + [j for j in range(n - 1) if j != i] for i in range(n - 1)])
    out = np.empty((batch, n_pred + 1, n_pred), dtype=np.intp)
    out[:, :-1] = _PREDATOR_ORDERS[n_pred]
    out[:, -1] = order
    return out


def observe(positions: np.ndarray, velocities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Observations and the unit LOS of every agent (SPEC "Observations").

    Returns ``(obs, los)``: obs (B, n_agents, 6 n - 2) float32, for agent i ``[x, y, own velocity
    (u, v)]`` then, for each other agent in :func:`others_order`, ``[x, y, relative position
    (u, v), velocity (u, v)]``, (u, v) being agent i's LOS frame; los (B, n_agents, 2).
    """
    z, w = as_complex(positions), as_complex(velocities)
    order = prey_order(positions)
    los = _line_of_sight(z, order)
    to_los = np.conj(los)[:, :, None]  # multiplying by it rotates into each agent's LOS frame
    others = others_order(order)
    arena = np.arange(z.shape[0])[:, None, None]
    other_z = z[arena, others]  # (B, n, n-1)
    n = z.shape[1]
    out = np.empty((z.shape[0], n, 3 * n - 1), dtype=np.complex128)
    out[:, :, 0] = z
    out[:, :, 1] = w * to_los[:, :, 0]
    out[:, :, 2::3] = other_z
    out[:, :, 3::3] = (other_z - z[:, :, None]) * to_los
    out[:, :, 4::3] = w[arena, others] * to_los
    return out.view(np.float64).astype(np.float32), as_xy(los)


def observations(positions: np.ndarray, velocities: np.ndarray) -> np.ndarray:
    """(B, n_agents, 6 n - 2) float32 observations; see :func:`observe`."""
    return observe(positions, velocities)[0]


@dataclass
class Outcome:
    """Rewards and episode end of one step, per arena."""

    rewards: np.ndarray
    """(B, n_agents) float64."""
    terminated: np.ndarray
    """(B,) bool: a capture, or (wall rule ``terminate``) an agent left the area."""
    captured: np.ndarray
    """(B,) bool: some predator overlaps the prey."""


def outcome(config: TaskConfig, contacts: Contacts, modes: np.ndarray) -> Outcome:
    """SPEC's reward table. Events in one step add up."""
    captured = np.logical_or.reduce(contacts.prey, axis=1)
    if config.reward_sharing == "shared":
        predator_reward = np.repeat(captured[:, None], config.n_predators, axis=1).astype(np.float64)
    else:
        predator_reward = contacts.prey.astype(np.float64)
    predator_reward -= contacts.wall[:, :-1]
    predator_reward -= config.chase_cost * (modes == CHASE)
    prey_reward = 0.0 - captured - contacts.wall[:, -1]
    rewards = np.concatenate([predator_reward, prey_reward[:, None]], axis=1)
    terminated = captured.copy()
    if config.wall_rule == "terminate":
        terminated |= np.logical_or.reduce(contacts.wall, axis=1)
    return Outcome(rewards=rewards, terminated=terminated, captured=captured)


def sample_start(rng: np.random.Generator, n_agents: int) -> np.ndarray:
    """(n_agents, 2) start positions, uniform in ``[-0.5, 0.5]²``, no two disks overlapping
    (redrawn until they do not; a departure from the paper, which does not say)."""
    while True:
        p = rng.uniform(-START_HALF_SIZE, START_HALF_SIZE, size=(n_agents, 2))
        delta = p[:, None, :] - p[None, :, :]
        dist2 = (delta * delta).sum(axis=-1)
        np.fill_diagonal(dist2, np.inf)
        if (dist2 >= (2 * RADIUS) ** 2).all():
            return p


def check_positions(positions: object, shape: tuple[int, ...]) -> np.ndarray:
    """Validate user-given start positions: finite, of ``shape``, every disk inside the arena."""
    arr = np.asarray(positions, dtype=np.float64)
    if arr.shape != shape or not np.isfinite(arr).all():
        raise ValueError(f"positions: expected finite numbers of shape {shape}, got shape {arr.shape}")
    if (np.abs(arr) >= HALF_SIZE - RADIUS).any():
        raise ValueError(f"positions: every coordinate must lie strictly within ±{HALF_SIZE - RADIUS}")
    return arr
