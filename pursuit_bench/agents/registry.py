"""Every learning agent's kind by the name the command line, checkpoints and run folders use."""

from __future__ import annotations

from pursuit_bench.agents.kinds import FlatPredator, HierarchicalPredator, LearningAgent, Prey
from pursuit_bench.agents.residual import ResidualPredator

KINDS: dict[str, type[LearningAgent]] = {
    k.kind: k for k in (HierarchicalPredator, Prey, FlatPredator, ResidualPredator)
}
