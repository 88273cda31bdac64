"""pursuit-bench: a predator–prey benchmark for multi-agent RL (Tsutsui, Takeda, Fujii 2023).

``parallel_env(condition=…)`` and ``env(condition=…)`` build the PettingZoo envs;
``gymnasium.make("pursuit_bench/Pursuit-v0", agent=…, condition=…)`` a single-agent view.
"""

from __future__ import annotations

import gymnasium

from pursuit_bench.conditions import CONDITIONS, TaskConfig
from pursuit_bench.env import PursuitParallelEnv, env, parallel_env

__all__ = ["CONDITIONS", "PursuitParallelEnv", "TaskConfig", "env", "parallel_env"]
__version__ = "0.1.0"

if "pursuit_bench/Pursuit-v0" not in gymnasium.registry:
    gymnasium.register(id="pursuit_bench/Pursuit-v0", entry_point="pursuit_bench.single:PursuitSingleAgentEnv")
