"""Prioritized replay against a naive reference (tests/reference/prioritized_replay.py)."""

import numpy as np
import pytest
from reference.prioritized_replay import CumulativeSumSampler, PrioritizedReplay, SumTreeSampler

from pursuit_bench.agents.config import PAPER
from pursuit_bench.agents.replay import ReplayStack, _tree_draw, _tree_set

SAMPLERS = ["flat", "tree"]


def filled(n: int, capacity: int = 100, sampler: str = "flat", **kwargs) -> PrioritizedReplay:
    replay = PrioritizedReplay(capacity, 3, sampler=sampler, **kwargs)
    obs = np.arange(n * 3, dtype=np.float32).reshape(n, 3)
    replay.add(obs, np.arange(n) % 2, np.arange(n, dtype=np.float32), obs + 1, np.zeros(n))
    return replay


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_sampling_frequencies_follow_priorities_to_the_alpha(sampler: str) -> None:
    replay = filled(20, sampler=sampler, alpha=0.6)
    td = np.linspace(0.0, 3.0, 20)
    replay.update_priorities(np.arange(20), td)
    expected = (np.abs(td) + 1e-4) ** 0.6
    expected /= expected.sum()
    np.testing.assert_allclose(replay.probabilities(), expected, rtol=1e-12)
    draws = 200_000
    counts = np.bincount(replay.sample(draws, 0.4, np.random.default_rng(0)).indices, minlength=20)
    sigma = np.sqrt(draws * expected * (1 - expected))
    # every slot within 4 standard deviations of its binomial expectation
    assert (np.abs(counts - draws * expected) < 4 * sigma + 1).all()


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_importance_weights_match_the_formula(sampler: str) -> None:
    replay = filled(10, sampler=sampler, alpha=0.6)
    td = np.array([0.5, 1.0, 2.0, 0.1, 0.0, 3.0, 0.2, 0.7, 1.5, 0.05])
    replay.update_priorities(np.arange(10), td)
    p = (np.abs(td) + 1e-4) ** 0.6
    prob = p / p.sum()
    for beta in (0.4, 0.7, 1.0):
        batch = replay.sample(64, beta, np.random.default_rng(1))
        naive = (10 * prob[batch.indices]) ** -beta
        np.testing.assert_allclose(batch.weights, naive / naive.max(), rtol=1e-6)
        assert batch.weights.max() == pytest.approx(1.0)
    assert (replay.sample(64, 0.0, np.random.default_rng(2)).weights == 1.0).all()  # β = 0: no correction


def test_new_transitions_enter_at_the_largest_priority_seen() -> None:
    replay = filled(4, alpha=1.0)
    replay.update_priorities(np.array([0, 1]), np.array([5.0, 0.5]))
    assert replay.max_priority == pytest.approx(5.0001)
    replay.add(np.zeros((1, 3)), np.zeros(1), np.zeros(1), np.zeros((1, 3)), np.zeros(1))
    assert replay.priorities[4] == pytest.approx(5.0001)
    assert replay.priorities[2] == 1.0  # untouched entries keep the initial maximum


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_wrap_around_when_full_and_never_past_the_filled_region(sampler: str) -> None:
    replay = PrioritizedReplay(8, 1, sampler=sampler)
    rng = np.random.default_rng(0)
    for start in range(0, 13, 3):  # 5 adds of 3: 15 transitions into 8 slots
        values = np.arange(start, start + 3, dtype=np.float32)[:, None]
        replay.add(values, np.zeros(3), values[:, 0], values, np.zeros(3))
        assert replay.sample(500, 0.4, rng).indices.max() < len(replay)
    assert len(replay) == 8 and replay.position == 15 % 8
    assert sorted(replay.obs[:, 0].tolist()) == list(range(7, 15))  # the oldest were overwritten
    assert replay.obs[replay.position - 1, 0] == 14


