"""One training run's configuration, :class:`TrainConfig`: apart from the training loop so that
reading a run folder's configuration and refusing bad options import neither torch nor the
physics (the command line answers at once).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Literal

from pursuit_bench.agents.config import QUICK, AgentConfig
from pursuit_bench.env.conditions import CONDITIONS, OBSTACLE_RADIUS, Backend, TaskConfig

PredatorKind = Literal["hierarchical", "flat", "residual", "always_chase", "always_stalk"]
PreyKind = Literal["learning", "scripted"]


@dataclass(frozen=True)
class TrainConfig:
    """One training run."""

    condition: str = "1p-high"
    """One of the paper's ten conditions (``pursuit_bench.CONDITIONS``)."""
    agent: AgentConfig = QUICK
    """Hyper-parameters shared by every learner (each has its own copy of the state)."""
    episodes: int = QUICK.episodes
    """Episodes to train for, counted over all arenas."""
    num_envs: int = 8
    """Arenas stepped together. Every arena-step is one transition for every agent."""
    seed: int = 0
    """Seeds the arenas, and with each agent's index its network's initialisation, its
    exploration and its replay sampling."""
    predator: PredatorKind = "hierarchical"
    """What the predators are: the paper's hierarchical agent, the flat ablation, the residual
    predator (the rule's direction corrected by up to ±60°, learned), or a scripted baseline
    (which does not learn)."""
    prey: PreyKind = "learning"
    """A learning prey (the paper) or the scripted fleeing prey."""
    batched_learners: bool = True
    """Stack the predators' learners into one batched computation, and with other runs' (the
    same results as separate updates, faster); False updates them one by one."""
    backend: Backend = "pymunk"
    """Physics backend of the arenas."""
    obstacles: int = 0
    """Obstacles per arena (0: the paper's empty arena; docs/obstacles.md)."""
    obstacle_radius: float = OBSTACLE_RADIUS
    """Radius of every obstacle."""
    avoidance: bool = True
    """With obstacles, the lower layer of the hierarchical predator and of the scripted
    baselines steers around them (``navigation.avoid``); False keeps plain parallel navigation."""

    def __post_init__(self) -> None:
        if self.condition not in CONDITIONS:
            raise ValueError(f"condition={self.condition!r}: expected one of {', '.join(CONDITIONS)}")
        for name in ("episodes", "num_envs"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name}={value!r}: expected an integer >= 1")
        if self.agent.episodes != self.episodes:  # one training length in config.json, the run's
            object.__setattr__(self, "agent", self.agent.replace(episodes=self.episodes))
        if self.predator not in ("hierarchical", "flat", "residual", "always_chase", "always_stalk"):
            raise ValueError(
                f"predator={self.predator!r}: expected 'hierarchical', 'flat', 'residual', 'always_chase' or "
                "'always_stalk'"
            )
        if self.prey not in ("learning", "scripted"):
            raise ValueError(f"prey={self.prey!r}: expected 'learning' or 'scripted'")
        if not isinstance(self.avoidance, bool):
            raise ValueError(f"avoidance={self.avoidance!r}: expected True or False")
        self.task  # noqa: B018 - validates the obstacle options

    @property
    def task_options(self) -> dict[str, Any]:
        """The task options beside the condition (the obstacles), for the envs' constructors."""
        if not self.obstacles:
            return {}
        return {"obstacles": self.obstacles, "obstacle_radius": self.obstacle_radius}

    @property
    def task(self) -> TaskConfig:
        """The task this run trains in: its condition with the obstacles."""
        return dataclasses.replace(CONDITIONS[self.condition], **self.task_options)

    @property
    def avoids(self) -> bool:
        """Whether the predators' lower layer avoids obstacles in this run (there are some and
        ``avoidance`` is on)."""
        return self.avoidance and self.obstacles > 0

    @property
    def protocol(self) -> dict[str, Any]:
        """``evaluate_agents``' options for this run's agents: the learned prey's ε (the paper's
        0.1; none for a scripted prey), the physics, the predators' kind, the obstacles and
        whether the baselines avoid them."""
        return {
            "prey_epsilon": 0.1 if self.prey == "learning" else None,
            "backend": self.backend,
            "predator_kind": self.predator,
            "task_options": self.task_options,
            "avoidance": self.avoids,
        }

    def to_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "agent": self.agent.to_dict()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """The inverse of :meth:`to_dict`; unknown keys are a ValueError."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ValueError(f"unknown training option(s) {unknown}")
        agent = AgentConfig().replace(**data.get("agent", {}))
        return cls(**{**data, "agent": agent})
