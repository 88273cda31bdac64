"""Training: every agent of a condition learns at once, each an independent learner, in B
arenas; and K such runs trained as one.

A *run* is one :class:`TrainConfig`. It owns its batched env, its agents, their replays, its
counters and its random streams. Learners of the same shape and hyper-parameters, within a run
and across runs, are stacked as the members of one :class:`DQNLearner`, so K runs cost one
forward pass and one update per group instead of K. A member's random streams (network
initialisation, exploration, replay sampling) come from its run's seed and its agent, and a
run's arenas from its seed, so what a run learns does not depend on its companions.

The loop, top to bottom (:meth:`Trainer.step`): act (one forward pass per group of learners) →
step every run's env → store each agent's transition → update → count finished episodes.
A run that reaches its episode budget is finished: its arenas stop, and its members leave their
stacked learners (each keeps a learner of its own with its final state), so a stack costs what
its unfinished runs cost.
The CLI parses options into a :class:`TrainConfig` and calls :class:`Trainer`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from pursuit_bench.agents.checkpoint import agent_state, load_agent_state
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.kinds import HierarchicalPredator, LearningAgent, ScriptedAgent, members_to_env
from pursuit_bench.agents.registry import KINDS
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.vector import VectorPursuitEnv, put_actions
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey
from pursuit_bench.training.train_config import (
    TrainConfig as TrainConfig,  # the configuration lives apart: no torch there
)
from pursuit_bench.trajectories.recording import EpisodeTrace, EpisodeTraces, Recorder


def member_seed(run_seed: int, agent: int) -> int:
    """The seed of agent ``agent``'s learner in a run seeded ``run_seed``."""
    return int(np.random.SeedSequence([run_seed, agent]).generate_state(1)[0])


@dataclass
class Group:
    """Agents that share one (stacked) learner: member m is ``agents[m]``, agent ``indices[m]``
    of run ``runs[m]``."""

    learner: DQNLearner
    agents: list[LearningAgent]
    indices: list[int]
    runs: list[int]
    span: tuple[int, slice] | None = field(init=False)
    """``(run, agents)`` when the members are consecutive agents of one run, in order (every
    member of a run alone, or its predators): their rows are one slice."""

    def __post_init__(self) -> None:
        if not self.indices or len(self.indices) != len(self.runs):
            raise ValueError(f"a group: expected one run per member, got indices {self.indices}, runs {self.runs}")
        first = self.indices[0]
        one_run = all(r == self.runs[0] for r in self.runs)
        consecutive = self.indices == list(range(first, first + len(self.indices)))
        self.span = (self.runs[0], slice(first, first + len(self.indices))) if one_run and consecutive else None

    def rows(self, arrays: Sequence[np.ndarray] | Mapping[int, np.ndarray]) -> np.ndarray:
        """Each member's rows of its run's array (B, n_agents, …), ``arrays[r]`` for run r,
        stacked as (M, B, …): the values of ``np.stack`` of ``arrays[runs[m]][:, indices[m]]``,
        as a view of ``arrays[r]`` when the members are one slice of run r's agents."""
        if self.span is not None:
            run, agents = self.span
            return arrays[run][:, agents].swapaxes(0, 1)
        return _stacked([arrays[r][:, i] for r, i in zip(self.runs, self.indices, strict=True)])

    def put(self, actions: Mapping[int, np.ndarray], env_actions: Sequence[np.ndarray] | np.ndarray) -> None:
        """Write member m's env actions ``env_actions[m]``, (B, 2) ``(mode, direction)`` pairs or
        (B,) directions, into its run's actions ``actions[r]`` (B, n_agents, 2): one assignment when
        the members are a slice of one run's agents and their pairs one array (M, B, 2)."""
        if self.span is not None and isinstance(env_actions, np.ndarray) and env_actions.ndim == 3:
            run, agents = self.span
            actions[run][:, agents] = env_actions.swapaxes(0, 1)
            return
        for m, (r, i) in enumerate(zip(self.runs, self.indices, strict=True)):
            put_actions(actions[r], i, env_actions[m])


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


