"""The predators' ``(mode, direction)`` as one of 24 joint actions, for learners that take one
categorical action per agent (BenchMARL's algorithms, a DQN without a wrapper of its own).

Joint action ``a`` is ``(mode, direction) = divmod(a, 12)``: 0..11 stalk in directions 0..11,
12..23 chase in them, the order the flat predator's network uses (docs/spec.md). The prey's
action (one of 12 directions) is unchanged, and so is everything else the env says."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo.utils.wrappers import BaseParallelWrapper

from pursuit_bench.env.pettingzoo_env import PursuitParallelEnv
from pursuit_bench.env.task import N_DIRECTIONS

#: How many joint actions a predator has: 2 modes × 12 directions.
N_JOINT = 2 * N_DIRECTIONS


def split(joint: np.ndarray) -> np.ndarray:
    """Joint actions (any shape) as ``(…, 2)`` rows of (mode, direction); ValueError outside 0..23."""
    joint = np.asarray(joint)
    if joint.dtype.kind not in "iu" or np.any((joint < 0) | (joint >= N_JOINT)):
        raise ValueError(f"joint predator actions must be integers in 0..{N_JOINT - 1}, got {joint!r}")
    return np.stack(np.divmod(joint.astype(np.int64), N_DIRECTIONS), axis=-1)


class JointActionParallelEnv(BaseParallelWrapper[str, np.ndarray, Any]):
    """A :class:`PursuitParallelEnv` whose predators act by ``Discrete(24)`` (above)."""

    def __init__(self, env: PursuitParallelEnv) -> None:
        if env.config.continuous:
            raise ValueError("joint actions are for the discrete task: make the env with continuous=False")
        super().__init__(env)
        self._predators = frozenset(env.possible_agents[:-1])
        self._joint_space = spaces.Discrete(N_JOINT)

    def action_space(self, agent: str) -> spaces.Space[Any]:
        return self._joint_space if agent in self._predators else self.env.action_space(agent)

    def step(self, actions: dict[str, Any]) -> Any:
        pairs = {}
        for agent, action in actions.items():
            if agent in self._predators:
                value = np.asarray(action)
                if value.size != 1:
                    raise ValueError(f"action for {agent}: got {action!r}, expected one joint action in 0..23")
                pairs[agent] = split(value.reshape(()))
            else:
                pairs[agent] = action
        return self.env.step(pairs)

    def state(self) -> np.ndarray:
        return self.env.state()
