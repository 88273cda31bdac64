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

from pursuit_bench.agents.checkpoint import agent_state, load_agent_state
from pursuit_bench.agents.config import QUICK, AgentConfig
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.kinds import KINDS, LearningAgent, ScriptedAgent
from pursuit_bench.conditions import CONDITIONS
from pursuit_bench.policies import AlwaysChase, AlwaysStalk, FleeingPrey
from pursuit_bench.recording import EpisodeTraces, Recorder
from pursuit_bench.vector import VectorPursuitEnv, put_actions
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

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrainConfig:
        """The inverse of :meth:`to_dict`; unknown keys are a ValueError."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise ValueError(f"unknown training option(s) {unknown}")
        agent = AgentConfig().replace(**data.get("agent", {}))
        return cls(**{**data, "agent": agent})


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


def load_agents_state(agents: dict[str, LearningAgent | ScriptedAgent], state: dict[str, Any], condition: str) -> None:
    """Load a run checkpoint's agents (:meth:`Trainer.state_dict`) into ``agents`` by name."""
    learning = {name: a for name, a in agents.items() if isinstance(a, LearningAgent)}
    if set(state["agents"]) != set(learning):
        raise ValueError(f"checkpoint holds agents {sorted(state['agents'])}, this run has {sorted(learning)}")
    for name, agent in learning.items():
        load_agent_state(agent, state["agents"][name], condition)


class Trainer:
    """Runs :class:`TrainConfig`; ``on_episode`` is called with each finished episode. With a
    ``recorder``, every ``record_every``-th episode (and the first) goes into it, and every
    episode's metrics; without one, no Rerun call is made."""

    def __init__(
        self,
        config: TrainConfig,
        on_episode: Callable[[EpisodeRecord], None] | None = None,
        *,
        recorder: Recorder | None = None,
        record_every: int = 100,
    ) -> None:
        if isinstance(record_every, bool) or not isinstance(record_every, int) or record_every < 1:
            raise ValueError(f"record_every={record_every!r}: expected an integer >= 1")
        self.config = config
        self.recorder, self.record_every = recorder, record_every
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
        self._traces = (
            EpisodeTraces(self.env.core.world.positions, self.env.config.max_steps) if recorder is not None else None
        )

    def state_dict(self) -> dict[str, Any]:
        """Everything a resumed run needs: every learning agent and the counters."""
        return {
            "episodes_done": self.episodes_done,
            "env_steps": self.env_steps,
            "recording_clock": self.recorder.clock if self.recorder is not None else 0,
            "config": self.config.to_dict(),
            "agents": {
                a.name: agent_state(a, self.config.condition)
                for a in self.agents.values()
                if isinstance(a, LearningAgent)
            },
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Restore from :meth:`state_dict`. Episodes under way when it was taken are not resumed:
        every arena starts afresh, from a seed derived from the run's seed and the episode count."""
        load_agents_state(self.agents, state, self.config.condition)
        self.episodes_done, self.env_steps = int(state["episodes_done"]), int(state["env_steps"])
        self.obs, _ = self.env.reset(seed=self.config.seed + 1_000_003 * self.episodes_done)
        self._chase_steps[:] = 0.0
        if self._traces is not None:
            self._traces = EpisodeTraces(self.env.core.world.positions, self.env.config.max_steps)
        if self.recorder is not None:  # a resumed piece of the recording plays on after the last
            self.recorder.clock = max(self.recorder.clock, int(state.get("recording_clock", 0)))

    def run(self, should_stop: Callable[[], bool] = lambda: False) -> None:
        """Step until the configured number of episodes has finished (or ``should_stop()``)."""
        while self.episodes_done < self.config.episodes and not should_stop():
            self.step()

    def step(self) -> None:
        """One step of every arena: act, step, store, update, count episodes."""
        obs = self.obs
        actions = np.zeros((self.config.num_envs, len(self.names), 2), dtype=np.int64)
        choices = []
        q_values = np.full((self.config.num_envs, self.n_predators, 2), np.nan)  # for recordings
        values = np.full((self.config.num_envs, self.n_predators), np.nan)
        for group in self.groups:  # one forward pass per group
            group_obs = obs[:, group.indices].transpose(1, 0, 2)  # (M, B, n_obs)
            q, v = group.learner.evaluate(group_obs)
            chosen = group.learner.choose(q, explore=True)
            choices.append(chosen)
            for m, (agent, i) in enumerate(zip(group.agents, group.indices, strict=True)):
                put_actions(actions, i, agent.to_env(chosen[m], obs[:, i]))
                if agent.kind == "hierarchical":
                    q_values[:, i], values[:, i] = q[m], v[m]
        for i, name in enumerate(self.names):
            scripted = self.agents[name]
            if isinstance(scripted, ScriptedAgent):
                put_actions(actions, i, scripted.act_batch(obs[:, i]))

        next_obs, rewards, terminated, truncated, info = self.env.step(actions)
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
        if self._traces is not None:
            self._traces.add_step(actions, rewards, info, q_values, values)
        for arena in np.flatnonzero(done):
            self._finish_episode(int(arena), info, bool(truncated[arena, 0]))
        self.obs = next_obs

    def _finish_episode(self, arena: int, info: dict[str, Any], truncated: bool) -> None:
        length = int(info["episode_length"][arena])
        chase = self._chase_steps[arena] / length
        self._chase_steps[arena] = 0.0
        trace = None
        if self._traces is not None:
            trace = self._traces.finish(arena, truncated, self.env.core.world.positions[arena])
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
        if self.recorder is not None and trace is not None:
            if self.episodes_done == 1 or self.episodes_done % self.record_every == 0:
                self.recorder.log_episode(self.episodes_done, trace)
            metrics = {f"return/{a}": r for a, r in record.returns.items()}
            metrics.update({"length": float(length), "captured": float(record.captured), **extra})
            metrics.update({f"chase_fraction/{a}": f for a, f in record.chase_fraction.items()})
            self.recorder.log_metrics(self.episodes_done, metrics)
        if self.on_episode is not None:
            self.on_episode(record)
