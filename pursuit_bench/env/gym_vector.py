"""The single-agent Gymnasium view, N of them at once, as a real ``gymnasium.vector.VectorEnv``
backed by the batched core (one core of N arenas, not N envs): what
``gymnasium.make_vec("pursuit_bench/Pursuit-v0", num_envs=N, agent=..., condition=...)`` returns.

It gives, step for step, what ``gymnasium.vector.SyncVectorEnv`` over N
:class:`~pursuit_bench.env.single.PursuitSingleAgentEnv` gives with ``autoreset_mode=SAME_STEP``
(``tests/test_gym_vector.py``): env i seeded with ``seed + i``; an episode that ends returns its
reward and ``terminated``/``truncated`` on that step with the next episode's first observation,
its last observation in ``info["final_obs"]`` (where ``info["_final_obs"]``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pursuit_bench.env import task
from pursuit_bench.env.single import DefaultOpponent, Policy, resolve_opponents
from pursuit_bench.env.vector import VectorPursuitEnv, put_actions


class PursuitVectorEnv(VectorEnv):
    """``num_envs`` copies of the single-agent view of ``agent``, stepped as one batch.

    Args:
        num_envs: the number of arenas N.
        agent: the learning agent, e.g. ``"predator_0"`` or ``"prey_0"``.
        condition: one of the paper's conditions (default ``"1p-low"``).
        opponents: policies for some or all of the other agents (``act_batch(observations)`` is
            used when they have it, else ``act`` arena by arena); the rest get
            ``default_opponent(name, obstacles)`` (``gymnasium.make_vec`` passes the scripted ones).
        backend: ``"pymunk"`` (default) or ``"numpy"``.
        **options: the task's other options (``max_steps``, ``wall_rule`` …).

    Observations are (N, 6n-2) float32; actions (N, 2) integers for a predator, (N,) for the
    prey, or (N, 2) floats for either with ``continuous=True``; rewards (N,) float64;
    ``terminated`` and ``truncated`` (N,) bool.
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int,
        agent: str = "predator_0",
        condition: str | None = "1p-low",
        opponents: Mapping[str, Policy] | None = None,
        backend: str = "pymunk",
        default_opponent: DefaultOpponent | None = None,
        **options: Any,
    ) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs={num_envs!r}: expected an integer >= 1")
        self._vec = VectorPursuitEnv(num_envs, condition, backend=backend, **options)  # type: ignore[arg-type]
        names = self._vec.agents
        self._opponents = resolve_opponents(agent, names, opponents, self._vec.config.obstacles > 0, default_opponent)
        self.agent, self.num_envs = agent, num_envs
        self._index = names.index(agent)
        self.single_observation_space = self._vec.single_observation_spaces[agent]
        self.single_action_space = self._vec.single_action_spaces[agent]
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._obs = np.zeros((num_envs, len(names), self._vec.obs_size), dtype=np.float32)

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start every arena afresh; ``seed``: an integer (arena i seeded ``seed + i``, as
        ``SyncVectorEnv`` seeds its envs) or one per arena."""
        if isinstance(seed, int):
            seed = [seed + i for i in range(self.num_envs)]
        self._obs, _ = self._vec.reset(seed=seed)
        return self._obs[:, self._index], {}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        continuous = self._vec.config.continuous
        mine = np.asarray(actions)
        expected = "floats" if continuous else "integers"
        if mine.shape[:1] != (self.num_envs,) or mine.dtype.kind not in ("fiu" if continuous else "iu"):
            raise ValueError(f"actions: expected {expected} with {self.num_envs} rows, got {mine.dtype} {mine.shape}")
        batch = np.zeros((self.num_envs, self._vec.n_agents, 2), dtype=np.int64)  # the opponents' discrete actions
        if not continuous:
            put_actions(batch, self._index, mine.astype(np.int64))
        for i, name in enumerate(self._vec.agents):
            if name == self.agent:
                continue
            policy, obs = self._opponents[name], self._obs[:, i]
            if hasattr(policy, "act_batch"):
                chosen = np.asarray(policy.act_batch(obs))
            else:
                chosen = np.array([np.asarray(policy.act(o)) for o in obs])
            put_actions(batch, i, chosen.astype(np.int64))
        if continuous:  # the opponents' actions as the vectors equal to them, then ours
            vectors = task.discrete_as_continuous(batch[:, :-1, 0], batch[..., 1])
            vectors[:, self._index] = mine
            self._obs, rewards, terminated, truncated, info = self._vec.step(vectors)
        else:
            self._obs, rewards, terminated, truncated, info = self._vec.step(batch)
        i = self._index
        done = info["done"]
        infos: dict[str, Any] = {}
        if done.any():
            infos = {"final_obs": np.where(done[:, None], info["final_obs"][:, i], 0.0), "_final_obs": done}
        return self._obs[:, i], rewards[:, i], terminated[:, i], truncated[:, i], infos
