"""The plain numpy prioritized replay that ``ReplayStack`` (``pursuit_bench/agents/replay.py``) is
pinned against in the tests: one member's ring buffer of ``(obs, action, reward, next_obs,
terminated)`` with proportional priorities (Schaul et al. 2015), sampled through one of two
samplers sharing one small interface (``set``, ``draw``): a flat cumulative sum, simplest at the
paper's capacity 1e4, and a sum tree for large capacities. Both recompute sums from the stored
priorities (the tree from its children). Until 0.2 it was ``pursuit_bench.agents.PrioritizedReplay``;
no learner used it.
"""

from __future__ import annotations

from typing import Any, Literal, Protocol

import numpy as np

from pursuit_bench.agents.replay import Batch

#: Above this capacity the sum tree replaces the flat cumulative sum.
TREE_ABOVE = 65_536


class Sampler(Protocol):
    """Holds one non-negative value per slot and draws slots in proportion to them."""

    def set(self, indices: np.ndarray, values: np.ndarray) -> None: ...

    def get(self, indices: np.ndarray) -> np.ndarray: ...

    def total(self, size: int) -> float: ...

    def draw(self, fractions: np.ndarray, size: int) -> np.ndarray: ...


class CumulativeSumSampler:
    """Draws by a binary search in the cumulative sum of the filled slots (O(n) per draw)."""

    def __init__(self, capacity: int) -> None:
        self.values = np.zeros(capacity)

    def set(self, indices: np.ndarray, values: np.ndarray) -> None:
        self.values[indices] = values

    def get(self, indices: np.ndarray) -> np.ndarray:
        return self.values[indices]

    def total(self, size: int) -> float:
        return float(self.values[:size].sum())

    def draw(self, fractions: np.ndarray, size: int) -> np.ndarray:
        """Indices in ``[0, size)`` with probability proportional to their values; ``fractions``
        uniform in [0, 1)."""
        cumulative = np.cumsum(self.values[:size])
        picks = np.searchsorted(cumulative, fractions * cumulative[-1], side="right")
        # a zero-valued slot adds nothing to the sum, so only rounding at the very top can pick
        # past the end: those picks go to the last slot with a value
        over = picks >= size
        if over.any():
            picks[over] = np.flatnonzero(self.values[:size])[-1]
        return picks


