"""Obstacles as the task sees them: where they go at each reset, and what agents sense of them.
Their physics is the world's (:mod:`pursuit_bench.env.world`).

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

from pursuit_bench.env.conditions import OBSTACLE_GAP
from pursuit_bench.env.world import HALF_SIZE, RADIUS

#: Free gap kept between an agent's start disk and every obstacle.
START_GAP = RADIUS
#: Range readings are capped here (half the arena's side).
RANGE_CAP = 1.0
#: Candidate centres drawn at a time while placing one obstacle, and draws before a layout is
#: started again; layouts started again before placement is declared impossible.
_CANDIDATES, _DRAWS, _RESTARTS = 32, 20, 50


def place_obstacles(rng: np.random.Generator, starts: np.ndarray, count: int, radius: float) -> np.ndarray:
    """Obstacles (L, count, 3) rows of x, y, radius for each of L start layouts ``starts``
    (L, n_agents, 2), drawn from ``rng`` one obstacle after another: candidate centres in
    batches of 32, uniform in the square where the wall gap holds; the first candidate of a
    batch clear of the starts and of the obstacles already placed is taken. After 20 batches
    without one the layout is started again; a ValueError if 50 starts fail (too many or too
    large obstacles: ``TaskConfig`` refuses those).

    The batches are drawn ahead in one call and the generator is then left exactly where this
    sequence of draws leaves it (its state restored, the used draws drawn again), so a reset
    costs one compiled loop instead of Python per candidate."""
    bound = HALF_SIZE - radius - OBSTACLE_GAP
    clear_start = (radius + RADIUS + START_GAP) ** 2
    clear_other = (2 * radius + OBSTACLE_GAP) ** 2
    out = np.empty((len(starts), count, 3))
    out[:, :, 2] = radius
    ahead = 4 * count * len(starts)
    while True:
        state = rng.bit_generator.state
        batches = rng.uniform(-bound, bound, size=(ahead, _CANDIDATES, 2))
        used = _place_kernel(batches, starts, count, clear_start, clear_other, _DRAWS, _RESTARTS, out)
        rng.bit_generator.state = state
        if used >= 0:
            rng.uniform(size=used * _CANDIDATES * 2)  # what those batches took from the generator
            return out
        if used == _IMPOSSIBLE:
            raise ValueError(
                f"obstacles={count}, obstacle_radius={radius}: no room for them with the gaps the "
                "placement rule keeps; expected fewer or smaller obstacles"
            )
        ahead *= 4  # more batches than were drawn ahead were needed


_IMPOSSIBLE, _MORE = -2, -1


@numba.njit(cache=True)
def _place_kernel(batches, starts, count, clear_start, clear_other, draws_per_try, tries, out):
    """Place the obstacles of every layout from the batches in order; return the batches used,
    ``_MORE`` if they ran out, ``_IMPOSSIBLE`` if a layout failed ``tries`` times."""
    used = 0
    for layout in range(starts.shape[0]):
        done = False
        for _ in range(tries):
            placed = 0
            draws = 0
            while placed < count and draws < draws_per_try:
                draws += 1
                if used == batches.shape[0]:
                    return _MORE
                batch = batches[used]
                used += 1
                for c in range(batch.shape[0]):
                    x, y = batch[c, 0], batch[c, 1]
                    fits = True
                    for i in range(starts.shape[1]):
                        dx, dy = x - starts[layout, i, 0], y - starts[layout, i, 1]
                        if dx * dx + dy * dy < clear_start:
                            fits = False
                            break
                    for j in range(placed):
                        if not fits:
                            break
                        dx, dy = x - out[layout, j, 0], y - out[layout, j, 1]
                        if dx * dx + dy * dy < clear_other:
                            fits = False
                    if fits:
                        out[layout, placed, 0], out[layout, placed, 1] = x, y
                        placed += 1
                        draws = 0
                        break
            if placed == count:
                done = True
                break
        if not done:
            return _IMPOSSIBLE
    return used


@numba.njit(cache=True)
def _ranges_kernel(z, los, obstacles, rotations, limit, cap, out):
    batch, n = z.shape
    k_obstacles = obstacles.shape[1]
    dx = np.empty(k_obstacles)
    dy = np.empty(k_obstacles)
    outside = np.empty(k_obstacles)
    for b in range(batch):
        for i in range(n):
            px, py = z[b, i].real, z[b, i].imag
            for j in range(k_obstacles):  # what does not depend on the direction, once
                dx[j], dy[j] = obstacles[b, j, 0] - px, obstacles[b, j, 1] - py
                reach = obstacles[b, j, 2] + RADIUS
                outside[j] = dx[j] * dx[j] + dy[j] * dy[j] - reach * reach
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
                for j in range(k_obstacles):
                    along = dx[j] * ux + dy[j] * uy
                    if along <= 0.0:
                        continue  # pointing away from it (or along its side when touching)
                    if outside[j] <= 0.0:
                        t = 0.0  # touching it already, pointing into it
                    elif along * along >= outside[j]:
                        t = min(t, along - np.sqrt(along * along - outside[j]))
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
