"""Obstacles as the task sees them: where they go at each reset, and what agents sense of them.
Their physics is the world's (:mod:`pursuit_bench.world`).

- :func:`place_obstacles`: the start-state rule extended (docs/spec.md, obstacles): centres
  uniform inside the arena, each obstacle at least :data:`OBSTACLE_GAP` from the walls and from
  every other obstacle (a passage an agent fits through, so no part of the arena is closed off),
  and every agent's start disk at least :data:`START_GAP` clear of every obstacle.
- :func:`range_readings`: for every agent, along each of its 12 action directions (in its
  line-of-sight frame: reading k and direction k share an index), how far its centre can travel
  before its disk touches an obstacle or a wall, capped at :data:`RANGE_CAP`.
"""

from __future__ import annotations

import numba
import numpy as np

from pursuit_bench.conditions import OBSTACLE_GAP
from pursuit_bench.world import HALF_SIZE, RADIUS

#: Free gap kept between an agent's start disk and every obstacle.
START_GAP = RADIUS
#: Range readings are capped here (half the arena's side).
RANGE_CAP = 1.0
#: Candidate centres drawn at a time while placing one obstacle, and draws before a layout is
#: started again; layouts started again before placement is declared impossible.
_CANDIDATES, _DRAWS, _RESTARTS = 32, 20, 50


def place_obstacles(rng: np.random.Generator, starts: np.ndarray, count: int, radius: float) -> np.ndarray:
    """Obstacles (L, count, 3) rows of x, y, radius for each of L start layouts ``starts``
    (L, n_agents, 2), drawn from ``rng`` one obstacle after another: candidate centres uniform
    in the square where the wall gap holds, the first clear of the starts and of the obstacles
    already placed taken. A layout that cannot be completed is started again; a ValueError if
    none can be (too many or too large obstacles)."""
    bound = HALF_SIZE - radius - OBSTACLE_GAP
    clear_start = (radius + RADIUS + START_GAP) ** 2
    clear_other = (2 * radius + OBSTACLE_GAP) ** 2
    out = np.empty((len(starts), count, 3))
    out[:, :, 2] = radius
    for layout, agents in enumerate(starts):
        for _ in range(_RESTARTS):
            placed: list[np.ndarray] = []
            draws = 0
            while len(placed) < count and draws < _DRAWS:
                draws += 1
                candidates = rng.uniform(-bound, bound, size=(_CANDIDATES, 2))
                near = np.concatenate([agents, np.array(placed).reshape(-1, 2)])
                gaps = ((candidates[:, None] - near[None]) ** 2).sum(-1)
                limits = np.r_[np.full(len(agents), clear_start), np.full(len(placed), clear_other)]
                fits = np.flatnonzero((gaps >= limits).all(axis=1))
                if len(fits):
                    placed.append(candidates[fits[0]])
                    draws = 0
            if len(placed) == count:
                out[layout, :, :2] = np.array(placed).reshape(count, 2)
                break
        else:
            raise ValueError(
                f"obstacles={count}, obstacle_radius={radius}: no room for them with the gaps the "
                "placement rule keeps; expected fewer or smaller obstacles"
            )
    return out


@numba.njit(cache=True)
def _ranges_kernel(z, los, obstacles, rotations, limit, cap, out):
    batch, n = z.shape
    for b in range(batch):
        for i in range(n):
            px, py = z[b, i].real, z[b, i].imag
            for k in range(rotations.shape[0]):
                u = los[b, i] * rotations[k]
                ux, uy = u.real, u.imag
                t = cap
                if ux > 1e-12:
                    t = min(t, (limit - px) / ux)
                elif ux < -1e-12:
                    t = min(t, (-limit - px) / ux)
                if uy > 1e-12:
                    t = min(t, (limit - py) / uy)
                elif uy < -1e-12:
                    t = min(t, (-limit - py) / uy)
                for j in range(obstacles.shape[1]):
                    dx, dy = obstacles[b, j, 0] - px, obstacles[b, j, 1] - py
                    reach = obstacles[b, j, 2] + RADIUS
                    outside = dx * dx + dy * dy - reach * reach
                    along = dx * ux + dy * uy
                    if along <= 0.0:
                        continue  # pointing away from it (or along its side when touching)
                    if outside <= 0.0:
                        t = 0.0  # touching it already, pointing into it
                    elif along * along >= outside:
                        t = min(t, along - np.sqrt(along * along - outside))
                out[b, i, k] = max(t, 0.0)


def range_readings(
    z: np.ndarray, los: np.ndarray, obstacles: np.ndarray, rotations: np.ndarray, out: np.ndarray
) -> None:
    """Fill ``out`` (B, n_agents, 12) with the range readings from positions ``z`` and unit LOS
    ``los`` (B, n_agents) complex, obstacles (B, K, 3) and the direction rotations
    (``task.ROTATIONS``): along direction k, the distance the agent's centre travels before its
    disk touches an obstacle (a ray against the obstacle grown by ``RADIUS``) or a wall (the
    centre reaching ``±(HALF_SIZE - RADIUS)``), capped at ``RANGE_CAP``: 0 along the directions
    that point into what the disk touches, and nothing is hit pointing away from an obstacle."""
    _ranges_kernel(z, los, obstacles, rotations, HALF_SIZE - RADIUS, RANGE_CAP, out)