@pytest.mark.parametrize("sampler", SAMPLERS)
def test_zero_and_tiny_priorities(sampler: str) -> None:
    replay = filled(6, sampler=sampler, alpha=0.6, priority_epsilon=0.0)
    replay.update_priorities(np.arange(6), np.array([0.0, 1.0, 0.0, 1e-12, 0.0, 0.0]))
    indices = replay.sample(100_000, 0.4, np.random.default_rng(0)).indices
    assert set(np.unique(indices)) <= {1, 3}  # a zero priority is never drawn
    assert (indices == 1).mean() > 0.99
    # the last filled slot at zero: rounding at the top must not pick it
    replay.update_priorities(np.arange(6), np.array([1.0, 0, 0, 0, 0, 0]))
    assert (replay.sample(1000, 0.4, np.random.default_rng(1)).indices == 0).all()


def test_samplers_agree_with_each_other_and_recompute_exactly() -> None:
    rng = np.random.default_rng(3)
    flat, tree = CumulativeSumSampler(50), SumTreeSampler(50)
    for _ in range(2000):  # many small updates: the tree's sums must not drift
        idx = rng.integers(0, 50, size=4)
        values = rng.random(4) * 10.0 ** rng.integers(-6, 3)
        flat.set(idx, values)
        tree.set(idx, values)
    assert tree.total(50) == pytest.approx(flat.values.sum(), rel=1e-12)
    fractions = rng.random(5000)
    np.testing.assert_array_equal(flat.draw(fractions, 50), tree.draw(fractions, 50))


def test_the_compiled_descent_draws_what_the_tree_sampler_draws() -> None:
    """The stack's compiled descent (a level at a time for all draws) against
    :meth:`SumTreeSampler.draw`, member by member: zero leaves, masses across twelve orders of
    magnitude, a zero last slot, and fractions at 0 and just below 1."""
    rng = np.random.default_rng(7)
    capacity, members = 37, 3
    samplers = [SumTreeSampler(capacity) for _ in range(members)]
    for sampler in samplers:
        values = rng.random(capacity) * 10.0 ** rng.integers(-9, 4, size=capacity)
        values[rng.random(capacity) < 0.3] = 0.0
        values[-1] = 0.0
        sampler.set(np.arange(capacity), values)
    # rounding can leave a descent with more than a node's children hold: here by hand, a root
    # above its children's sum; the draws that pass a node's left sum must still not step into a
    # right subtree without mass
    samplers[-1].tree[1] *= 1.5
    tree = np.stack([s.tree for s in samplers])
    fractions = rng.random((members, 500))
    fractions[:, :2] = [0.0, np.nextafter(1.0, 0.0)]
    picks = _tree_draw(tree, samplers[0].leaves, fractions)
    for m, sampler in enumerate(samplers):
        np.testing.assert_array_equal(picks[m], sampler.draw(fractions[m], capacity))
        assert (sampler.get(picks[m]) > 0).all()


def test_uniform_replay_ignores_priorities() -> None:
    replay = filled(10, prioritized=False)
    replay.update_priorities(np.arange(10), np.arange(10.0))
    batch = replay.sample(50_000, 0.4, np.random.default_rng(0))
    assert (batch.weights == 1).all()
    assert np.bincount(batch.indices, minlength=10).min() > 4500


