"""Continuous actions: the discrete task is the continuous one at 24 (12) points; the envs,
the checkers and the batched views take continuous actions."""

import gymnasium
import numpy as np
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import pursuit_bench
from pursuit_bench.env import task
from pursuit_bench.env.pettingzoo_env import as_continuous


def test_discrete_actions_and_their_continuous_equivalents_give_identical_episodes() -> None:
    discrete = pursuit_bench.parallel_env("2p-high-individual")
    continuous = pursuit_bench.parallel_env("2p-high-individual", continuous=True)
    for seed in range(3):
        obs_d, _ = discrete.reset(seed=seed)
        obs_c, _ = continuous.reset(seed=seed)
        for space in (discrete.action_space(a) for a in discrete.possible_agents):
            space.seed(seed)
        while discrete.agents:
            actions = {a: discrete.action_space(a).sample() for a in discrete.agents}
            vectors = {a: as_continuous(a, act, a != "prey_0") for a, act in actions.items()}
            obs_d, rew_d, term_d, trunc_d, info_d = discrete.step(actions)
            obs_c, rew_c, term_c, trunc_c, info_c = continuous.step(vectors)
            for a in obs_d:
                np.testing.assert_array_equal(obs_d[a], obs_c[a])
            assert rew_d == rew_c and term_d == term_c and trunc_d == trunc_c
            assert [info_d[p]["mode"] for p in ("predator_0", "predator_1")] == [
                info_c[p]["mode"] for p in ("predator_0", "predator_1")
            ]
        assert not continuous.agents


def test_a_long_vector_is_scaled_down_and_the_stalk_level_sets_the_mode() -> None:
    los = np.zeros((1, 2, 2))
    los[..., 0] = 1.0  # both lines of sight along +x
    actions = np.array([[[0.3, 0.0], [3.0, 4.0]]])  # a stalking predator; the prey beyond norm 1
    acc, modes = task.continuous_accelerations(los, actions, 1)
    np.testing.assert_allclose(acc[0, 0], [0.3 * task.ACCEL_CHASE, 0.0])
    np.testing.assert_allclose(acc[0, 1], [0.6 * task.ACCEL_PREY, 0.8 * task.ACCEL_PREY])
    assert modes.tolist() == [[0]]
    _, modes = task.continuous_accelerations(los, np.array([[[0.0, 0.51], [0.0, 0.0]]]), 1)
    assert modes.tolist() == [[1]]


def test_the_checkers_pass_with_continuous_actions() -> None:
    parallel_api_test(pursuit_bench.parallel_env("3p-low-shared", continuous=True), num_cycles=200)
    for agent in ("predator_0", "prey_0"):
        env = gymnasium.make("pursuit_bench/Pursuit-v0", agent=agent, condition="2p-high-shared", continuous=True)
        check_env(env.unwrapped, skip_render_check=True)
        env.reset(seed=0)
        assert env.action_space.shape == (2,)
        env.step(env.action_space.sample())


def test_the_batched_views_take_continuous_actions() -> None:
    vec = pursuit_bench.VectorPursuitEnv(4, "1p-high", continuous=True)
    vec.reset(seed=0)
    obs, rewards, _, _, _ = vec.step(np.zeros((4, 2, 2)))
    assert obs.shape == (4, 2, 10) and rewards.shape == (4, 2)
    envs = gymnasium.make_vec(
        "pursuit_bench/Pursuit-v0", num_envs=4, agent="predator_0", condition="1p-high", continuous=True
    )
    envs.reset(seed=0)
    assert envs.single_action_space.shape == (2,)
    for _ in range(20):
        envs.step(envs.action_space.sample())


def test_a_continuous_episode_is_recorded(tmp_path) -> None:
    from pursuit_bench.trajectories.recording import RecordEpisodes

    env = RecordEpisodes(pursuit_bench.parallel_env("1p-high", continuous=True), tmp_path / "c.rrd")
    env.reset(seed=0)
    while env.agents:
        env.step({a: np.array([0.9, 0.1]) for a in env.agents})  # chasing: norm above the stalk level
    env.close()
    assert env.recorder.clock > 0 and (tmp_path / "c.rrd").stat().st_size > 1000
