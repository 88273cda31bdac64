"""Proportional prioritized experience replay (Schaul et al. 2015), vectorized and exact.

Priorities are ``|δ| + ε`` (docs/spec.md); a transition is drawn with probability ``p_i^α / Σ p^α``;
new transitions enter at the largest priority seen so far; importance weights are
``(N · P(i))^-β`` divided by the batch maximum. Sampling only ever sees the filled slots.

:class:`ReplayStack` holds the replays of every member of a stacked learner in one array with a
member axis: one sum tree per member, stacked (O(log n) a draw, where the cumulative sum is O(n)
an update). Storing, sampling (the draws, the importance weights and the gathered transitions)
and the priority updates are one compiled call each for all members; the learners use it, and
it is tested to draw exactly as one plain numpy replay with a sum tree per member
(``tests/reference/prioritized_replay.py``). The sums are recomputed from the stored priorities
(each parent from its children), so nothing drifts with time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from pursuit_bench.agents.generators import compiled_generators


@dataclass
class Batch:
    """A sample of transitions and their importance weights."""

    indices: np.ndarray
    obs: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    next_obs: np.ndarray
    terminated: np.ndarray
    weights: np.ndarray


@numba.njit(cache=True)
def _tree_set(tree, leaves, slots, values):
    """Set leaves ``slots[m]`` of member m's tree to ``values[m]`` (in order: a slot given twice
    keeps its last value), then recompute every touched parent from its children, as
    :meth:`SumTreeSampler.set` does."""
    for m in range(slots.shape[0]):
        for j in range(slots.shape[1]):
            tree[m, leaves + slots[m, j]] = values[m, j]
        for j in range(slots.shape[1]):
            node = (leaves + slots[m, j]) // 2
            while node >= 1:
                tree[m, node] = tree[m, 2 * node] + tree[m, 2 * node + 1]
                node //= 2


@numba.njit(cache=True)
def _tree_draw(tree, leaves, fractions):
    """Slots (M, B) drawn in proportion to the leaves, ``fractions`` uniform in [0, 1): the descent
    of :meth:`SumTreeSampler.draw` (``leaves`` a power of two, as both trees are built), member
    by member, a level at a time for all B draws: each
    draw takes the steps it would take alone, but the B reads of a level are independent, so
    they overlap, and the step left or right is a select, not a branch the processor mispredicts
    half the time."""
    members, size = fractions.shape
    picks = np.empty((members, size), dtype=np.int64)
    target = np.empty(size)
    node = np.empty(size, dtype=np.int64)
    for m in range(members):
        for i in range(size):
            target[i] = fractions[m, i] * tree[m, 1]
            node[i] = 1
        level = 1
        while level < leaves:
            for i in range(size):
                k = node[i]
                left = tree[m, 2 * k]
                go_right = (target[i] >= left) & (tree[m, 2 * k + 1] > 0)  # no branch: a select
                target[i] = target[i] - left if go_right else target[i]
                node[i] = 2 * k + 1 if go_right else 2 * k
            level *= 2
        for i in range(size):
            picks[m, i] = node[i] - leaves
    return picks


@numba.njit(cache=True)
def _tree_set_one(tree, leaves, m, slot, value):
    """Leaf ``slot`` of member m's tree to ``value``, and its ancestors recomputed from their children."""
    node = leaves + slot
    tree[m, node] = value
    node //= 2
    while node >= 1:
        tree[m, node] = tree[m, 2 * node] + tree[m, 2 * node + 1]
        node //= 2


