"""Every agent's observation and action space for a condition: what the PettingZoo envs, the
Gymnasium views and the batched env all declare (docs/spec.md, observations and actions)."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from pursuit_bench import task
from pursuit_bench.conditions import TaskConfig

#: Bounds of the observation's entries: positions, relative positions, velocities.
POSITION_BOUND, RELATIVE_BOUND, VELOCITY_BOUND = 1.0, 3.0, 2.0


def observation_bounds(n_agents: int) -> np.ndarray:
    """The bound of each entry of one agent's observation (own position and velocity, then per
    other agent its position, position relative to this one, velocity)."""
    own = [POSITION_BOUND] * 2 + [VELOCITY_BOUND] * 2
    other = [POSITION_BOUND] * 2 + [RELATIVE_BOUND] * 2 + [VELOCITY_BOUND] * 2
    return np.array(own + other * (n_agents - 1), dtype=np.float32)


def agent_spaces(config: TaskConfig) -> tuple[dict[str, spaces.Space[Any]], dict[str, spaces.Space[Any]]]:
    """(observation spaces, action spaces) by agent name: a predator's action is
    ``MultiDiscrete([2, 12])`` (mode, direction), the prey's ``Discrete(12)``; with
    ``config.continuous`` every agent's is ``Box(-1, 1, (2,))``, an acceleration in its
    line-of-sight frame."""
    bound = observation_bounds(config.n_agents)
    names = list(config.agent_names)
    observation: dict[str, spaces.Space[Any]] = {a: spaces.Box(-bound, bound, dtype=np.float32) for a in names}
    if config.continuous:
        return observation, {a: spaces.Box(-1.0, 1.0, (2,), dtype=np.float32) for a in names}
    action: dict[str, spaces.Space[Any]] = {a: spaces.MultiDiscrete([2, task.N_DIRECTIONS]) for a in names[:-1]}
    action[names[-1]] = spaces.Discrete(task.N_DIRECTIONS)
    return observation, action
