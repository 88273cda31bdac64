"""Draws in compiled kernels against numpy's own calls on the same generators."""

import copy
import pickle

import numpy as np
import pytest

from pursuit_bench.agents.fused import exploration_kernel
from pursuit_bench.agents.generators import CompiledGenerators, compiled_generators
from pursuit_bench.agents.replay import ReplayStack, draws_kernel


def numpy_exploration(rngs: list[np.random.Generator], rows: int, n_actions: int) -> tuple[np.ndarray, np.ndarray]:
    """The naive form: each member's uniforms, then its random actions, by numpy."""
    uniforms = np.array([rng.random(rows) for rng in rngs]).reshape(len(rngs), rows)
    randoms = np.array([rng.integers(0, n_actions, size=rows) for rng in rngs]).reshape(len(rngs), rows)
    return uniforms, randoms


def numpy_draws(rngs: list[np.random.Generator], batch: int, size: int, prioritized: bool) -> np.ndarray:
    if prioritized:
        return np.array([rng.random(batch) for rng in rngs])
    return np.array([rng.integers(0, size, size=batch) for rng in rngs])


# 3 · 2^30 and 2^31 + 1: ranges where numpy's bounded draws reject often, and take more words
@pytest.mark.parametrize("n_actions", [2, 12, 24, 3 * 2**30, 2**31 + 1])
@pytest.mark.parametrize("rows", [1, 31, 32])
def test_compiled_draws_are_numpys_and_move_the_generators_on_alike(n_actions: int, rows: int) -> None:
    ours = [np.random.default_rng(seed) for seed in (5, 6, 7)]
    theirs = [np.random.default_rng(seed) for seed in (5, 6, 7)]
    generators = compiled_generators(ours)
    for _ in range(4):  # an odd count of 32-bit halves left over from one call must carry on
        uniforms, randoms = exploration_kernel(generators, rows, n_actions)
        expected_uniforms, expected_randoms = numpy_exploration(theirs, rows, n_actions)
        np.testing.assert_array_equal(uniforms, expected_uniforms)
        np.testing.assert_array_equal(randoms, expected_randoms)
    for mine, other in zip(ours, theirs, strict=True):  # the Python objects moved on with them
        np.testing.assert_array_equal(mine.random(5), other.random(5))
        assert mine.bit_generator.state == other.bit_generator.state


@pytest.mark.parametrize("prioritized", [True, False])
def test_replay_draws_are_numpys(prioritized: bool) -> None:
    ours = [np.random.default_rng(seed) for seed in (1, 2)]
    theirs = [np.random.default_rng(seed) for seed in (1, 2)]
    for size in (1, 17, 10_000):
        fractions, uniform = draws_kernel(compiled_generators(ours), 64, size, prioritized)
        drawn, empty = (fractions, uniform) if prioritized else (uniform, fractions)
        assert empty.shape == (2, 0)
        np.testing.assert_array_equal(drawn, numpy_draws(theirs, 64, size, prioritized))


def test_a_replay_refuses_to_draw_when_empty_or_with_a_generator_per_member_missing() -> None:
    stack = ReplayStack(2, 10, 3, alpha=0.6)
    rngs = [np.random.default_rng(0), np.random.default_rng(1)]
    with pytest.raises(ValueError, match="empty replay"):
        stack.draws(8, rngs)
    obs = np.zeros((2, 4, 3), dtype=np.float32)
    stack.add(obs, np.zeros((2, 4), dtype=np.int64), np.zeros((2, 4)), obs, np.zeros((2, 4)))
    with pytest.raises(ValueError, match="1 generators for 2 members"):
        stack.draws(8, rngs[:1])
    assert stack.draws(8, rngs)[0].shape == (2, 8)


def test_the_compiled_list_is_rebuilt_when_the_generators_change_and_never_pickled() -> None:
    rngs = [np.random.default_rng(0), np.random.default_rng(1)]
    cache = CompiledGenerators()
    first = cache.of(rngs)
    assert cache.of(list(rngs)) is first  # the same generators: the same list
    swapped = [rngs[1], rngs[0]]
    second = cache.of(swapped)
    assert second is not first and second[0] is rngs[1]
    assert cache.of(rngs[:1]) is not second
    with pytest.raises(ValueError, match="no generators"):
        compiled_generators([])
    for clone in (copy.deepcopy(cache), pickle.loads(pickle.dumps(cache))):
        assert len(clone.of(rngs)) == 2  # built afresh on use