def build_agents(
    configs: Sequence[TrainConfig], n_obs: Sequence[int]
) -> tuple[list[Group], list[dict[str, LearningAgent | ScriptedAgent]]]:
    """The learner groups over all runs, and every run's agents by name. Learners stack when
    their kind, observation size, hyper-parameters and arena count agree (and the run allows it)."""
    plans: dict[tuple, list[tuple[int, int, str]]] = {}  # group key -> members (run, agent index, name)
    kinds: dict[tuple, type[LearningAgent]] = {}
    runs_agents: list[dict[str, LearningAgent | ScriptedAgent]] = []
    for r, config in enumerate(configs):
        names = list(CONDITIONS[config.condition].agent_names)
        predators, prey = names[:-1], names[-1]
        agents: dict[str, LearningAgent | ScriptedAgent] = {}
        learning: list[tuple[type[LearningAgent], str]] = []
        if config.predator in KINDS:
            learning += [(KINDS[config.predator], p) for p in predators]
        else:
            fixed = AlwaysChase if config.predator == "always_chase" else AlwaysStalk
            agents.update({p: ScriptedAgent(p, fixed(avoidance=config.avoids)) for p in predators})
        if config.prey == "learning":
            learning.append((KINDS["prey"], prey))
        else:
            agents[prey] = ScriptedAgent(prey, FleeingPrey(obstacles=config.obstacles > 0))
        for kind, name in learning:
            alone = () if config.batched_learners or kind.kind == "prey" else (r, name)
            # the training length (agent.episodes, the run's) is no learner's hyper-parameter: runs of
            # other lengths stack, and leave the stack as they finish
            key = (kind.kind, n_obs[r], config.agent.replace(episodes=1), config.num_envs, *alone)
            kinds[key] = kind
            plans.setdefault(key, []).append((r, names.index(name), name))
        runs_agents.append(agents)
    groups = []
    for key, members in plans.items():
        seeds = [member_seed(configs[r].seed, i) for r, i, _ in members]
        kind = kinds[key]
        learner = kind.new_learner(key[1], configs[members[0][0]].agent, members=len(members), seed=seeds)
        made = [
            kind(name, learner, m, avoidance=configs[r].avoids)
            if issubclass(kind, HierarchicalPredator)
            else kind(name, learner, m)
            for m, (r, _, name) in enumerate(members)
        ]
        groups.append(Group(learner, made, [i for _, i, _ in members], [r for r, _, _ in members]))
        for (r, _, name), agent in zip(members, made, strict=True):
            runs_agents[r][name] = agent
    ordered = [
        {a: agents[a] for a in CONDITIONS[c.condition].agent_names}
        for c, agents in zip(configs, runs_agents, strict=True)
    ]
    return groups, ordered


def load_agents_state(agents: dict[str, LearningAgent | ScriptedAgent], state: dict[str, Any], condition: str) -> None:
    """Load a run checkpoint's agents (:meth:`Trainer.state_dict`) into ``agents`` by name."""
    learning = {name: a for name, a in agents.items() if isinstance(a, LearningAgent)}
    if set(state["agents"]) != set(learning):
        raise ValueError(f"checkpoint holds agents {sorted(state['agents'])}, this run has {sorted(learning)}")
    for name, agent in learning.items():
        load_agent_state(agent, state["agents"][name], condition)


