"""A single-agent Gymnasium view of the pursuit env: one agent learns, the others follow
policies passed in. Registered as ``pursuit_bench/Pursuit-v0`` through
:mod:`pursuit_bench.rules.opponents`, which gives the scripted agents as default opponents (this
layer does not know them)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from pursuit_bench.env.pettingzoo_env import PursuitParallelEnv, as_continuous


class Policy(Protocol):
    """What an opponent is: ``act(observation) -> action`` (one agent's observation)."""

    def act(self, observation: np.ndarray) -> Any: ...


#: Makes an agent's default opponent: ``default(agent name, the task has obstacles)``.
DefaultOpponent = Callable[[str, bool], Policy]


def resolve_opponents(
    agent: str,
    agents: list[str],
    opponents: Mapping[str, Policy] | None,
    obstacles: bool = False,
    default: DefaultOpponent | None = None,
) -> dict[str, Policy]:
    """The policy of every agent but ``agent``: the given ones, ``default(name, obstacles)`` for
    the rest (``obstacles``: the task has some); ValueError for an unknown learning agent, an
    opponent that is not another agent, or one missing with no default."""
    if agent not in agents:
        raise ValueError(f"agent={agent!r}: expected one of {agents}")
    given = dict(opponents or {})
    strangers = sorted(set(given) - set(agents) | ({agent} & set(given)))
    if strangers:
        raise ValueError(f"opponents for {strangers}: expected other agents of {agents}")
    missing = [a for a in agents if a != agent and given.get(a) is None]
    if missing and default is None:
        raise ValueError(
            f"no policy for {missing}: expected them in opponents (gymnasium.make gives the scripted ones by default)"
        )
    return {a: given.get(a) or default(a, obstacles) for a in agents if a != agent}  # type: ignore[misc]


class PursuitSingleAgentEnv(gym.Env[np.ndarray, Any]):
    """One agent of :class:`~pursuit_bench.env.pettingzoo_env.PursuitParallelEnv` as a Gymnasium env.

    Spaces, rewards and episode end are that agent's in the multi-agent env (see its docstring).

    Args:
        agent: the learning agent, e.g. ``"predator_0"`` or ``"prey_0"``.
        condition: one of the paper's conditions (default ``"1p-low"``).
        opponents: policies (``act(observation) -> action``) for some or all of the other agents;
            the rest get ``default_opponent(name, obstacles)``.
        default_opponent: makes the policies not given (``gymnasium.make`` passes
            :func:`pursuit_bench.rules.opponents.default_opponent`); None: all must be given.
        render_mode: ``None`` or ``"rgb_array"``.
        **options: any other option of the multi-agent env (``max_steps``, ``wall_rule``,
            ``continuous`` …); with ``continuous=True`` the opponents' discrete actions are
            turned into the continuous actions equal to them.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012 - typed so by gym.Env

    def __init__(
        self,
        agent: str = "predator_0",
        condition: str | None = "1p-low",
        opponents: Mapping[str, Policy] | None = None,
        render_mode: str | None = None,
        default_opponent: DefaultOpponent | None = None,
        **options: Any,
    ) -> None:
        self._env = PursuitParallelEnv(condition, render_mode=render_mode, **options)
        obstacles = self._env.config.obstacles > 0
        self.opponents = resolve_opponents(agent, self._env.possible_agents, opponents, obstacles, default_opponent)
        self.agent = agent
        self.render_mode = render_mode
        self.observation_space = self._env.observation_space(agent)
        self.action_space = self._env.action_space(agent)
        self._last_obs: dict[str, np.ndarray] = {}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        obs, infos = self._env.reset(seed=seed, options=options)
        self._last_obs = obs
        return obs[self.agent], infos[self.agent]

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        actions = {a: policy.act(self._last_obs[a]) for a, policy in self.opponents.items()}
        if self._env.config.continuous:  # the scripted opponents act discretely: their equal vectors
            predators = self._env.possible_agents[:-1]
            actions = {a: as_continuous(a, act, a in predators) for a, act in actions.items()}
        actions[self.agent] = action
        obs, rewards, terminated, truncated, infos = self._env.step(actions)
        self._last_obs = obs
        a = self.agent
        return obs[a], rewards[a], terminated[a], truncated[a], infos[a]

    @property
    def obstacles(self) -> np.ndarray:
        """(K, 3) this episode's obstacles, rows of x, y, radius."""
        return self._env.obstacles

    def render(self) -> np.ndarray | None:
        return self._env.render()
