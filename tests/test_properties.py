"""Property-based: whatever the condition, seed and actions, the state stays finite and inside
the arena, and episodes end by the step limit."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import pursuit_bench
from pursuit_bench import CONDITIONS
from pursuit_bench.env.world import HALF_SIZE, RADIUS


@settings(max_examples=60, deadline=None)
@given(
    condition=st.sampled_from(list(CONDITIONS)),
    wall_rule=st.sampled_from(["terminate", "contain"]),
    backend=st.sampled_from(["pymunk", "numpy"]),
    seed=st.integers(0, 2**32 - 1),
    actions=st.lists(st.tuples(st.integers(0, 1), st.integers(0, 11)), min_size=1, max_size=40),
)
def test_episodes_stay_finite_inside_and_bounded(condition, wall_rule, backend, seed, actions) -> None:
    env = pursuit_bench.parallel_env(condition, wall_rule=wall_rule, backend=backend, max_steps=120)
    env.reset(seed=seed)
    for t in range(121):
        mode, k = actions[t % len(actions)]
        step_actions = {a: (k if a == "prey_0" else [mode, (k + 3 * i) % 12]) for i, a in enumerate(env.agents)}
        obs, rewards, term, trunc, _ = env.step(step_actions)
        state = env.state().reshape(-1, 4)
        assert np.isfinite(state).all() and all(np.isfinite(o).all() for o in obs.values())
        assert all(np.isfinite(r) for r in rewards.values())
        assert (np.abs(state[:, :2]) <= HALF_SIZE - RADIUS + 1e-6).all()
        assert all(env.observation_space(a).contains(o) for a, o in obs.items())
        if not env.agents:
            assert t < 120 or all(trunc.values()) or all(term.values())
            break
    else:
        raise AssertionError("the episode outlived max_steps")
