"""Every agent's observation and action space for a condition: what the PettingZoo envs, the
Gymnasium views and the batched env all declare (docs/spec.md, observations and actions)."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from pursuit_bench.env import task
from pursuit_bench.env.conditions import TaskConfig
from pursuit_bench.env.obstacles import RANGE_CAP

#: Bounds of the observation's entries: positions, relative positions, velocities.
POSITION_BOUND, RELATIVE_BOUND, VELOCITY_BOUND = 1.0, 3.0, 2.0


def observation_bounds(n_agents: int, ranges: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of each entry of one agent's observation (own position and velocity, then per
    other agent its position, position relative to this one, velocity; with ``ranges`` the 12
    range readings, in ``[0, RANGE_CAP]``)."""
    own = [POSITION_BOUND] * 2 + [VELOCITY_BOUND] * 2
    other = [POSITION_BOUND] * 2 + [RELATIVE_BOUND] * 2 + [VELOCITY_BOUND] * 2
    high = own + other * (n_agents - 1)
    low = [-b for b in high]
    if ranges:
        low, high = low + [0.0] * task.N_DIRECTIONS, high + [RANGE_CAP] * task.N_DIRECTIONS
    return np.array(low, dtype=np.float32), np.array(high, dtype=np.float32)


def agent_spaces(config: TaskConfig) -> tuple[dict[str, spaces.Space[Any]], dict[str, spaces.Space[Any]]]:
    """(observation spaces, action spaces) by agent name: a predator's action is
    ``MultiDiscrete([2, 12])`` (mode, direction), the prey's ``Discrete(12)``; with
    ``config.continuous`` every agent's is ``Box(-1, 1, (2,))``, an acceleration in its
    line-of-sight frame. With obstacles every observation ends with 12 range readings."""
    low, high = observation_bounds(config.n_agents, config.obstacles > 0)
    names = list(config.agent_names)
    observation: dict[str, spaces.Space[Any]] = {a: spaces.Box(low, high, dtype=np.float32) for a in names}
    if config.continuous:
        return observation, {a: spaces.Box(-1.0, 1.0, (2,), dtype=np.float32) for a in names}
    action: dict[str, spaces.Space[Any]] = {a: spaces.MultiDiscrete([2, task.N_DIRECTIONS]) for a in names[:-1]}
    action[names[-1]] = spaces.Discrete(task.N_DIRECTIONS)
    return observation, action