class SumTreeSampler:
    """A complete binary tree of sums over a power-of-two number of leaves (O(log n) per draw);
    each update recomputes the touched parents from their children."""

    def __init__(self, capacity: int) -> None:
        self.leaves = 1 << max(capacity - 1, 1).bit_length()
        self.tree = np.zeros(2 * self.leaves)

    def set(self, indices: np.ndarray, values: np.ndarray) -> None:
        nodes = np.asarray(indices) + self.leaves
        self.tree[nodes] = values
        nodes = np.unique(nodes // 2)
        while nodes[0] >= 1:
            self.tree[nodes] = self.tree[2 * nodes] + self.tree[2 * nodes + 1]
            if nodes[0] == 1:
                break
            nodes = np.unique(nodes // 2)

    def get(self, indices: np.ndarray) -> np.ndarray:
        return self.tree[np.asarray(indices) + self.leaves]

    def total(self, size: int) -> float:
        return float(self.tree[1])  # slots past ``size`` hold zero

    def draw(self, fractions: np.ndarray, size: int) -> np.ndarray:
        target = fractions * self.tree[1]
        nodes = np.ones(len(fractions), dtype=np.int64)
        while nodes[0] < self.leaves:
            left = self.tree[2 * nodes]
            right_has_mass = self.tree[2 * nodes + 1] > 0
            go_right = (target >= left) & right_has_mass
            target = np.where(go_right, target - left, target)
            nodes = 2 * nodes + go_right
        return nodes - self.leaves


class PrioritizedReplay:
    """A ring buffer of ``(obs, action, reward, next_obs, terminated)`` with proportional
    priorities. ``prioritized=False`` makes it a uniform replay with unit weights."""

    def __init__(
        self,
        capacity: int,
        n_obs: int,
        *,
        alpha: float = 0.6,
        priority_epsilon: float = 1e-4,
        prioritized: bool = True,
        sampler: Literal["auto", "flat", "tree"] = "auto",
    ) -> None:
        if capacity < 1:
            raise ValueError(f"capacity={capacity!r}: expected an integer >= 1")
        self.capacity, self.alpha, self.priority_epsilon, self.prioritized = (
            capacity,
            alpha,
            priority_epsilon,
            prioritized,
        )
        self.obs = np.zeros((capacity, n_obs), dtype=np.float32)
        self.next_obs = np.zeros((capacity, n_obs), dtype=np.float32)
        self.actions = np.zeros(capacity, dtype=np.int64)
        self.rewards = np.zeros(capacity, dtype=np.float32)
        self.terminated = np.zeros(capacity, dtype=np.float32)
        self.priorities = np.zeros(capacity)  # |δ| + ε, before the exponent α
        self.position = 0  # the next slot to write
        self.size = 0
        self.max_priority = 1.0
        use_tree = sampler == "tree" or (sampler == "auto" and capacity > TREE_ABOVE)
        self._sampler: Sampler = SumTreeSampler(capacity) if use_tree else CumulativeSumSampler(capacity)

    def __len__(self) -> int:
        return self.size

    def add(
        self, obs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray, terminated: np.ndarray
    ) -> None:
        """Store k transitions (arrays with a leading axis k) at the largest priority so far."""
        k = len(actions)
        slots = (self.position + np.arange(k)) % self.capacity
        self.obs[slots] = obs
        self.actions[slots] = actions
        self.rewards[slots] = rewards
        self.next_obs[slots] = next_obs
        self.terminated[slots] = terminated
        self._set_priorities(slots, np.full(k, self.max_priority))
        self.position = int((self.position + k) % self.capacity)
        self.size = min(self.size + k, self.capacity)

    def _set_priorities(self, slots: np.ndarray, priorities: np.ndarray) -> None:
        self.priorities[slots] = priorities
        self._sampler.set(slots, priorities**self.alpha)

    def probabilities(self) -> np.ndarray:
        """P(i) for every filled slot (what :meth:`sample` draws from)."""
        if not self.prioritized:
            return np.full(self.size, 1.0 / self.size)
        scaled = self.priorities[: self.size] ** self.alpha
        return scaled / scaled.sum()

    def sample(self, batch_size: int, beta: float, rng: np.random.Generator) -> Batch:
        """Draw ``batch_size`` transitions (with replacement) and their importance weights."""
        if self.size == 0:
            raise ValueError("sample() from an empty replay: add transitions first")
        if not self.prioritized:
            indices = rng.integers(0, self.size, size=batch_size)
            weights = np.ones(batch_size, dtype=np.float32)
        else:
            indices = self._sampler.draw(rng.random(batch_size), self.size)
            probabilities = self._sampler.get(indices) / self._sampler.total(self.size)
            w = (self.size * probabilities) ** -beta
            weights = (w / w.max()).astype(np.float32)
        return Batch(
            indices=indices,
            obs=self.obs[indices],
            actions=self.actions[indices],
            rewards=self.rewards[indices],
            next_obs=self.next_obs[indices],
            terminated=self.terminated[indices],
            weights=weights,
        )

    def update_priorities(self, indices: np.ndarray, td_errors: np.ndarray) -> None:
        """Set the priorities of sampled transitions to ``|δ| + ε``."""
        if not self.prioritized:
            return
        priorities = np.abs(np.asarray(td_errors, dtype=np.float64)) + self.priority_epsilon
        self._set_priorities(np.asarray(indices), priorities)
        self.max_priority = max(self.max_priority, float(priorities.max()))

    def state_dict(self) -> dict[str, Any]:
        """Everything needed to resume: the filled slots, the write position, the max priority."""
        n = self.size
        return {
            "obs": self.obs[:n].copy(),
            "next_obs": self.next_obs[:n].copy(),
            "actions": self.actions[:n].copy(),
            "rewards": self.rewards[:n].copy(),
            "terminated": self.terminated[:n].copy(),
            "priorities": self.priorities[:n].copy(),
            "position": self.position,
            "size": n,
            "max_priority": self.max_priority,
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        n = int(state["size"])
        if n > self.capacity or np.asarray(state["obs"]).shape[1:] != self.obs.shape[1:]:
            raise ValueError("replay state does not fit this replay (capacity or observation size differ)")
        for name in ("obs", "next_obs", "actions", "rewards", "terminated"):
            getattr(self, name)[:n] = np.asarray(state[name])
        self.size, self.position, self.max_priority = n, int(state["position"]), float(state["max_priority"])
        self._set_priorities(np.arange(n), np.asarray(state["priorities"], dtype=np.float64))
