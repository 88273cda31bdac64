"""The numpy backend against the pymunk reference, and the batched env's own contract."""

import numpy as np
import pytest

from pursuit_bench import parallel_env
from pursuit_bench.env.vector import VectorPursuitEnv, _actions_in_range


def lockstep(wall_rule: str, steps: int, num_envs: int = 64, condition: str = "3p-low-individual"):
    """Step both backends with the same seed and actions; yield both step results and states."""
    envs = {b: VectorPursuitEnv(num_envs, condition, backend=b, wall_rule=wall_rule) for b in ("pymunk", "numpy")}
    for env in envs.values():
        env.reset(seed=11)
    rng = np.random.default_rng(0)
    for _ in range(steps):
        n = envs["pymunk"].n_agents
        actions = np.stack([rng.integers(0, 2, (num_envs, n)), rng.integers(0, 12, (num_envs, n))], axis=-1)
        yield {b: (*env.step(actions), env.core.world.positions.copy()) for b, env in envs.items()}


def test_terminate_outcomes_identical_and_trajectories_equal() -> None:
    episodes = captures = walls = 0
    worst = 0.0
    for out in lockstep("terminate", 600):
        (_, rew_p, term_p, trunc_p, info_p, pos_p), (_, rew_n, term_n, trunc_n, info_n, pos_n) = (
            out["pymunk"],
            out["numpy"],
        )
        np.testing.assert_array_equal(term_p, term_n)
        np.testing.assert_array_equal(trunc_p, trunc_n)
        np.testing.assert_array_equal(info_p["captured"], info_n["captured"])
        np.testing.assert_array_equal(info_p["left_area"], info_n["left_area"])
        np.testing.assert_array_equal(info_p["episode_length"], info_n["episode_length"])
        np.testing.assert_array_equal(rew_p, rew_n)
        worst = max(worst, float(np.abs(pos_p - pos_n).max()))
        np.testing.assert_allclose(info_p["final_obs"], info_n["final_obs"], atol=1e-6)  # float32
        done = info_p["done"]
        episodes += done.sum()
        captures += info_p["captured"][done].sum()
        walls += info_p["left_area"][done].any(axis=1).sum()
    assert worst < 1e-9, worst
    assert episodes > 1000 and captures > 100 and walls > 100  # both kinds of ending were exercised


def test_contain_outcomes_identical_and_trajectories_close() -> None:
    """Under ``contain`` pymunk resolves wall contacts with its own solver while the numpy
    backend clamps; they still agree on every episode end and reward, and on positions to 1e-9
    (measured worst case ~1e-11, see docs/departures.md)."""
    worst, episodes = 0.0, 0
    for out in lockstep("contain", 1000, num_envs=128, condition="3p-high-shared"):
        (_, rew_p, term_p, trunc_p, info_p, pos_p), (_, rew_n, term_n, trunc_n, _, pos_n) = (
            out["pymunk"],
            out["numpy"],
        )
        np.testing.assert_array_equal(term_p, term_n)
        np.testing.assert_array_equal(trunc_p, trunc_n)
        np.testing.assert_allclose(rew_p, rew_n, atol=1e-12)
        worst = max(worst, float(np.abs(pos_p - pos_n).max()))
        episodes += info_p["done"].sum()
    assert worst < 1e-9, worst
    assert episodes > 500


def test_batched_env_matches_single_envs_and_autoresets() -> None:
    """Arena i of the batched env is the single env seeded with the i-th spawned seed (to float
    rounding: in the batched pymunk space each arena sits at its own offset)."""
    vec = VectorPursuitEnv(3, "2p-low-shared", max_steps=12)
    obs, _ = vec.reset(seed=4)
    seeds = np.random.SeedSequence(4).spawn(3)
    singles = [parallel_env("2p-low-shared", max_steps=12) for _ in range(3)]
    for env, seed in zip(singles, seeds, strict=True):
        env.np_random = np.random.default_rng(seed)
    single_obs = [env.reset()[0] for env in singles]
    for i in range(3):
        np.testing.assert_array_equal(obs[i], np.stack(list(single_obs[i].values())))
    rng = np.random.default_rng(1)
    finished = 0
    for _ in range(30):
        actions = np.stack([rng.integers(0, 2, (3, 3)), rng.integers(0, 12, (3, 3))], axis=-1)
        obs, rewards, term, trunc, info = vec.step(actions)
        assert term.shape == trunc.shape == rewards.shape == (3, 3) and obs.shape == (3, 3, 16)
        for i, env in enumerate(singles):
            step_actions = {a: (actions[i, j] if j < 2 else int(actions[i, j, 1])) for j, a in enumerate(env.agents)}
            s_obs, s_rew, s_term, s_trunc, _ = env.step(step_actions)
            np.testing.assert_allclose(info["final_obs"][i], np.stack(list(s_obs.values())), atol=1e-6)
            np.testing.assert_array_equal(rewards[i], list(s_rew.values()))
            assert term[i, 0] == s_term["prey_0"] and trunc[i, 0] == s_trunc["prey_0"]
            if info["done"][i]:
                finished += 1
                assert info["episode_length"][i] <= 12
                np.testing.assert_allclose(obs[i], np.stack(list(env.reset()[0].values())), atol=1e-6)
            else:
                np.testing.assert_array_equal(obs[i], info["final_obs"][i])
    assert finished >= 3


def test_bad_batched_actions() -> None:
    vec = VectorPursuitEnv(2, "1p-low")
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 2, 2\)"):
        vec.step(np.zeros((2, 2), dtype=int))
    with pytest.raises(ValueError, match=r"directions in 0\.\.11"):
        vec.step(np.full((2, 2, 2), 12))
    for bad in ((0, 0, 0, 2), (1, 1, 1, -1), (0, 0, 1, 12)):  # a predator's mode, a direction
        actions = np.zeros((2, 2, 2), dtype=np.int64)
        actions[bad[:3]] = bad[3]
        with pytest.raises(ValueError, match="modes must be 0"):
            vec.step(actions)
    actions = np.zeros((2, 2, 2), dtype=np.int64)
    actions[:, 1, 0] = 7  # the prey's mode is ignored
    vec.step(actions)
    with pytest.raises(ValueError, match="num_envs=0"):
        VectorPursuitEnv(0, "1p-low")


@pytest.mark.parametrize("dtype", [np.int8, np.uint8, np.int32, np.int64, np.uint64])
def test_the_compiled_action_check_agrees_with_the_array_form(dtype: type) -> None:
    rng = np.random.default_rng(0)
    low = 0 if np.issubdtype(dtype, np.unsignedinteger) else -1
    for _ in range(300):
        actions = rng.integers(low, 13, size=(3, rng.integers(2, 5), 2)).astype(dtype)
        actions[..., 0] = np.where(rng.random(actions.shape[:2]) < 0.9, actions[..., 0] % 2, actions[..., 0])
        actions[..., 1] = np.where(rng.random(actions.shape[:2]) < 0.9, actions[..., 1] % 12, actions[..., 1])
        modes, directions = actions[:, :-1, 0], actions[..., 1]
        naive = not (((modes < 0) | (modes > 1)).any() or ((directions < 0) | (directions >= 12)).any())
        assert _actions_in_range(actions, 12) == naive
