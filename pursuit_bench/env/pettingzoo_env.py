"""The pursuit task as a PettingZoo ``ParallelEnv`` (and, through PettingZoo's converter, AEC)."""

from __future__ import annotations

import functools
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import AECEnv, ParallelEnv
from pettingzoo.utils import parallel_to_aec

from pursuit_bench.env import task
from pursuit_bench.env.agent_spaces import POSITION_BOUND, VELOCITY_BOUND, agent_spaces
from pursuit_bench.env.conditions import OBSTACLE_RADII, TaskConfig, resolve_condition
from pursuit_bench.env.core import PursuitCore
from pursuit_bench.env.render import draw_arena
from pursuit_bench.env.world import Backend

#: Observation bounds: positions lie in [-1, 1], relative positions in [-2√2, 2√2] and speeds
#: never exceed the chase terminal speed 1.44 (see ``world``), so these bounds always hold.


def _action_error(agent: str, action: Any, allowed: str) -> ValueError:
    return ValueError(f"action for {agent}: got {action!r}, expected {allowed}")


def parse_continuous(agent: str, action: Any) -> np.ndarray:
    """One agent's continuous action as a float64 2-vector, or ``ValueError``."""
    arr = np.asarray(action, dtype=np.float64) if not isinstance(action, str) else None
    if arr is None or arr.shape != (2,) or not np.isfinite(arr).all():
        raise _action_error(agent, action, "a finite 2-vector (acceleration in the line-of-sight frame, norm <= 1)")
    return arr


def as_continuous(agent: str, action: Any, is_predator: bool) -> np.ndarray:
    """A discrete action (a scripted opponent's, say) as the continuous action equal to it."""
    mode, direction = parse_action(agent, action, is_predator)
    level = task.MODE_NORMS[mode] if is_predator else 1.0
    return task.as_xy(task.ROTATIONS[direction] * level)


def parse_action(agent: str, action: Any, is_predator: bool) -> tuple[int, int]:
    """``(mode, direction)`` from one agent's action (the prey's mode is 0), or ``ValueError``."""
    # fast paths for what the action spaces sample: an int64 pair, an integer scalar
    if is_predator and type(action) is np.ndarray and action.dtype == np.int64 and action.shape == (2,):
        mode, direction = action.tolist()
        if 0 <= mode <= 1 and 0 <= direction < task.N_DIRECTIONS:
            return mode, direction
    elif not is_predator and type(action) in (int, np.int64) and 0 <= action < task.N_DIRECTIONS:
        return 0, int(action)
    allowed = "(mode in 0..1, direction in 0..11)" if is_predator else "a direction in 0..11"
    arr = np.asarray(action)
    if arr.dtype.kind == "f":
        if not np.isfinite(arr).all() or (arr != np.round(arr)).any():
            raise _action_error(agent, action, allowed + " as integers")
    elif arr.dtype.kind not in "iu":
        raise _action_error(agent, action, allowed + " as integers")
    if is_predator:
        if arr.shape != (2,):
            raise _action_error(agent, action, allowed + ", shape (2,)")
        mode, direction = int(arr[0]), int(arr[1])
        if not (0 <= mode <= 1 and 0 <= direction < task.N_DIRECTIONS):
            raise _action_error(agent, action, allowed)
        return mode, direction
    if arr.size != 1 or arr.ndim > 1:
        raise _action_error(agent, action, allowed + ", a scalar")
    direction = int(arr.reshape(()))
    if not 0 <= direction < task.N_DIRECTIONS:
        raise _action_error(agent, action, allowed)
    return 0, direction