@numba.njit(cache=True)
def _store(
    obs,
    actions,
    rewards,
    next_obs,
    terminated,
    priorities,
    tree,
    leaves,
    alpha,
    max_priority,
    position,
    new_obs,
    new_actions,
    new_rewards,
    new_next,
    new_terminated,
):
    """Write k transitions per member (``new_…``, each (M, k, …)) into the slots from ``position``
    on (wrapping), each at its member's largest priority so far, and update the trees (each
    touched parent recomputed from its children once they are final, as :func:`_tree_set` does)."""
    members, k = new_actions.shape
    if k == 0:
        return
    capacity = actions.shape[1]
    last = position + k - 1  # the slots position … last, modulo the capacity
    for m in range(members):
        scaled = max_priority[m] ** alpha
        for j in range(k):
            slot = (position + j) % capacity
            obs[m, slot] = new_obs[m, j]
            next_obs[m, slot] = new_next[m, j]
            actions[m, slot] = new_actions[m, j]
            rewards[m, slot] = new_rewards[m, j]
            terminated[m, slot] = new_terminated[m, j]
            priorities[m, slot] = max_priority[m]
            tree[m, leaves + slot] = scaled
        if k >= capacity:
            _tree_refresh(tree, leaves, m, 0, capacity - 1)
        elif last < capacity:
            _tree_refresh(tree, leaves, m, position, last)
        else:  # wrapped: two runs of slots
            _tree_refresh(tree, leaves, m, position, capacity - 1)
            _tree_refresh(tree, leaves, m, 0, last - capacity)


@numba.njit(cache=True)
def _tree_refresh(tree, leaves, m, first, last):
    """Member m's ancestors of the leaves of slots ``first … last`` recomputed from their
    children, a level at a time (each once, after its children: the sums a leaf-by-leaf update
    of those leaves ends with)."""
    low, high = (leaves + first) // 2, (leaves + last) // 2
    while low >= 1:
        for node in range(low, high + 1):
            tree[m, node] = tree[m, 2 * node] + tree[m, 2 * node + 1]
        low //= 2
        high //= 2


@numba.njit(cache=True)
def sample_kernel(tree, leaves, size, beta, fractions, uniform, obs, actions, rewards, next_obs, terminated):
    """Indices (M, B), importance weights (M, B) and the transitions at those indices.

    Prioritized (``fractions`` (M, B) uniform in [0, 1)): the descent of :func:`_tree_draw`, and
    weights ``(size · P(i))^-β`` over the member's largest. Uniform (``fractions`` empty): the
    indices ``uniform`` (M, B) and unit weights."""
    prioritized = fractions.shape[1] > 0
    indices = _tree_draw(tree, leaves, fractions) if prioritized else uniform.copy()
    members, batch = indices.shape
    weights = np.ones((members, batch), dtype=np.float32)
    out_obs = np.empty((members, batch, obs.shape[2]), dtype=obs.dtype)
    out_next = np.empty((members, batch, obs.shape[2]), dtype=obs.dtype)
    out_actions = np.empty((members, batch), dtype=actions.dtype)
    out_rewards = np.empty((members, batch), dtype=rewards.dtype)
    out_terminated = np.empty((members, batch), dtype=terminated.dtype)
    w = np.empty(batch)
    for m in range(members):
        if prioritized:
            largest = 0.0
            for i in range(batch):
                w[i] = (size * (tree[m, indices[m, i] + leaves] / tree[m, 1])) ** -beta
                largest = max(largest, w[i])
            for i in range(batch):
                weights[m, i] = w[i] / largest
        for i in range(batch):
            slot = indices[m, i]
            out_obs[m, i] = obs[m, slot]
            out_next[m, i] = next_obs[m, slot]
            out_actions[m, i] = actions[m, slot]
            out_rewards[m, i] = rewards[m, slot]
            out_terminated[m, i] = terminated[m, slot]
    return indices, weights, out_obs, out_actions, out_rewards, out_next, out_terminated


@numba.njit(cache=True)
def draws_kernel(generators, batch_size, size, prioritized):
    """The uniforms of one sample, member m's drawn from ``generators[m]`` (a typed list,
    :mod:`~pursuit_bench.agents.generators`): ``(fractions, uniform)``, the fractions (M, B) of
    the tree descents when prioritized, else the slots (M, B) drawn uniformly from ``0 … size -
    1`` (the other of the two empty), as :func:`sample_kernel` takes them."""
    members = len(generators)
    fractions = np.empty((members, batch_size if prioritized else 0))
    uniform = np.empty((members, 0 if prioritized else batch_size), dtype=np.int64)
    for m in range(members):
        if prioritized:
            fractions[m] = generators[m].random(batch_size)
        else:
            uniform[m] = generators[m].integers(0, size, batch_size)
    return fractions, uniform


