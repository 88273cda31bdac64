"""Scripted policies: ``act(observation) -> action`` for one observation, ``act_batch`` for a stack.

- :class:`AlwaysChase`, :class:`AlwaysStalk`: a predator at a fixed mode, the direction from
  parallel navigation (the paper's baselines, section 3.4).
- :class:`PurePursuitPredator`: a fixed mode, always straight at the prey (for comparison).
- :class:`FleeingPrey`: flees the nearest predator while keeping off the walls (and, in a task
  with obstacles, off the obstacles).

In a task with obstacles a predator's lower layer may avoid them (``avoidance=True``,
:func:`pursuit_bench.rules.navigation.navigate`); the prey must be told that its observations carry
range readings (``obstacles=True``).
"""

from __future__ import annotations

import numpy as np

from pursuit_bench.env.single import Policy as Policy
from pursuit_bench.env.task import ACCEL_PREY, CHASE, N_DIRECTIONS, STALK, rotate_by_direction
from pursuit_bench.env.world import DAMPING, DT, HALF_SIZE, RADIUS
from pursuit_bench.rules.navigation import SAFETY_DISTANCE, around_obstacles, navigate, pure_pursuit


class _FixedModePredator:
    mode: int
    #: ``act_batch``'s row i depends on observation i alone (no state, no draws): copies that
    #: hold the same settings may act for all their rows in one call (an evaluation's batch).
    row_wise = True

    def __init__(self, *, avoidance: bool = False) -> None:
        self.avoidance = avoidance

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """(B, 2) actions ``(mode, direction)`` for (B, obs) observations."""
        directions = self._directions(np.asarray(observations))
        return np.stack([np.full_like(directions, self.mode), directions], axis=-1)

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.act_batch(np.asarray(observation)[None])[0]

    def _directions(self, observations: np.ndarray) -> np.ndarray:
        return navigate(observations, self.mode, avoidance=self.avoidance)


class AlwaysChase(_FixedModePredator):
    """Chase mode on every step; direction by parallel navigation (with ``avoidance``, around
    obstacles)."""

    mode = CHASE


class AlwaysStalk(_FixedModePredator):
    """Stalk mode on every step; direction by parallel navigation (with ``avoidance``, around
    obstacles)."""

    mode = STALK


class PurePursuitPredator(_FixedModePredator):
    """A fixed mode (chase by default), always heading straight at the prey (with
    ``avoidance``, around obstacles)."""

    def __init__(self, mode: int = CHASE, *, avoidance: bool = False) -> None:
        super().__init__(avoidance=avoidance)
        self.mode = mode

    def _directions(self, observations: np.ndarray) -> np.ndarray:
        return around_obstacles(pure_pursuit(observations), observations, self.avoidance)


class FleeingPrey:
    """Picks the direction whose predicted next position is farthest from the nearest predator's
    predicted position, minus a penalty for coming within ``wall_margin`` of a wall. With
    ``obstacles`` (its observations end with range readings) also minus the same weight times
    how far a direction's reading falls short of the avoidance rule's safety distance."""

    row_wise = True  # as the predators' (above)

    def __init__(self, wall_margin: float = 0.25, wall_weight: float = 10.0, *, obstacles: bool = False) -> None:
        self.wall_margin = wall_margin
        self.wall_weight = wall_weight
        self.obstacles = obstacles

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        obs = np.asarray(observations, dtype=np.float64)
        shortfall = np.zeros((len(obs), N_DIRECTIONS))
        if self.obstacles:
            obs, ranges = obs[:, :-N_DIRECTIONS], obs[:, -N_DIRECTIONS:]
            shortfall = np.clip(SAFETY_DISTANCE - ranges, 0.0, None)
        own = obs[:, 0:2]
        nearest = obs[:, 4:6]
        los = nearest - own
        los = los / np.maximum(np.hypot(los[:, 0], los[:, 1]), 1e-12)[:, None]
        left = np.stack([-los[:, 1], los[:, 0]], axis=-1)
        own_v = obs[:, 2:3] * los + obs[:, 3:4] * left
        n_pred = (obs.shape[1] - 4) // 6
        preds = obs[:, 4:].reshape(-1, n_pred, 6)
        pred_v = preds[..., 4:5] * los[:, None] + preds[..., 5:6] * left[:, None]
        pred_next = preds[..., 0:2] + pred_v * DT  # (B, n_pred, 2)
        k = np.arange(N_DIRECTIONS)
        dirs = rotate_by_direction(np.repeat(los[:, None], N_DIRECTIONS, axis=1), k[None])
        own_next = own[:, None] + ((1 - DAMPING) * own_v[:, None] + ACCEL_PREY * DT * dirs) * DT
        gap = own_next[:, :, None, :] - pred_next[:, None, :, :]  # (B, 12, n_pred, 2)
        closest = np.sqrt((gap * gap).sum(-1)).min(-1)
        safe = HALF_SIZE - RADIUS - self.wall_margin
        intrusion = np.clip(np.abs(own_next) - safe, 0.0, None).sum(-1)
        return np.argmax(closest - self.wall_weight * (intrusion + shortfall), axis=1)

    def act(self, observation: np.ndarray) -> int:
        return int(self.act_batch(np.asarray(observation)[None])[0])
