"""Learning agents: dueling double DQN with prioritized replay, one independent learner per agent
(optionally stacked into one batched computation, its update one compiled call: ``fused``), the
hierarchical predator, the prey, the flat ablation and the scripted baselines, and the protocol
outside agents follow (``external``).
Imports ``rules``, ``env`` and ``io``.

torch is imported when a learner, network or agent kind is first used: ``agents.config`` alone
(the hyper-parameters, the presets) stays light for the command line.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from pursuit_bench.agents.config import PAPER, PRESETS, QUICK, AgentConfig
from pursuit_bench.io.lazy import submodule_getattr

if TYPE_CHECKING:
    from pursuit_bench.agents.dqn import DQNLearner
    from pursuit_bench.agents.kinds import (
        FlatPredator,
        HierarchicalPredator,
        LearningAgent,
        Prey,
        ScriptedAgent,
    )
    from pursuit_bench.agents.network import DuelingQNetwork
    from pursuit_bench.agents.registry import KINDS
    from pursuit_bench.agents.residual import ResidualLearner, ResidualPredator

__all__ = [
    "KINDS",
    "PAPER",
    "PRESETS",
    "QUICK",
    "AgentConfig",
    "DQNLearner",
    "DuelingQNetwork",
    "FlatPredator",
    "HierarchicalPredator",
    "LearningAgent",
    "Prey",
    "ResidualLearner",
    "ResidualPredator",
    "ScriptedAgent",
]

_LAZY = {
    "DQNLearner": "dqn",
    "KINDS": "registry",
    "FlatPredator": "kinds",
    "HierarchicalPredator": "kinds",
    "LearningAgent": "kinds",
    "Prey": "kinds",
    "ResidualLearner": "residual",
    "ResidualPredator": "residual",
    "ScriptedAgent": "kinds",
    "DuelingQNetwork": "network",
}


def _lazy(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f"pursuit_bench.agents.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    if name == "PrioritizedReplay":
        raise AttributeError(
            "pursuit_bench.agents.PrioritizedReplay was a test reference, no learner's replay; it moved to the tests "
            "(tests/reference/prioritized_replay.py) in 0.2: the learners' replay is agents.replay.ReplayStack"
        )
    raise AttributeError(f"module 'pursuit_bench.agents' has no attribute {name!r}")


__getattr__ = submodule_getattr(__name__, __path__, _lazy)