class PursuitParallelEnv(ParallelEnv[str, np.ndarray, Any]):
    """Predators hunt a prey in a walled 2-D arena (Tsutsui, Takeda, Fujii 2023).

    ## Description

    One prey (``prey_0``, blue) and 1–3 predators (``predator_0`` …, red) are disks of radius
    0.05 in the square arena ``[-1, 1]²``. Every step (0.1 s) each agent accelerates in one of 12
    directions relative to its line of sight (LOS): a predator's LOS points at the prey, the
    prey's at its nearest predator. Velocities lose 25 % per step (viscous drag). Predators also
    choose a mode: stalk (acceleration 1.8, 60 % of the prey's 3.0) or chase (3.6, 120 %, at a
    cost). Predators pass through each other.

    ## Action Space

    Direction index ``k`` in 0..11 is the unit vector at ``-k · 30°`` from the LOS (k = 0 straight
    at the target, 6 straight away).

    | agent | space | meaning |
    |---|---|---|
    | ``predator_i`` | ``MultiDiscrete([2, 12])`` | (mode: 0 stalk / 1 chase, direction k) |
    | ``prey_0`` | ``Discrete(12)`` | direction k |

    With ``continuous=True`` every agent's action is ``Box(-1, 1, (2,))``: an acceleration in its
    LOS frame (u, v), norm ≤ 1 (longer is scaled to 1), times its maximum (prey 3.0, predators
    3.6); a predator chases, and pays for it, in a step whose norm exceeds 0.5 (the stalk level
    1.8). Discrete action (mode, k) is the vector ``level · (cos(-k·30°), sin(-k·30°))`` with
    level 0.5 (stalk) or 1 (chase), the prey's level 1: the two give the same trajectories.

    ## Observation Space

    ``Box(float32, (6n - 2,))`` per agent for n agents in all (10, 16, 22), 12 more with
    obstacles. (u, v) is the observing agent's LOS frame: u along the LOS, v to its left.

    | index | observation |
    |---|---|
    | 0, 1 | own x, y (world frame) |
    | 2, 3 | own velocity (u, v) |
    | 4 + 6j, 5 + 6j | other agent j: x, y |
    | 6 + 6j, 7 + 6j | other agent j: position relative to self (u, v) |
    | 8 + 6j, 9 + 6j | other agent j: velocity (u, v) |
    | 6n - 2 + k, k = 0..11 | with obstacles: range reading along direction k |

    Other agents in order: for a predator the prey, then the other predators by index; for the
    prey the predators by increasing distance. A range reading is how far the agent's centre can
    travel along direction k (the action's, in the LOS frame) before its disk touches an obstacle
    or a wall, 0 when touching, capped at 1.

    ## Rewards

    | event | predator | prey |
    |---|---|---|
    | capture (a predator's disk overlaps the prey's) | +1 each (``shared``) / +1 if touching (``individual``) | -1 |
    | leaving the area (a disk touches or crosses a wall) | -1 to that predator | -1 |
    | a step in chase mode | ``-chase_cost`` | – |

    Events in one step add up.

    ## Starting State

    Positions uniform in ``[-0.5, 0.5]²`` with no two disks overlapping; velocities zero. With
    obstacles, drawn after the positions from the same generator: centres uniform where each
    keeps a gap of 0.15 from the walls and from every other obstacle, every agent's disk 0.05
    clear of them. ``env.obstacles`` is this episode's, (K, 3) rows of x, y, radius.

    ## Obstacles

    ``obstacles=K`` static circles of radius ``obstacle_radius`` stand in the arena. Agents
    collide with them as solid, frictionless, inelastic bodies: no reward, no episode end.

    ## Episode End

    - Termination: a capture, or (``wall_rule="terminate"``) any agent leaving the area.
    - Truncation: ``max_steps`` steps (300 = 30 s) without termination.

    Either ends the episode for every agent (``env.agents`` becomes empty).

    ## Arguments

    - ``condition``: one of :data:`pursuit_bench.CONDITIONS` (e.g. ``"2p-high-shared"``); it fixes
      the next three, which may instead be given directly:
    - ``n_predators`` (1–3, default 1), ``chase_cost`` (≥ 0, default 0.01),
      ``reward_sharing`` (``"shared"`` default, or ``"individual"``);
    - ``max_steps`` (default 300);
    - ``wall_rule``: ``"terminate"`` (default, the paper) or ``"contain"`` (walls stop the disk,
      -1 per step in contact, the episode goes on);
    - ``continuous``: ``False`` (default, the paper) or ``True`` (acceleration actions, above);
    - ``obstacles`` (0–8, default 0: the paper's empty arena, unchanged) and ``obstacle_radius``
      (0.1–0.25, default 0.15); at most ``K (2 r + 0.15)² <= 1.65``;
    - ``render_mode``: ``None`` or ``"rgb_array"``;
    - ``backend``: ``"pymunk"`` (default, the reference) or ``"numpy"``.

    ``info[agent]`` holds ``captured`` (this predator touches the prey / the prey was caught),
    ``left_area``, ``distance_to_prey`` (the prey: to its nearest predator) and, for predators,
    ``mode`` (0 stalk, 1 chase; -1 at reset).

    ## Version History

    - v0: first release.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "name": "pursuit_v0",
        "render_modes": ["rgb_array"],
        "render_fps": 10,
        "is_parallelizable": True,
    }

    def __init__(
        self,
        condition: str | None = None,
        *,
        n_predators: int | None = None,
        chase_cost: float | None = None,
        reward_sharing: str | None = None,
        max_steps: int | None = None,
        wall_rule: str | None = None,
        continuous: bool = False,
        obstacles: int = 0,
        obstacle_radius: float | None = None,
        render_mode: str | None = None,
        backend: Backend = "pymunk",
    ) -> None:
        self.config: TaskConfig = resolve_condition(
            condition,
            n_predators=n_predators,
            chase_cost=chase_cost,
            reward_sharing=reward_sharing,
            max_steps=max_steps,
            wall_rule=wall_rule,
            continuous=continuous,
            obstacles=obstacles,
            obstacle_radius=obstacle_radius,
        )
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode={render_mode!r}: expected None or 'rgb_array'")
        self.condition = condition
        self.render_mode = render_mode
        self.possible_agents = list(self.config.agent_names)
        self.agents: list[str] = []
        self._core = PursuitCore(self.config, 1, backend=backend)
        self._n_predators = self.config.n_predators
        self._agent_set = set(self.possible_agents)
        self._parse_plan = [(a, i < self._n_predators) for i, a in enumerate(self.possible_agents)]
        self._observation_spaces, self._action_spaces = agent_spaces(self.config)
        agent_bound = [POSITION_BOUND] * 2 + [VELOCITY_BOUND] * 2
        obstacle_bound = [POSITION_BOUND] * 2 + [OBSTACLE_RADII[1]]
        state_bound = np.array(
            agent_bound * self.config.n_agents + obstacle_bound * self.config.obstacles, dtype=np.float32
        )
        self.state_space = spaces.Box(-state_bound, state_bound, dtype=np.float32)
        self.np_random, self.np_random_seed = seeding.np_random()

    @functools.cache  # noqa: B019 - PettingZoo requires the same object
    def observation_space(self, agent: str) -> spaces.Space[Any]:
        return self._observation_spaces[agent]

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> spaces.Space[Any]:
        return self._action_spaces[agent]

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Start a new episode.

        ``options={"positions": array (n_agents, 2)}`` places the agents (in ``possible_agents``
        order) instead of drawing them, and in a task with obstacles ``"obstacles": array
        (K, 3)`` (x, y, radius) must come with them; other keys are ignored.
        """
        if seed is not None:
            self.np_random, self.np_random_seed = seeding.np_random(seed)
        positions = (options or {}).get("positions")
        obstacles = (options or {}).get("obstacles")
        if positions is not None:
            positions = task.check_positions(positions, (self.config.n_agents, 2))[None]
            obstacles = None if obstacles is None else np.asarray(obstacles, dtype=np.float64)[None]
        obs = self._core.reset(np.array([0]), [self.np_random], positions, obstacles)[0]
        self.agents = list(self.possible_agents)
        no = np.zeros((1, self.config.n_agents), dtype=bool)
        distance = task.distances_to_prey(self._core.world.positions)
        infos = self._infos(no[:, :-1], no, np.full((1, self._n_predators), -1), distance)
        return {a: obs[i] for i, a in enumerate(self.agents)}, infos

    def _infos(
        self, prey_contact: np.ndarray, wall: np.ndarray, modes: np.ndarray, distance: np.ndarray
    ) -> dict[str, dict[str, Any]]:
        """Per-agent infos of arena 0 from (1, …) arrays."""
        touching, walls, mode_list, distances = (
            prey_contact[0].tolist(),
            wall[0].tolist(),
            modes[0].tolist(),
            distance[0].tolist(),
        )
        infos: dict[str, dict[str, Any]] = {
            name: {
                "captured": touching[i],
                "left_area": walls[i],
                "mode": mode_list[i],
                "distance_to_prey": distances[i],
            }
            for i, name in enumerate(self.possible_agents[:-1])
        }
        infos["prey_0"] = {"captured": any(touching), "left_area": walls[-1], "distance_to_prey": distances[-1]}
        return infos

    def step(
        self, actions: dict[str, Any]
    ) -> tuple[dict[str, np.ndarray], dict[str, float], dict[str, bool], dict[str, bool], dict[str, dict[str, Any]]]:
        if not self.agents:
            raise ValueError("step() called on a finished episode: call reset() first")
        if actions.keys() != self._agent_set:
            unknown = sorted(set(actions) - self._agent_set)
            if unknown:
                raise ValueError(f"actions for unknown agent(s) {unknown}: expected keys {self.agents}")
            missing = sorted(self._agent_set - set(actions))
            raise ValueError(f"missing action for {', '.join(missing)}: every live agent acts each step")
        if self.config.continuous:
            vectors = np.stack([parse_continuous(agent, actions[agent]) for agent in self.possible_agents])
            r = self._core.step_continuous(vectors[None])
        else:
            parsed = [parse_action(agent, actions[agent], predator) for agent, predator in self._parse_plan]
            modes, directions = np.array(parsed, dtype=np.int64).T[:, None, :]
            r = self._core.step(modes[:, : self._n_predators], directions)
        agents = self.possible_agents
        terminated, truncated = bool(r.terminated[0]), bool(r.truncated[0])
        obs = dict(zip(agents, r.observations[0], strict=True))
        rewards = dict(zip(agents, r.rewards[0].tolist(), strict=True))
        infos = self._infos(r.contacts.prey, r.contacts.wall, r.modes, r.distance_to_prey)
        if terminated or truncated:
            self.agents = []
        return obs, rewards, dict.fromkeys(agents, terminated), dict.fromkeys(agents, truncated), infos

    def state(self) -> np.ndarray:
        """Global state, float32 ``[x, y, vx, vy]`` per agent in ``possible_agents`` order, then
        ``[x, y, radius]`` per obstacle."""
        return self._core.state()[0]

    @property
    def obstacles(self) -> np.ndarray:
        """(K, 3) this episode's obstacles, rows of x, y, radius (K = 0 without obstacles)."""
        return self._core.world.obstacles[0].copy()

    def render(self) -> np.ndarray | None:
        """An RGB frame (uint8, 400×400×3) in ``rgb_array`` mode; None when render_mode is None."""
        if self.render_mode is None:
            return None
        return draw_arena(self._core.world.positions[0], obstacles=self._core.world.obstacles[0])

    def close(self) -> None:
        pass


ENV_OPTIONS = (
    "n_predators",
    "chase_cost",
    "reward_sharing",
    "max_steps",
    "wall_rule",
    "continuous",
    "obstacles",
    "obstacle_radius",
    "render_mode",
    "backend",
)


def parallel_env(condition: str | None = None, **options: Any) -> PursuitParallelEnv:
    """The pursuit env as a PettingZoo ``ParallelEnv``; see :class:`PursuitParallelEnv`."""
    unknown = sorted(set(options) - set(ENV_OPTIONS))
    if unknown:
        raise ValueError(f"unknown option(s) {unknown}: expected some of {list(ENV_OPTIONS)}")
    return PursuitParallelEnv(condition, **options)


def env(condition: str | None = None, **options: Any) -> AECEnv[str, np.ndarray, Any]:
    """The pursuit env as a PettingZoo AEC env (PettingZoo's conversion of the parallel one)."""
    return parallel_to_aec(parallel_env(condition, **options))