class Run:
    """One run inside a :class:`Trainer`: its env, agents, counters and what it reports."""

    def __init__(
        self,
        config: TrainConfig,
        on_episode: Callable[[EpisodeRecord], None] | None,
        recorder: Recorder | None,
        record_every: int,
    ) -> None:
        if isinstance(record_every, bool) or not isinstance(record_every, int) or record_every < 1:
            raise ValueError(f"record_every={record_every!r}: expected an integer >= 1")
        self.config, self.on_episode = config, on_episode
        self.recorder, self.record_every = recorder, record_every
        self.env = VectorPursuitEnv(config.num_envs, config.condition, backend=config.backend, **config.task_options)
        self.names = self.env.agents
        self.n_predators = len(self.names) - 1
        self.agents: dict[str, LearningAgent | ScriptedAgent] = {}
        self.learner: DQNLearner | None = None  # whose ε and β the metrics show
        self.episodes_done = 0
        self.env_steps = 0
        self.last_losses: dict[str, float] = {}
        self.pending: list[EpisodeRecord] = []  # episodes ended beyond the budget, reported if it grows
        self.obs, _ = self.env.reset(seed=config.seed)
        self.chase_steps = np.zeros((config.num_envs, self.n_predators))
        core = self.env.core
        self.traces = (
            EpisodeTraces(core.world.positions, core.config.max_steps, core.obstacles) if recorder is not None else None
        )
        self.q_values = np.full((config.num_envs, self.n_predators, 2), np.nan)  # for recordings
        self.values = np.full((config.num_envs, self.n_predators), np.nan)

    @property
    def finished(self) -> bool:
        return self.episodes_done >= self.config.episodes

    def after_step(self, actions: np.ndarray, step: tuple[np.ndarray, ...], info: dict[str, Any]) -> None:
        """Count the step, trace it, and report the episodes it ended."""
        next_obs, rewards, _, truncated = step
        self.chase_steps += actions[:, :-1, 0]
        self.env_steps += 1
        if self.traces is not None:
            self.traces.add_step(actions, rewards, info, self.q_values, self.values)
        ended = info["done"].nonzero()[0]
        if len(ended):
            self._finish_episodes(ended, info, truncated[ended, 0])
        self.obs = next_obs

    def _finish_episodes(self, arenas: np.ndarray, info: dict[str, Any], truncated: np.ndarray) -> None:
        """Report the episodes that ended in ``arenas`` this step, in arena order."""
        lengths = info["episode_length"][arenas]
        chase = (self.chase_steps[arenas] / lengths[:, None]).tolist()
        extra: dict[str, float] = {f"loss/{a}": loss for a, loss in self.last_losses.items()}
        if self.learner is not None:
            extra.update({"epsilon": self.learner.epsilon, "beta": self.learner.beta})
        returns, captured = info["episode_return"][arenas].tolist(), info["captured"][arenas].tolist()
        for k, (arena, length) in enumerate(zip(arenas.tolist(), lengths.tolist(), strict=True)):
            self.chase_steps[arena] = 0.0  # each arena's count reset as its episode is reported
            trace = None
            if self.traces is not None:
                world = self.env.core.world
                trace = self.traces.finish(arena, bool(truncated[k]), world.positions[arena], world.obstacles[arena])
            record = EpisodeRecord(
                episode=0,  # numbered when reported
                length=length,
                captured=captured[k],
                returns=dict(zip(self.names, returns[k], strict=True)),
                chase_fraction=dict(zip(self.names[:-1], chase[k], strict=True)),
                extra=dict(extra),
            )
            if self.finished:  # beyond the budget: not counted, kept for a resume that extends it
                self.pending.append(record)
            else:
                self._report(record, trace)

    def _report(self, record: EpisodeRecord, trace: EpisodeTrace | None) -> None:
        """Count a finished episode and tell the recorder and ``on_episode`` of it."""
        self.episodes_done += 1
        record.episode = self.episodes_done  # the record is this run's alone: numbered in place
        if self.recorder is not None:
            recorded = self.episodes_done == 1 or self.episodes_done % self.record_every == 0
            if recorded and trace is not None:
                self.recorder.log_episode(self.episodes_done, trace)
            metrics = {f"return/{a}": r for a, r in record.returns.items()}
            metrics.update({"length": float(record.length), "captured": float(record.captured), **record.extra})
            metrics.update({f"chase_fraction/{a}": f for a, f in record.chase_fraction.items()})
            self.recorder.log_metrics(self.episodes_done, metrics)
        if self.on_episode is not None:
            self.on_episode(record)

    def state_dict(self) -> dict[str, Any]:
        """The run's checkpoint. A finished run stops stepping and leaves its learners with its
        members' final state (:meth:`Trainer._drop_finished`), so this stays as it finished.
        It holds the arenas mid-episode too (``arenas``: the env's state, the last observations,
        the chase counts), the last losses and the episodes ended beyond the budget, so that a
        resumed run goes on exactly as one that never stopped."""
        arenas = {"env": self.env.state_dict(), "obs": self.obs, "chase_steps": self.chase_steps}
        return {
            "arenas": _as_tensors(arenas),
            "last_losses": dict(self.last_losses),
            "pending": [dataclasses.asdict(record) for record in self.pending],
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
        """Restore :meth:`state_dict`: the arenas go on where they were (a checkpoint written
        before they were saved restarts them, from a seed derived from the run's seed and the
        episode count); the episodes that ended beyond the old budget are reported first."""
        load_agents_state(self.agents, state, self.config.condition)
        self.episodes_done, self.env_steps = int(state["episodes_done"]), int(state["env_steps"])
        if "arenas" in state:
            arenas = _as_arrays(state["arenas"])
            self.env.load_state_dict(arenas["env"])
            self.obs, self.chase_steps = arenas["obs"], arenas["chase_steps"]
            self.last_losses = {a: float(v) for a, v in state["last_losses"].items()}
        else:
            self.obs, _ = self.env.reset(seed=self.config.seed + 1_000_003 * self.episodes_done)
            self.chase_steps[:] = 0.0
        if self.traces is not None:
            core = self.env.core
            self.traces = EpisodeTraces(core.world.positions, core.config.max_steps, core.obstacles)
        if self.recorder is not None:  # a resumed piece of the recording plays on after the last
            self.recorder.clock = max(self.recorder.clock, int(state.get("recording_clock", 0)))
        pending = [EpisodeRecord(**record) for record in state.get("pending", [])]
        self.pending = []
        for record in pending:
            if self.finished:
                self.pending.append(record)
            else:
                self._report(record, None)


def _as_tensors(value: Any) -> Any:
    """numpy arrays as torch tensors, all the way down: what a checkpoint read with
    ``weights_only`` holds (``_as_arrays`` turns them back)."""
    if isinstance(value, np.ndarray):
        return torch.from_numpy(value.copy())
    if isinstance(value, dict):
        return {k: _as_tensors(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_as_tensors(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _as_arrays(value: Any) -> Any:
    if isinstance(value, torch.Tensor):
        return value.numpy()
    if isinstance(value, dict):
        return {k: _as_arrays(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_as_arrays(v) for v in value]
    return value


def _stacked(arrays: list[np.ndarray]) -> np.ndarray:
    """``np.stack(arrays)`` of arrays of one shape and type (each member's rows of the same
    kind); a view of the one array when there is one (a run alone)."""
    first = arrays[0]
    if len(arrays) == 1:
        return first[None]
    if any(a.shape != first.shape or a.dtype != first.dtype for a in arrays):
        raise ValueError(f"rows to stack: expected one shape and type, got {[(a.shape, a.dtype.name) for a in arrays]}")
    stacked = np.empty((len(arrays), *first.shape), dtype=first.dtype)
    for k, array in enumerate(arrays):
        stacked[k] = array
    return stacked


def _per_run(value: Any, k: int, what: str) -> list[Any]:
    """``value`` for each of k runs: a list of k, or one value (for k = 1, or None for all)."""
    if isinstance(value, (list, tuple)):
        if len(value) != k:
            raise ValueError(f"{what}: expected one per run ({k}), got {len(value)}")
        return list(value)
    if value is not None and k > 1:
        raise ValueError(f"{what}: expected a list of one per run ({k})")
    return [value] * k


class Trainer:
    """Trains K runs as one: ``config`` is one :class:`TrainConfig` or a list. ``on_episode``
    (one callback, or one per run) is called with each finished episode of its run. With a
    ``recorder`` (one per run), every ``record_every``-th episode of that run (one number, or
    one per run; and its first episode) goes into it, and every episode's metrics; without
    one, no Rerun call is made.

    ``agents``, ``episodes_done``, ``env``, ``state_dict`` and ``load_state_dict`` speak of
    run 0, the only one when K = 1; ``runs[r]`` holds run r."""

    def __init__(
        self,
        config: TrainConfig | Sequence[TrainConfig],
        on_episode: Callable[[EpisodeRecord], None] | Sequence[Callable[[EpisodeRecord], None] | None] | None = None,
        *,
        recorder: Recorder | Sequence[Recorder | None] | None = None,
        record_every: int | Sequence[int] = 100,
    ) -> None:
        configs = [config] if isinstance(config, TrainConfig) else list(config)
        if not configs:
            raise ValueError("config: expected at least one run")
        k = len(configs)
        callbacks, recorders = _per_run(on_episode, k, "on_episode"), _per_run(recorder, k, "recorder")
        every = _per_run(record_every, k, "record_every") if not isinstance(record_every, int) else [record_every] * k
        self.runs = [Run(*run) for run in zip(configs, callbacks, recorders, every, strict=True)]
        self.groups, agents = build_agents(configs, [run.env.obs_size for run in self.runs])
        for run, run_agents in zip(self.runs, agents, strict=True):
            run.agents = run_agents
        for group in self.groups:
            for r in group.runs:
                self.runs[r].learner = self.runs[r].learner or group.learner

    @property
    def config(self) -> TrainConfig:
        return self.runs[0].config

    @property
    def env(self) -> VectorPursuitEnv:
        return self.runs[0].env

    @property
    def agents(self) -> dict[str, LearningAgent | ScriptedAgent]:
        return self.runs[0].agents

    @property
    def episodes_done(self) -> int:
        return self.runs[0].episodes_done

    @property
    def finished(self) -> bool:
        return all(run.finished for run in self.runs)

    def state_dict(self, run: int = 0) -> dict[str, Any]:
        """Everything a resumed run needs: its learning agents and its counters."""
        return self.runs[run].state_dict()

    def load_state_dict(self, state: dict[str, Any], run: int = 0) -> None:
        """Restore run ``run`` from :meth:`state_dict`: the episodes under way when it was taken
        go on where they were (:meth:`Run.load_state_dict`). Runs stacked together move in
        lockstep: all must be restored from the same number of env steps (ValueError otherwise,
        once all are loaded: see :meth:`check_lockstep`)."""
        self.runs[run].load_state_dict(state)

    def check_lockstep(self) -> None:
        """ValueError unless the runs of every group have taken the same number of env steps."""
        for group in self.groups:
            steps = {self.runs[r].env_steps for r in group.runs}
            if len(steps) > 1:
                raise ValueError(f"runs stacked together must resume from the same env step, got {sorted(steps)}")

    def run(self, should_stop: Callable[[], bool] = lambda: False) -> None:
        """Step until every run has finished its episodes (or ``should_stop()``)."""
        while not self.finished and not should_stop():
            self.step()

    def step(self) -> None:
        """One step of every arena of every unfinished run: act, step, store, update, count
        episodes; then the runs this step finished leave their learners."""
        active = [r for r, run in enumerate(self.runs) if not run.finished]
        actions = {
            r: np.zeros((self.runs[r].config.num_envs, len(self.runs[r].names), 2), dtype=np.int64) for r in active
        }
        decided = []
        observations = [run.obs for run in self.runs]
        recording = any(self.runs[r].traces is not None for r in active)
        for group in self.groups:  # one forward pass per group, all its runs at once
            obs = np.ascontiguousarray(group.rows(observations))  # one copy for the network, the rule and the replay
            chosen, q, v = group.learner.act_members(obs, explore=True)
            decided.append((obs, chosen))
            group.put(actions, members_to_env(group.agents, chosen, obs))
            if recording:  # what the recordings draw: each hierarchical predator's Q and V
                for m, (agent, r, i) in enumerate(zip(group.agents, group.runs, group.indices, strict=True)):
                    if self.runs[r].traces is not None and isinstance(agent, HierarchicalPredator):
                        self.runs[r].q_values[:, i], self.runs[r].values[:, i] = agent.mode_q(q[m]), v[m]
        for r in active:
            run = self.runs[r]
            for i, name in enumerate(run.names):
                scripted = run.agents[name]
                if isinstance(scripted, ScriptedAgent):
                    put_actions(actions[r], i, scripted.act_batch(run.obs[:, i]))

        steps = {r: self.runs[r].env.step(actions[r]) for r in active}
        # what each arena's agents saw next: the ended episodes' last observations, not the new ones
        # (VectorPursuitEnv's final_obs is every arena's observation before its autoreset)
        real_next = {r: info["final_obs"] for r, (_, _, _, _, info) in steps.items()}
        rewards_of = {r: step[1] for r, step in steps.items()}
        terminated_of = {r: step[2] for r, step in steps.items()}
        for group, (obs, chosen) in zip(self.groups, decided, strict=True):
            group.learner.store(obs, chosen, group.rows(rewards_of), group.rows(real_next), group.rows(terminated_of))
            losses = group.learner.train()
            if losses is not None:
                for agent, r, loss in zip(group.agents, group.runs, losses.tolist(), strict=True):
                    self.runs[r].last_losses[agent.name] = loss

        for r in active:
            next_obs, rewards, terminated, truncated, info = steps[r]
            self.runs[r].after_step(actions[r], (next_obs, rewards, terminated, truncated), info)
        if any(self.runs[r].finished for r in active):
            self._drop_finished()

    def _drop_finished(self) -> None:
        """Finished runs leave their groups: the other members go on in a learner of their own
        (:meth:`DQNLearner.take`, the same arithmetic), each finished member keeps its final
        state in a learner of one."""
        groups = []
        for group in self.groups:
            members = list(zip(group.agents, group.indices, group.runs, strict=True))
            going_on = [m for m, (_, _, r) in enumerate(members) if not self.runs[r].finished]
            if len(going_on) == len(members):
                groups.append(group)
                continue
            for m, (agent, _, r) in enumerate(members):
                if self.runs[r].finished:
                    agent.learner, agent.member = group.learner.take([m]), 0
                    self.runs[r].learner = agent.learner
            if going_on:
                learner = group.learner.take(going_on)
                kept = [members[m] for m in going_on]
                for new_member, (agent, _, r) in enumerate(kept):
                    agent.learner, agent.member = learner, new_member
                    self.runs[r].learner = learner
                groups.append(Group(learner, [a for a, _, _ in kept], [i for _, i, _ in kept], [r for _, _, r in kept]))
        self.groups = groups
