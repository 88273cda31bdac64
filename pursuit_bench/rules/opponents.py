"""The single-agent views with the scripted agents as the opponents not given: what
``gymnasium.make("pursuit_bench/Pursuit-v0", …)`` and ``gymnasium.make_vec`` build (the views
live in ``env``, which does not know the scripted agents)."""

from __future__ import annotations

from typing import Any

from pursuit_bench.env.gym_vector import PursuitVectorEnv
from pursuit_bench.env.single import Policy, PursuitSingleAgentEnv
from pursuit_bench.rules.policies import AlwaysChase, FleeingPrey


def default_opponent(agent: str, obstacles: bool = False) -> Policy:
    """The scripted stand-in for an agent: always-chase predators, a fleeing prey; in a task
    with ``obstacles`` both steer around them."""
    return FleeingPrey(obstacles=obstacles) if agent.startswith("prey") else AlwaysChase(avoidance=obstacles)


def single_agent_env(**kwargs: Any) -> PursuitSingleAgentEnv:
    """:class:`~pursuit_bench.env.single.PursuitSingleAgentEnv` with :func:`default_opponent`."""
    return PursuitSingleAgentEnv(default_opponent=default_opponent, **kwargs)


def vector_env(num_envs: int, **kwargs: Any) -> PursuitVectorEnv:
    """:class:`~pursuit_bench.env.gym_vector.PursuitVectorEnv` with :func:`default_opponent`."""
    return PursuitVectorEnv(num_envs, default_opponent=default_opponent, **kwargs)
