"""Many arenas stepped at once: the same core as the single env, with stacked arrays.

Autoreset is *same-step*: when an arena's episode ends on a step, that step's rewards,
``terminated`` and ``truncated`` belong to the ended episode, the returned observation is
already the first of the arena's next episode, and the ended episode's last observation is in
``info["final_obs"]`` (every arena's observation before the autoreset: where not
``info["done"]``, the returned one). A learner bootstraps from it, unless
the arena terminated. Each arena draws its start states from its own generator, spawned from
the seed given to ``reset``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numba
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from pursuit_bench.env import task
from pursuit_bench.env.agent_spaces import agent_spaces
from pursuit_bench.env.conditions import TaskConfig, resolve_condition
from pursuit_bench.env.core import PursuitCore
from pursuit_bench.env.world import Backend


@numba.njit(cache=True)
def _actions_in_range(actions, n_directions):
    """Whether every predator's mode (``actions[:, :-1, 0]``) is 0 or 1 and every agent's
    direction (``actions[..., 1]``) in ``0 … n_directions - 1``."""
    arenas, agents, _ = actions.shape
    for b in range(arenas):
        for i in range(agents):
            if i < agents - 1 and not 0 <= actions[b, i, 0] <= 1:
                return False
            if not 0 <= actions[b, i, 1] < n_directions:
                return False
    return True


def put_actions(actions: np.ndarray, agent: int, env_actions: np.ndarray) -> None:
    """Write one agent's env actions, (B, 2) ``(mode, direction)`` or (B,) directions, into a
    batch of actions (B, n_agents, 2)."""
    if env_actions.ndim == 2:
        actions[:, agent] = env_actions
    else:
        actions[:, agent, 1] = env_actions


class VectorPursuitEnv:
    """``num_envs`` arenas of one condition, stepped together.

    Args:
        num_envs: number of arenas B.
        condition: one of :data:`pursuit_bench.CONDITIONS`, or None to give the options.
        backend: ``"pymunk"`` (the reference, default) or ``"numpy"``.
        blocks: sizes of consecutive runs of arenas, each laid out in the physics as an env of
            that many arenas alone lays them out (an arena's play then gives the bits it gives
            there; an evaluation batching what used to be separate envs uses it). Default: one.
        **options: ``n_predators``, ``chase_cost``, ``reward_sharing``, ``max_steps``, ``wall_rule``,
            ``continuous``, ``obstacles``, ``obstacle_radius``.

    ``step(actions)`` takes integers of shape (B, n_agents, 2): ``(mode, direction)`` per agent
    (the prey's mode is ignored), or with ``continuous=True`` floats of that shape (each agent's
    acceleration in its line-of-sight frame), and returns ``obs`` (B, n_agents, 6n-2) float32, ``rewards``
    (B, n_agents) float64, ``terminated`` and ``truncated`` (B, n_agents) bool, and ``info``
    with ``done`` (B,), ``final_obs`` (B, n_agents, 6n-2) (before any autoreset), ``positions`` (B, n_agents, 2)
    float64 at the end of the step (before any autoreset), ``captured`` (B,), ``touching_prey``
    (B, n_predators), ``left_area`` (B, n_agents), ``touching_obstacle`` (B, n_agents),
    ``episode_return`` (B, n_agents) and ``episode_length`` (B,) of the episodes that ended.
    With obstacles (``obstacles=K``) observations end with 12 range readings and
    ``obstacles`` is every arena's, (B, K, 3) rows of x, y, radius.

    Spaces: ``single_observation_spaces`` and ``single_action_spaces`` by agent name (those of
    the PettingZoo env), ``observation_spaces`` and ``action_spaces`` the same batched over the
    B arenas (Gymnasium's ``batch_space``); ``observation_space`` is the whole (B, n_agents,
    6n-2) array ``step`` returns and ``action_space`` the whole (B, n_agents, 2) array it takes
    (``MultiDiscrete`` of (mode, direction), the prey's mode ignored; ``Box(-1, 1)`` when
    continuous): ``action_space.sample()`` is a valid action. The ended episodes' last
    observations are in ``info["final_obs"]``, Gymnasium's vector env's name.

    The contract beside the ecosystem's: like VMAS, every array is stacked with the arena axis
    first and every arena steps on every call; unlike VMAS (a list per agent) and PettingZoo
    (dicts by agent name), agents are a second axis, in ``agents`` order; unlike PettingZoo, no
    agent leaves an arena mid-episode: an episode ends for all of its agents at once, and that
    arena resets on the same step (above).
    """

    def __init__(
        self,
        num_envs: int,
        condition: str | None = None,
        *,
        backend: Backend = "pymunk",
        blocks: list[int] | None = None,
        **options: Any,
    ):
        self.config: TaskConfig = resolve_condition(condition, **options)
        self.condition = condition
        self.num_envs = num_envs
        self.core = PursuitCore(self.config, num_envs, backend=backend, blocks=blocks)
        self.agents = list(self.config.agent_names)
        self.n_agents = self.config.n_agents
        self.obs_size = task.obs_size(self.n_agents, self.config.obstacles > 0)
        self.observation_space = spaces.Box(-np.inf, np.inf, (num_envs, self.n_agents, self.obs_size), np.float32)
        shape = (num_envs, self.n_agents, 2)
        self.action_space: spaces.Space[Any] = (
            spaces.Box(-1.0, 1.0, shape, np.float64)
            if self.config.continuous
            else spaces.MultiDiscrete(np.broadcast_to(np.array([2, task.N_DIRECTIONS]), shape))
        )
        self.single_observation_spaces, self.single_action_spaces = agent_spaces(self.config)
        self.observation_spaces = {a: batch_space(sp, num_envs) for a, sp in self.single_observation_spaces.items()}
        self.action_spaces = {a: batch_space(sp, num_envs) for a, sp in self.single_action_spaces.items()}
        self._rngs = [np.random.default_rng(s) for s in np.random.SeedSequence().spawn(num_envs)]
        self._returns = np.zeros((num_envs, self.n_agents))
        # start layouts set for some arenas' next episodes (``queue_starts``): used once, instead of a draw
        self._queued = np.zeros(num_envs, dtype=bool)
        self._queued_positions = np.zeros((num_envs, self.n_agents, 2))
        self._queued_obstacles = np.zeros((num_envs, self.config.obstacles, 3))

    @property
    def obstacles(self) -> np.ndarray:
        """(B, K, 3) every arena's obstacles in its current episode (x, y, radius)."""
        return self.core.world.obstacles.copy()

    def reset(self, seed: int | Sequence[int] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Start every arena afresh. ``seed``: one integer, from which every arena's generator is
        spawned; or one integer per arena, arena i then drawing exactly what a single env reset
        with ``seed[i]`` draws (Gymnasium's ``SyncVectorEnv`` seeds its env i with ``seed + i``)."""
        if isinstance(seed, (list, tuple, np.ndarray)):
            if len(seed) != self.num_envs:
                raise ValueError(f"seed: expected one per arena ({self.num_envs}), got {len(seed)}")
            self._rngs = [np.random.default_rng(int(s)) for s in seed]
        elif seed is not None:
            self._rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(self.num_envs)]
        obs = self.core.reset(np.arange(self.num_envs), self._rngs)
        self._returns[:] = 0.0
        self._queued[:] = False
        return obs, {}

    def reseed(self, arena: int, seed: int) -> None:
        """Draw arena ``arena``'s next start states (from its next reset on) from a generator
        seeded ``seed``: what a single env reset with ``seed`` draws first. An evaluation with
        common random numbers gives each episode its own seed this way."""
        self._rngs[arena] = np.random.default_rng(seed)

    def queue_starts(self, arenas: np.ndarray, positions: np.ndarray, obstacles: np.ndarray | None = None) -> None:
        """Start arenas ``arenas``' next episodes (at their next autoreset, once) from the layouts
        ``positions`` (len(arenas), n_agents, 2) and, in a task with obstacles, ``obstacles``
        (len(arenas), K, 3), instead of drawing them. An evaluation with common random numbers
        draws each episode's start once (``core.first_start``) for every arena that plays it."""
        arenas = np.asarray(arenas, dtype=np.int64)
        self._queued_positions[arenas] = task.check_positions(positions, (len(arenas), self.n_agents, 2))
        if self.config.obstacles:
            self._queued_obstacles[arenas] = self.core._given_obstacles(obstacles, len(arenas))
        self._queued[arenas] = True

    def _restart(self, arenas: np.ndarray) -> np.ndarray:
        """Reset ``arenas`` (ended this step): from their queued layouts where set, else drawn."""
        queued = self._queued[arenas]
        if not queued.any():
            return self.core.reset(arenas, [self._rngs[i] for i in arenas.tolist()])
        obs = np.empty((len(arenas), self.n_agents, self.obs_size), dtype=np.float32)
        given = arenas[queued]
        placed = self._queued_obstacles[given] if self.config.obstacles else None
        obs[queued] = self.core.reset(given, [], self._queued_positions[given], placed)
        self._queued[given] = False
        if not queued.all():
            drawn = arenas[~queued]
            obs[~queued] = self.core.reset(drawn, [self._rngs[i] for i in drawn.tolist()])
        return obs

    def state_dict(self) -> dict[str, Any]:
        """Every arena as it is mid-episode, with its generator and return so far: with
        :meth:`load_state_dict`, an env that goes on exactly as this one would (a checkpoint)."""
        return {
            "rngs": [rng.bit_generator.state for rng in self._rngs],
            "returns": self._returns.copy(),
            "core": self.core.state_dict(),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Put back :meth:`state_dict` (of an env of the same task and number of arenas)."""
        if len(state["rngs"]) != self.num_envs:
            raise ValueError(f"state of {len(state['rngs'])} arenas: expected {self.num_envs}")
        self._rngs = []
        for saved in state["rngs"]:
            rng = np.random.default_rng()
            rng.bit_generator.state = saved
            self._rngs.append(rng)
        self._returns = np.array(state["returns"], dtype=np.float64)
        self.core.load_state_dict(state["core"], self._rngs)

    def _check(self, actions: np.ndarray) -> np.ndarray:
        arr = np.asarray(actions)
        expected = (self.num_envs, self.n_agents, 2)
        if arr.shape != expected or arr.dtype.kind not in "iu":
            raise ValueError(f"actions: expected integers of shape {expected}, got {arr.dtype} {arr.shape}")
        if not _actions_in_range(arr, task.N_DIRECTIONS):
            raise ValueError("actions: modes must be 0 (stalk) or 1 (chase) and directions in 0..11")
        return arr

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if self.config.continuous:
            vectors = np.asarray(actions, dtype=np.float64)
            if vectors.shape != (self.num_envs, self.n_agents, 2) or not np.isfinite(vectors).all():
                raise ValueError(f"actions: expected finite floats of shape {(self.num_envs, self.n_agents, 2)}")
            result = self.core.step_continuous(vectors)
        else:
            arr = self._check(actions)
            result = self.core.step(arr[:, :-1, 0], arr[..., 1])
        self._returns += result.rewards
        done = result.terminated | result.truncated
        info: dict[str, Any] = {
            "done": done,
            "final_obs": result.observations,
            "positions": self.core.world.positions.copy(),
            "captured": result.captured,
            "touching_prey": result.contacts.prey,
            "left_area": result.contacts.wall,
            "touching_obstacle": result.contacts.obstacle,
            "episode_return": self._returns.copy(),
            "episode_length": self.core.steps.copy(),
        }
        obs = result.observations
        ended = done.nonzero()[0]
        if len(ended):
            obs = obs.copy()  # the ended episodes' last observations stay in the info
            obs[ended] = self._restart(ended)
            self._returns[ended] = 0.0
        terminated = result.terminated.repeat(self.n_agents).reshape(self.num_envs, self.n_agents)
        truncated = result.truncated.repeat(self.n_agents).reshape(self.num_envs, self.n_agents)
        return obs, result.rewards, terminated, truncated, info
