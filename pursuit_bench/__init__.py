"""pursuit-bench: a predator–prey benchmark for multi-agent RL (Tsutsui, Takeda, Fujii 2023).

``parallel_env(condition=…)`` and ``env(condition=…)`` build the PettingZoo envs;
``VectorPursuitEnv`` steps B arenas at once; ``gymnasium.make("pursuit_bench/Pursuit-v0",
agent=…, condition=…)`` is a single-agent view, and ``gymnasium.make_vec`` with the same
arguments N of them as one Gymnasium ``VectorEnv`` over the batched core; ``load_agents(RUN)``
returns the trained agents of a run folder by name.

The envs, numba's kernels and torch are imported when first used, so that ``import
pursuit_bench`` (and the command line's ``--help``) stays quick.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

import gymnasium

from pursuit_bench.conditions import CONDITIONS, TaskConfig

if TYPE_CHECKING:
    from pursuit_bench.pettingzoo_env import PursuitParallelEnv, env, parallel_env
    from pursuit_bench.runs import load_agents
    from pursuit_bench.vector import VectorPursuitEnv

__all__ = [
    "CONDITIONS",
    "PursuitParallelEnv",
    "TaskConfig",
    "VectorPursuitEnv",
    "env",
    "load_agents",
    "parallel_env",
]
__version__ = "0.1.0"

_LAZY = {
    "PursuitParallelEnv": "pursuit_bench.pettingzoo_env",
    "env": "pursuit_bench.pettingzoo_env",
    "parallel_env": "pursuit_bench.pettingzoo_env",
    "VectorPursuitEnv": "pursuit_bench.vector",
    "load_agents": "pursuit_bench.runs",
}


#: The library's modules, imported on first use as attributes (``pursuit_bench.pretrained.info``).
_SUBMODULES = {
    "analysis",
    "conditions",
    "evaluate",
    "guidance",
    "gym_vector",
    "navigation",
    "obstacles",
    "policies",
    "pretrained",
    "recording",
    "report",
    "runs",
    "stack",
    "sweep",
    "task",
    "train",
    "vector",
    "world",
}


def __getattr__(name: str) -> Any:
    if name in _SUBMODULES:
        return importlib.import_module(f"pursuit_bench.{name}")
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pursuit_bench' has no attribute {name!r}")


if "pursuit_bench/Pursuit-v0" not in gymnasium.registry:
    gymnasium.register(
        id="pursuit_bench/Pursuit-v0",
        entry_point="pursuit_bench.single:PursuitSingleAgentEnv",
        vector_entry_point="pursuit_bench.gym_vector:PursuitVectorEnv",
    )
