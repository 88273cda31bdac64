"""Training: every agent of a condition learns at once, each an independent learner, in B arenas.

The loop, top to bottom (:meth:`Trainer.step`): act (one forward pass per group of learners) →
step the batched env → store each agent's transition → update → count finished episodes.
The CLI parses options into a :class:`TrainConfig` and calls :class:`Trainer`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from pursuit_bench.agents.config import QUICK, AgentConfig
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.kinds import KINDS, LearningAgent, ScriptedAgent
from pursuit_bench.conditions import CONDITIONS
from pursuit_bench.policies import AlwaysChase, AlwaysStalk, FleeingPrey
from pursuit_bench.vector import VectorPursuitEnv
from pursuit_bench.world import Backend

PredatorKind = Literal["hierarchical", "flat", "always_chase", "always_stalk"]
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
    """Seeds the arenas, every network's initialisation and every learner's sampling."""
    predator: PredatorKind = "hierarchical"
    """What the predators are: the paper's hierarchical agent, the flat ablation, or a scripted
    baseline (which does not learn)."""
    prey: PreyKind = "learning"
    """A learning prey (the paper) or the scripted fleeing prey."""
    batched_learners: bool = True
    """Stack the predators' learners into one batched computation (same mathematics as
    separate updates, faster); False updates them one by one."""
    backend: Backend = "pymunk"
    """Physics backend of the arenas."""

    def __post_init__(self) -> None:
        if self.condition not in CONDITIONS:
            raise ValueError(f"condition={self.condition!r}: expected one of {', '.join(CONDITIONS)}")
        for name in ("episodes", "num_envs"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"{name}={value!r}: expected an integer >= 1")
        if self.predator not in ("hierarchical", "flat", "always_chase", "always_stalk"):
            raise ValueError(
                f"predator={self.predator!r}: expected 'hierarchical', 'flat', 'always_chase' or 'always_stalk'"
            )
        if self.prey not in ("learning", "scripted"):
            raise ValueError(f"prey={self.prey!r}: expected 'learning' or 'scripted'")

    def to_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "agent": self.agent.to_dict()}


@dataclass
class Group:
    """Agents that share one (stacked) learner: member m is ``agents[m]`` at env index ``indices[m]``."""

    learner: DQNLearner
    agents: list[LearningAgent]
    indices: list[int]


@dataclass
class EpisodeRecord:
    """One finished episode, as the metrics file writes it."""

    episode: int
    length: int
    captured: bool
    returns: dict[str, float]
    chase_fraction: dict[str, float]
    extra: dict[str, float] = field(default_factory=dict)

    def as_row(self) -> dict[str, Any]:
        row: dict[str, Any] = {"episode": self.episode, "length": self.length, "captured": self.captured}
        row.update({f"return/{a}": r for a, r in self.returns.items()})
        row.update({f"chase_fraction/{a}": f for a, f in self.chase_fraction.items()})
        row.update(self.extra)
        return row


def build_agents(config: TrainConfig, n_obs: int) -> tuple[list[Group], dict[str, LearningAgent | ScriptedAgent]]:
    """The learner groups and every agent by name, for a condition."""
    names = list(CONDITIONS[config.condition].agent_names)
    predators, prey = names[:-1], names[-1]
    groups: list[Group] = []
    agents: dict[str, LearningAgent | ScriptedAgent] = {}

    def add_group(kind: type[LearningAgent], members: list[str]) -> None:
        learner = DQNLearner(
            n_obs, kind.n_actions, config.agent, members=len(members), seed=config.seed * 1000 + len(groups)
        )
        group = Group(learner, [kind(a, learner, m) for m, a in enumerate(members)], [names.index(a) for a in members])
        groups.append(group)
        agents.update({a.name: a for a in group.agents})

    if config.predator in KINDS:
        kind = KINDS[config.predator]
        for members in [predators] if config.batched_learners else [[p] for p in predators]:
            add_group(kind, members)
    else:
        policy = AlwaysChase() if config.predator == "always_chase" else AlwaysStalk()
        agents.update({p: ScriptedAgent(p, policy) for p in predators})
    if config.prey == "learning":
        add_group(KINDS["prey"], [prey])
    else:
        agents[prey] = ScriptedAgent(prey, FleeingPrey())
    return groups, {a: agents[a] for a in names}


class Trainer:
    """Runs :class:`TrainConfig`; ``on_episode`` is called with each finished episode."""

    def __init__(self, config: TrainConfig, on_episode: Callable[[EpisodeRecord], None] | None = None) -> None:
        self.config = config
        self.env = VectorPursuitEnv(config.num_envs, config.condition, backend=config.backend)
        self.groups, self.agents = build_agents(config, self.env.obs_size)
        self.on_episode = on_episode
        self.names = self.env.agents
        self.n_predators = len(self.names) - 1
        self.episodes_done = 0
        self.env_steps = 0
        self.last_losses: dict[str, float] = {}
        self.obs, _ = self.env.reset(seed=config.seed)
        self._chase_steps = np.zeros((config.num_envs, self.n_predators))

    def run(self, should_stop: Callable[[], bool] = lambda: False) -> None:
        """Step until the configured number of episodes has finished (or ``should_stop()``)."""
        while self.episodes_done < self.config.episodes and not should_stop():
            self.step()

    def step(self) -> None:
        """One step of every arena: act, step, store, update, count episodes."""
        obs = self.obs
        actions = np.zeros((self.config.num_envs, len(self.names), 2), dtype=np.int64)
        choices = []
        for group in self.groups:  # one forward pass per group
            group_obs = obs[:, group.indices].transpose(1, 0, 2)  # (M, B, n_obs)
            chosen = group.learner.act(group_obs, explore=True)
            choices.append(chosen)
            for m, (agent, i) in enumerate(zip(group.agents, group.indices, strict=True)):
                self._put(actions, i, agent.to_env(chosen[m], obs[:, i]))
        for i, name in enumerate(self.names):
            scripted = self.agents[name]
            if isinstance(scripted, ScriptedAgent):
                self._put(actions, i, scripted.act_batch(obs[:, i]))

        next_obs, rewards, terminated, _, info = self.env.step(actions)
        done = info["done"]
        real_next = np.where(done[:, None, None], info["final_observation"], next_obs)
        for group, chosen in zip(self.groups, choices, strict=True):
            idx = group.indices
            group.learner.store(
                obs[:, idx].transpose(1, 0, 2),
                chosen,
                rewards[:, idx].T,
                real_next[:, idx].transpose(1, 0, 2),
                terminated[:, idx].T,
            )
            losses = group.learner.train()
            if losses is not None:
                self.last_losses.update({a.name: float(loss) for a, loss in zip(group.agents, losses, strict=True)})

        self._chase_steps += actions[:, :-1, 0]
        self.env_steps += 1
        for arena in np.flatnonzero(done):
            self._finish_episode(int(arena), info)
        self.obs = next_obs

    @staticmethod
    def _put(actions: np.ndarray, i: int, env_actions: np.ndarray) -> None:
        if env_actions.ndim == 2:
            actions[:, i] = env_actions
        else:
            actions[:, i, 1] = env_actions

    def _finish_episode(self, arena: int, info: dict[str, Any]) -> None:
        length = int(info["episode_length"][arena])
        chase = self._chase_steps[arena] / length
        self._chase_steps[arena] = 0.0
        if self.episodes_done >= self.config.episodes:
            return  # arenas finishing on the last step beyond the budget are not counted
        self.episodes_done += 1
        extra: dict[str, float] = {f"loss/{a}": loss for a, loss in self.last_losses.items()}
        if self.groups:
            learner = self.groups[0].learner
            extra.update({"epsilon": learner.epsilon, "beta": learner.beta})
        record = EpisodeRecord(
            episode=self.episodes_done,
            length=length,
            captured=bool(info["captured"][arena]),
            returns={a: float(r) for a, r in zip(self.names, info["episode_return"][arena], strict=True)},
            chase_fraction={a: float(c) for a, c in zip(self.names[:-1], chase, strict=True)},
            extra=extra,
        )
        if self.on_episode is not None:
            self.on_episode(record)
