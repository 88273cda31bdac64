"""The agents: what each learns, what it stores and how it turns a decision into an env action.

- :class:`HierarchicalPredator` (paper 2.4): the network picks the mode (stalk/chase, A = 2);
  parallel navigation picks the direction (with ``avoidance``, around obstacles). The replay
  stores the mode, never the direction.
- :class:`Prey`: the network picks one of the 12 directions (A = 12).
- :class:`FlatPredator` (ablation): the network picks one of the 24 (mode, direction) pairs,
  action ``a = 12 · mode + direction``; no rule.
- The residual predator (the paper's future work, residual RL) has a module of its own,
  :mod:`pursuit_bench.agents.residual`; :mod:`pursuit_bench.agents.registry` names every kind.
- :class:`ScriptedAgent`: a scripted policy (always-chase, always-stalk, fleeing prey) behind
  the same ``act`` / ``act_batch`` interface.

Every agent has ``act(observation, *, explore)`` for one observation and ``act_batch`` for a
stack (B, n_obs). A learning agent is member ``member`` of a :class:`DQNLearner`, alone
(one member) or stacked with the other agents of its kind.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
import torch

import pursuit_bench.agents.names as names
from pursuit_bench.agents.config import AgentConfig
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.env.task import N_DIRECTIONS
from pursuit_bench.rules.navigation import navigate
from pursuit_bench.rules.policies import Policy


class LearningAgent:
    """One agent's view of its learner: member ``member`` of ``learner``."""

    kind: ClassVar[str]
    n_actions: ClassVar[int]

    def __init__(self, name: str, learner: DQNLearner, member: int = 0) -> None:
        if learner.n_actions != self.n_actions:
            raise ValueError(f"{self.kind} needs a learner with {self.n_actions} actions, got {learner.n_actions}")
        self.name, self.learner, self.member = name, learner, member

    @classmethod
    def new_learner(
        cls, n_obs: int, config: AgentConfig, *, members: int = 1, seed: int | Sequence[int] = 0
    ) -> DQNLearner:
        """A learner for ``members`` agents of this kind (one seed per member, or one)."""
        return DQNLearner(n_obs, cls.n_actions, config, members=members, seed=seed)

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Env actions for the network's choices (B,), integers, given the observations (B, n_obs)."""
        raise NotImplementedError

    def decide(
        self, obs: np.ndarray, *, explore: bool, epsilon: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(choices, env_actions, q_values, values)`` for observations (B, n_obs): what the
        replay stores, what the env receives, and the network's Q (B, A) and V(s) (B,) that
        led there; ε-greedy when ``explore`` (ε from the schedule unless given). This runs the
        whole learner; a training loop acts for all members at once instead."""
        stacked = np.zeros((self.learner.members, *obs.shape), dtype=np.float32)
        stacked[self.member] = obs
        q, v = self.learner.evaluate(stacked)
        choices = self.learner.choose(q, explore=explore, epsilon=epsilon)[self.member]
        return choices, self.to_env(choices, obs), q[self.member], v[self.member]

    def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> np.ndarray:
        """Env actions (B, …) for observations (B, n_obs): :meth:`decide`'s, by the fast forward
        pass whose choices are torch's (:meth:`DQNLearner.decisive_q`), drawing exploration
        from the learner's generators exactly as :meth:`decide` does."""
        obs = np.asarray(obs, dtype=np.float32)
        q = self.learner.decisive_q(obs, self.member)
        if not explore:
            choices = q.argmax(axis=-1)
        else:
            everyone = np.zeros((self.learner.members, *q.shape), dtype=np.float32)
            everyone[self.member] = q
            choices = self.learner.choose(everyone, explore=True, epsilon=epsilon)[self.member]
        return self.to_env(choices, obs)

    def act(self, observation: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> Any:
        return self.act_batch(np.asarray(observation)[None], explore=explore, epsilon=epsilon)[0]

    def _own(self, obs: np.ndarray) -> torch.Tensor:
        stacked = torch.zeros((self.learner.members, *obs.shape))
        stacked[self.member] = torch.as_tensor(obs, dtype=torch.float32)
        return stacked

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """Q-values (B, A) of the online network."""
        return self.learner.q_values(self._own(obs).numpy())[self.member]

    def value_features(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The value stream's last hidden layer (B, 32) and V(s) (B,): the paper's Fig. 3 input."""
        with torch.no_grad():
            hidden, value, _ = self.learner.online.streams(self.learner.encode(self._own(obs)))
        return hidden[self.member].numpy(), value[self.member, :, 0].numpy()


class HierarchicalPredator(LearningAgent):
    """Deep RL picks how hard (stalk 0 / chase 1); parallel navigation picks where. With
    ``avoidance`` (a task with obstacles: the observations end with range readings) the lower
    layer steers around what they show (:func:`pursuit_bench.rules.navigation.navigate`)."""

    kind = names.HIERARCHICAL
    n_actions = 2

    def __init__(self, name: str, learner: DQNLearner, member: int = 0, *, avoidance: bool = False) -> None:
        super().__init__(name, learner, member)
        self.avoidance = avoidance

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        actions = np.empty((*np.shape(choices), 2), dtype=np.int64)  # (mode, direction) pairs
        actions[..., 0] = choices
        actions[..., 1] = navigate(obs, choices, avoidance=self.avoidance)
        return actions

    @staticmethod
    def mode_q(q: np.ndarray) -> np.ndarray:
        """The Q-value of each mode (…, 2) from the network's (…, A): what recordings draw."""
        return q


class Prey(LearningAgent):
    """Deep RL over the 12 directions."""

    kind = names.PREY
    n_actions = N_DIRECTIONS

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        return choices


class FlatPredator(LearningAgent):
    """Ablation: deep RL over all 24 (mode, direction) pairs, no rule."""

    kind = names.FLAT
    n_actions = 2 * N_DIRECTIONS

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        return np.stack(np.divmod(choices, N_DIRECTIONS), axis=-1)


class ScriptedAgent:
    """A scripted policy under the agents' interface (``explore`` is ignored)."""

    kind = names.SCRIPTED

    def __init__(self, name: str, policy: Policy) -> None:
        self.name, self.policy = name, policy

    def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> np.ndarray:
        batch = getattr(self.policy, "act_batch", None)
        if batch is not None:
            return np.asarray(batch(np.asarray(obs)))
        return np.array([self.policy.act(o) for o in obs])

    def act(self, observation: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> Any:
        return self.act_batch(np.asarray(observation)[None])[0]


def members_to_env(agents: list[LearningAgent], choices: np.ndarray, obs: np.ndarray) -> list[np.ndarray] | np.ndarray:
    """Each member's env actions (member m's at ``[m]``) for the choices (M, B) of one learner's
    members ``agents`` given their observations (M, B, n_obs): one call of the rule for all of
    them, one array (M, B, 2), when they are hierarchical predators that steer alike (the rule
    is elementwise: the same numbers)."""
    first = agents[0]
    if isinstance(first, HierarchicalPredator) and all(
        type(a) is type(first) and isinstance(a, HierarchicalPredator) and a.avoidance == first.avoidance
        for a in agents
    ):
        return first.to_env(choices, obs)
    return [agent.to_env(choices[m], obs[m]) for m, agent in enumerate(agents)]