@numba.njit(cache=True)
def update_priorities_kernel(priorities, tree, leaves, alpha, epsilon, max_priority, indices, td_errors):
    """Member m's slots ``indices[m]`` to priorities ``|δ| + ε`` (in order: a slot drawn twice
    keeps its last), the trees updated and each member's largest priority raised."""
    members, batch = indices.shape
    for m in range(members):
        largest = max_priority[m]
        for i in range(batch):
            priority = abs(np.float64(td_errors[m, i])) + epsilon
            priorities[m, indices[m, i]] = priority
            _tree_set_one(tree, leaves, m, indices[m, i], priority**alpha)
            largest = max(largest, priority)
        max_priority[m] = largest


class ReplayStack:
    """M prioritized replays, one per member of a stacked learner, their arrays stacked on a
    member axis so that sampling and priority updates are one call for all members.

    Member m behaves exactly as the tests' plain replay (``tests/reference/prioritized_replay.py``) with
    the tree sampler fed the same
    transitions and drawing from the same generator (``tests/test_replay.py`` checks it): the
    same sums, the same draws, the same weights. Members add transitions in lockstep (the same
    number each time), so the write position and size are shared. Each member's uniform draws
    come from its own generator (what keeps a member's draws its own), drawn in the compiled
    kernels (:func:`draws_kernel`).
    """

    def __init__(
        self,
        members: int,
        capacity: int,
        n_obs: int,
        *,
        alpha: float = 0.6,
        priority_epsilon: float = 1e-4,
        prioritized: bool = True,
    ) -> None:
        if capacity < 1:
            raise ValueError(f"capacity={capacity!r}: expected an integer >= 1")
        self.members, self.capacity, self.n_obs = members, capacity, n_obs
        self.alpha, self.priority_epsilon, self.prioritized = alpha, priority_epsilon, prioritized
        self.obs = np.zeros((members, capacity, n_obs), dtype=np.float32)
        self.next_obs = np.zeros((members, capacity, n_obs), dtype=np.float32)
        self.actions = np.zeros((members, capacity), dtype=np.int64)
        self.rewards = np.zeros((members, capacity), dtype=np.float32)
        self.terminated = np.zeros((members, capacity), dtype=np.float32)
        self.priorities = np.zeros((members, capacity))  # |δ| + ε, before the exponent α
        self.leaves = 1 << max(capacity - 1, 1).bit_length()
        self.tree = np.zeros((members, 2 * self.leaves))  # sums of priorities ** α over each node's leaves
        self.max_priority = np.ones(members)
        self.position = 0
        self.size = 0

    def __len__(self) -> int:
        return self.size

    def add(
        self, obs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray, terminated: np.ndarray
    ) -> None:
        """Store k transitions per member (arrays (M, k, …)) at each member's largest priority."""
        k = actions.shape[1]
        _store(
            self.obs,
            self.actions,
            self.rewards,
            self.next_obs,
            self.terminated,
            self.priorities,
            self.tree,
            self.leaves,
            self.alpha,
            self.max_priority,
            self.position,
            np.asarray(obs),
            np.asarray(actions),
            np.asarray(rewards),
            np.asarray(next_obs),
            np.asarray(terminated),
        )
        self.position = int((self.position + k) % self.capacity)
        self.size = min(self.size + k, self.capacity)

    def sample(self, batch_size: int, beta: float, rngs: Any) -> Batch:
        """``batch_size`` transitions per member (with replacement), member m drawing from
        ``rngs[m]`` (see :meth:`draws`); every array of the batch has the member axis first, (M, B, …)."""
        fractions, uniform = self.draws(batch_size, rngs)
        arrays = self.obs, self.actions, self.rewards, self.next_obs, self.terminated
        indices, weights, obs, actions, rewards, next_obs, terminated = sample_kernel(
            self.tree, self.leaves, self.size, beta, fractions, uniform, *arrays
        )
        return Batch(indices, obs, actions, rewards, next_obs, terminated, weights)

    def draws(self, batch_size: int, rngs: Any) -> tuple[np.ndarray, np.ndarray]:
        """The uniforms of one sample, member m's from ``rngs[m]`` (a list of generators, or
        their :mod:`~pursuit_bench.agents.generators` typed list): ``(fractions, uniform)``, as
        :func:`draws_kernel` gives them."""
        self.check_drawable(len(rngs))
        return draws_kernel(compiled_generators(rngs), batch_size, self.size, self.prioritized)

    def check_drawable(self, generators: int) -> None:
        """What a sample needs: transitions, and a generator per member (ValueError otherwise)."""
        if self.size == 0:
            raise ValueError("sample() from an empty replay: add transitions first")
        if generators != self.members:
            raise ValueError(f"{generators} generators for {self.members} members: expected one per member")

    def arrays(self) -> tuple[Any, ...]:
        """What the compiled update (:func:`pursuit_bench.agents.fused.replay_update_kernel`) reads
        and writes of this replay: the trees and their sizes, α and ε, whether prioritized, the
        five transition arrays, the priorities and each member's largest."""
        return (
            self.tree,
            self.leaves,
            self.size,
            self.alpha,
            self.priority_epsilon,
            self.prioritized,
            self.obs,
            self.actions,
            self.rewards,
            self.next_obs,
            self.terminated,
            self.priorities,
            self.max_priority,
        )

    def update_priorities(self, indices: np.ndarray, td_errors: np.ndarray) -> None:
        """Set the priorities of sampled transitions (M, B) to ``|δ| + ε`` (a slot drawn twice
        keeps its last value)."""
        if not self.prioritized:
            return
        update_priorities_kernel(
            self.priorities,
            self.tree,
            self.leaves,
            self.alpha,
            self.priority_epsilon,
            self.max_priority,
            np.asarray(indices, dtype=np.int64),
            np.asarray(td_errors),
        )

    def member_state(self, m: int) -> dict[str, Any]:
        """Member m's replay as one plain replay's ``state_dict`` (the tests' reference) writes it."""
        n = self.size
        return {
            "obs": self.obs[m, :n].copy(),
            "next_obs": self.next_obs[m, :n].copy(),
            "actions": self.actions[m, :n].copy(),
            "rewards": self.rewards[m, :n].copy(),
            "terminated": self.terminated[m, :n].copy(),
            "priorities": self.priorities[m, :n].copy(),
            "position": self.position,
            "size": n,
            "max_priority": float(self.max_priority[m]),
        }

    def load_member_state(self, m: int, state: dict[str, Any]) -> None:
        """Restore member m from :meth:`member_state` (or a plain replay's ``state_dict``)."""
        n = int(state["size"])
        if n > self.capacity or np.asarray(state["obs"]).shape[1:] != self.obs.shape[2:]:
            raise ValueError("replay state does not fit this replay (capacity or observation size differ)")
        for name in ("obs", "next_obs", "actions", "rewards", "terminated"):
            getattr(self, name)[m, :n] = np.asarray(state[name])
        self.size, self.position = n, int(state["position"])
        self.max_priority[m] = float(state["max_priority"])
        self.priorities[m, :n] = np.asarray(state["priorities"], dtype=np.float64)
        single = np.zeros((1, self.tree.shape[1]))  # member m's tree rebuilt from its priorities
        _tree_set(single, self.leaves, np.arange(n)[None], self.priorities[m : m + 1, :n] ** self.alpha)
        self.tree[m] = single[0]

    def take(self, members: list[int]) -> ReplayStack:
        """A new stack holding (copies of) these members' replays, in this order."""
        new = ReplayStack(
            len(members),
            self.capacity,
            self.n_obs,
            alpha=self.alpha,
            priority_epsilon=self.priority_epsilon,
            prioritized=self.prioritized,
        )
        for name in ("obs", "next_obs", "actions", "rewards", "terminated", "priorities", "tree", "max_priority"):
            setattr(new, name, getattr(self, name)[members].copy())
        new.position, new.size = self.position, self.size
        return new
