"""Learning agents: dueling double DQN with prioritized replay, one independent learner per agent
(optionally stacked into one batched computation), the hierarchical predator, the prey, the flat
ablation and the scripted baselines."""

from pursuit_bench.agents.config import PAPER, PRESETS, QUICK, AgentConfig
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.kinds import KINDS, FlatPredator, HierarchicalPredator, LearningAgent, Prey, ScriptedAgent
from pursuit_bench.agents.network import DuelingQNetwork
from pursuit_bench.agents.replay import PrioritizedReplay

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
    "PrioritizedReplay",
    "ScriptedAgent",
]