def test_beta_is_annealed_and_epsilon_decays() -> None:
    assert PAPER.beta(0) == 0.4
    assert PAPER.beta(PAPER.beta_anneal_steps // 2) == pytest.approx(0.7)
    assert PAPER.beta(10 * PAPER.beta_anneal_steps) == 1.0
    assert PAPER.epsilon(0) == 1.0 and PAPER.epsilon(5_000) == pytest.approx(0.55)
    assert PAPER.epsilon(10_000) == pytest.approx(0.1) and PAPER.epsilon(10**7) == pytest.approx(0.1)


def test_state_round_trip() -> None:
    replay = filled(30, capacity=20)
    replay.update_priorities(np.arange(5), np.arange(5.0))
    other = PrioritizedReplay(20, 3)
    other.load_state_dict(replay.state_dict())
    np.testing.assert_array_equal(other.probabilities(), replay.probabilities())
    assert (other.position, len(other), other.max_priority) == (replay.position, len(replay), replay.max_priority)
    with pytest.raises(ValueError, match="does not fit"):
        PrioritizedReplay(20, 4).load_state_dict(replay.state_dict())


@pytest.mark.parametrize("prioritized", [True, False])
def test_a_replay_stack_samples_each_member_as_its_own_replay(prioritized: bool) -> None:
    """One sampling call and one priority update over the member axis, equal to per-member
    replays drawing from the same generators, through wrap-around and repeated draws."""
    members, capacity, n_obs = 4, 50, 3
    stack = ReplayStack(members, capacity, n_obs, alpha=0.6, prioritized=prioritized)
    singles = [PrioritizedReplay(capacity, n_obs, alpha=0.6, prioritized=prioritized, sampler="tree") for _ in range(4)]
    data = np.random.default_rng(0)
    rngs_a = [np.random.default_rng(10 + m) for m in range(members)]
    rngs_b = [np.random.default_rng(10 + m) for m in range(members)]
    for step in range(12):
        k = 7
        obs = data.normal(size=(members, k, n_obs)).astype(np.float32)
        actions = data.integers(0, 5, size=(members, k))
        rewards = data.normal(size=(members, k)).astype(np.float32)
        terminated = (data.random((members, k)) < 0.1).astype(np.float32)
        stack.add(obs, actions, rewards, obs + 1, terminated)
        for m, single in enumerate(singles):
            single.add(obs[m], actions[m], rewards[m], obs[m] + 1, terminated[m])
        batch = stack.sample(16, 0.4 + 0.05 * step, rngs_a)
        td = data.normal(size=(members, 16)) * 3
        stack.update_priorities(batch.indices, td)
        for m, single in enumerate(singles):
            mine = single.sample(16, 0.4 + 0.05 * step, rngs_b[m])
            for name in ("indices", "obs", "actions", "rewards", "next_obs", "terminated", "weights"):
                np.testing.assert_array_equal(getattr(batch, name)[m], getattr(mine, name))
            single.update_priorities(mine.indices, td[m])
    for m, single in enumerate(singles):
        theirs, ours = single.state_dict(), stack.member_state(m)
        assert theirs.keys() == ours.keys()
        for key in theirs:
            np.testing.assert_array_equal(ours[key], theirs[key])
    kept = stack.take([3, 1])
    np.testing.assert_array_equal(kept.member_state(0)["priorities"], stack.member_state(3)["priorities"])
    np.testing.assert_array_equal(kept.obs[1], stack.obs[1])


@pytest.mark.parametrize("k", [1, 7, 30, 49, 50, 64, 130])
def test_storing_updates_each_tree_as_leaf_by_leaf_updates_do(k: int) -> None:
    """``ReplayStack.add`` recomputes the touched parents a level at a time; the sums are those
    of setting the same leaves one after another (``_tree_set``), through wrap-around and adds
    of more transitions than the capacity."""
    members, capacity = 2, 50
    stack = ReplayStack(members, capacity, 3, alpha=0.6)
    naive = stack.tree.copy()
    data = np.random.default_rng(k)
    for _ in range(4):
        stack.max_priority[:] = data.uniform(0.5, 3.0, members)  # as a priority update leaves it
        start = stack.position
        obs = data.normal(size=(members, k, 3)).astype(np.float32)
        stack.add(
            obs, data.integers(0, 2, (members, k)), np.zeros((members, k), np.float32), obs, np.zeros((members, k))
        )
        slots = (start + np.arange(k)) % capacity
        scaled = np.array([[p**0.6] * k for p in stack.max_priority.tolist()])  # the kernel's scalar power
        _tree_set(naive, stack.leaves, np.repeat(slots[None], members, axis=0), scaled)
        np.testing.assert_array_equal(stack.tree, naive)
