"""The batched TorchRL env (``marl/torchrl_env.py``) against what it replaces: TorchRL's
``PettingZooWrapper`` of one env per arena stacked by a ``SerialEnv`` (``benchmarl_task.make_env``),
the same seeds, the same random actions, compared key for key and bit for bit through TorchRL's
own stepping (``step_and_maybe_reset``: partial resets of the arenas whose episodes ended)."""

import pytest

pytest.importorskip("benchmarl", reason="the marl extra is not installed (pip install -e '.[marl]')")

import torch
from torchrl.envs import SerialEnv
from torchrl.envs.utils import check_env_specs

from pursuit_bench.marl.benchmarl_task import PursuitTask, first_seeds, make_env
from pursuit_bench.marl.torchrl_env import PursuitTorchRLEnv


def _play(env, steps: int, seed: int) -> list:
    generator = torch.Generator().manual_seed(seed)
    td = env.reset()
    seen = [td.clone()]
    for _ in range(steps):
        td["predator", "action"] = torch.randint(0, 24, td["predator", "observation"].shape[:-1], generator=generator)
        td["prey", "action"] = torch.randint(0, 12, td["prey", "observation"].shape[:-1], generator=generator)
        td, after = env.step_and_maybe_reset(td)
        seen += [td.clone(), after.clone()]
    return seen


@pytest.mark.parametrize(
    ("condition", "options"),
    [("2p-low-shared", {}), ("3p-high-individual", {}), ("1p-high", {"obstacles": 2, "max_steps": 40})],
)
def test_the_batched_env_plays_what_serial_pettingzoo_envs_play_bit_for_bit(condition: str, options: dict) -> None:
    seeds = [3001, 3002, 3003]
    serial = SerialEnv(3, [lambda s=s: make_env(condition, s, "cpu", **options) for s in seeds])
    batched = PursuitTorchRLEnv(condition, seeds, "cpu", **options)
    assert batched.observation_spec == serial.observation_spec and batched.full_done_spec == serial.full_done_spec
    assert batched.full_action_spec == serial.full_action_spec and batched.full_reward_spec == serial.full_reward_spec
    theirs, ours = _play(serial, 90, seed=5), _play(batched, 90, seed=5)
    ended = sum(int(td["next", "done"].sum()) for td in theirs[1::2])
    assert ended >= 3  # partial resets were exercised
    for a, b in zip(theirs, ours, strict=True):
        assert set(a.keys(True, True)) == set(b.keys(True, True))
        for key in a.keys(True, True):
            assert torch.equal(a[key], b[key]), key
    serial.close()


def test_the_batched_env_passes_torchrl_s_spec_check_and_refuses_bad_input() -> None:
    env = PursuitTorchRLEnv("2p-high-shared", [1, 2], "cpu")
    check_env_specs(env, seed=None)
    td = env.reset()
    td["predator", "action"] = torch.full((2, 2), 24)
    td["prey", "action"] = torch.zeros((2, 1), dtype=torch.int64)
    with pytest.raises(ValueError, match=r"0\.\.23"):
        env.step(td)
    with pytest.raises(ValueError, match="one seed per arena"):
        PursuitTorchRLEnv("2p-high-shared", [], "cpu")
    with pytest.raises(ValueError, match="discrete task"):
        PursuitTorchRLEnv("2p-high-shared", [1], "cpu", continuous=True)


def test_the_task_builds_one_batched_env_of_distinct_arenas() -> None:
    task = PursuitTask.PURSUIT_3P_HIGH_INDIVIDUAL.get_task(config={})
    env = task.get_env_fun(3, False, 4, "cpu")()
    assert env.batch_size == (3,) and first_seeds(4, 3) == [4001, 4002, 4003]
    state = env.reset()["state"]
    assert not torch.equal(state[0], state[1]) and not torch.equal(state[1], state[2])
    assert task.observation_spec(env)["predator", "observation"].shape == (3, 22)
    assert task.state_spec(env)["state"].shape == (16,)
    assert task.action_spec(env)["predator", "action"].space.n == 24
