"""Running fixed agents for many episodes in B arenas and collecting what they did."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from pursuit_bench.vector import VectorPursuitEnv
from pursuit_bench.world import Backend


class Actor(Protocol):
    def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> Any: ...


@dataclass
class Episodes:
    """Per-episode results, in the order the episodes finished."""

    returns: np.ndarray
    """(E, n_agents) cumulative reward."""
    lengths: np.ndarray
    """(E,) steps."""
    captured: np.ndarray
    """(E,) bool."""
    chase_fraction: np.ndarray
    """(E, n_predators) fraction of steps in chase mode."""
    distance: np.ndarray
    """(E, n_agents) distance travelled."""


def run_episodes(
    condition: str,
    actors: dict[str, Actor],
    episodes: int,
    *,
    seed: int,
    num_envs: int = 16,
    epsilons: dict[str, float] | None = None,
    backend: Backend = "pymunk",
) -> Episodes:
    """Play ``episodes`` episodes with ``actors`` (one per agent name). Agents named in
    ``epsilons`` act ε-greedily with that ε (learning agents only), the rest greedily."""
    env = VectorPursuitEnv(min(num_envs, episodes), condition, backend=backend)
    epsilons = epsilons or {}
    names, n_pred = env.agents, env.n_agents - 1
    obs, _ = env.reset(seed=seed)
    chase = np.zeros((env.num_envs, n_pred))
    travelled = np.zeros((env.num_envs, env.n_agents))
    rows: list[tuple[np.ndarray, int, bool, np.ndarray, np.ndarray]] = []
    while len(rows) < episodes:
        actions = np.zeros((env.num_envs, env.n_agents, 2), dtype=np.int64)
        for i, name in enumerate(names):
            eps = epsilons.get(name)
            chosen = np.asarray(actors[name].act_batch(obs[:, i], explore=eps is not None, epsilon=eps))
            if chosen.ndim == 2:
                actions[:, i] = chosen
            else:
                actions[:, i, 1] = chosen
        before = env.core.world.positions.copy()
        obs, _, _, _, info = env.step(actions)
        final = info["final_observation"]  # positions are its first two entries per agent
        travelled += np.hypot(*(final[..., :2] - before).transpose(2, 0, 1))
        chase += actions[:, :-1, 0]
        for arena in np.flatnonzero(info["done"]):
            length = int(info["episode_length"][arena])
            rows.append(
                (
                    info["episode_return"][arena].copy(),
                    length,
                    bool(info["captured"][arena]),
                    chase[arena] / length,
                    travelled[arena].copy(),
                )
            )
            chase[arena] = 0.0
            travelled[arena] = 0.0
    rows = rows[:episodes]
    return Episodes(
        returns=np.array([r[0] for r in rows]),
        lengths=np.array([r[1] for r in rows]),
        captured=np.array([r[2] for r in rows]),
        chase_fraction=np.array([r[3] for r in rows]).reshape(len(rows), n_pred),
        distance=np.array([r[4] for r in rows]),
    )
