"""The batched TorchRL env (``marl/torchrl_env.py``) against what it replaces: TorchRL's
``PettingZooWrapper`` of one env per arena stacked by a ``SerialEnv`` (``benchmarl_task.make_env``),
the same seeds, the same random actions, compared key for key and bit for bit through TorchRL's
own stepping (``step_and_maybe_reset``: partial resets of the arenas whose episodes ended)."""

import pytest

pytest.importorskip("benchmarl", reason="the marl extra is not installed (pip install -e '.[marl]')")

import torch
from tensordict import TensorDict, TensorDictBase
from torchrl.envs import SerialEnv
from torchrl.envs.utils import check_env_specs

from pursuit_bench.marl.benchmarl_task import PursuitTask, first_seeds, make_env
from pursuit_bench.marl.torchrl_env import PursuitTorchRLEnv


def _play(env, steps: int, seed: int, set_seed: int | None = None) -> list:
    """What TorchRL's collectors see: ``step_and_maybe_reset``'s stepped tensordict each step, the
    next root it gives back fed in (partial resets of the arenas whose episodes ended)."""
    generator = torch.Generator().manual_seed(seed)
    seen = [] if set_seed is None else [env.set_seed(set_seed)]
    td = env.reset()
    seen.append(td.clone())
    for _ in range(steps):
        td["predator", "action"] = torch.randint(0, 24, td["predator", "observation"].shape[:-1], generator=generator)
        td["prey", "action"] = torch.randint(0, 12, td["prey", "observation"].shape[:-1], generator=generator)
        out, td = env.step_and_maybe_reset(td)
        seen += [out.clone(), td.clone()]
    return seen


def _same(theirs: list, ours: list) -> None:
    for a, b in zip(theirs, ours, strict=True):
        if not isinstance(a, TensorDictBase):  # set_seed's next seed
            assert a == b
            continue
        assert set(a.keys(True, True)) == set(b.keys(True, True))
        for key in a.keys(True, True):
            assert torch.equal(a[key], b[key]), key


@pytest.mark.parametrize(
    ("condition", "options"),
    [("2p-low-shared", {}), ("3p-high-individual", {}), ("1p-high", {"obstacles": 2, "max_steps": 40})],
)
def test_the_batched_env_plays_what_serial_pettingzoo_envs_play_bit_for_bit(condition: str, options: dict) -> None:
    seeds = [3001, 3002, 3003]
    serial = SerialEnv(3, [lambda s=s: make_env(condition, s, "cpu", **options) for s in seeds])
    try:
        batched = PursuitTorchRLEnv(condition, seeds, "cpu", **options)
        assert batched.observation_spec == serial.observation_spec and batched.full_done_spec == serial.full_done_spec
        assert batched.full_action_spec == serial.full_action_spec
        assert batched.full_reward_spec == serial.full_reward_spec
        theirs, ours = _play(serial, 90, seed=5), _play(batched, 90, seed=5)
        partial = [
            (before, after)
            for before, after in zip(ours[1::2], ours[2::2], strict=True)
            if 0 < int(before["next", "done"].sum()) < 3
        ]
        assert len(partial) >= 3  # partial resets were exercised: the ended arenas started again, the others went on
        for stepped, fed in partial:
            ended = stepped["next", "done"].reshape(-1)
            assert torch.equal(fed["state"][~ended], stepped["next", "state"][~ended])
            assert not torch.equal(fed["state"][ended], stepped["next", "state"][ended])
            assert (fed["predator", "info", "mode"][ended] == -1).all()
        _same(theirs, ours)
        # seeded by set_seed as SerialEnv seeds its envs: TorchRL's seed chain, the same next seed
        _same(_play(serial, 30, seed=6, set_seed=11), _play(batched, 30, seed=6, set_seed=11))
    finally:
        serial.close()


def test_the_batched_env_passes_torchrl_s_spec_check_and_refuses_bad_input() -> None:
    env = PursuitTorchRLEnv("2p-high-shared", [1, 2], "cpu")
    check_env_specs(env, seed=None)
    td = env.reset()
    td["predator", "action"] = torch.full((2, 2), 24)
    td["prey", "action"] = torch.zeros((2, 1), dtype=torch.int64)
    with pytest.raises(ValueError, match=r"\('predator', 'action'\) holds 24\.\.24; expected integers in 0\.\.23"):
        env.step(td)
    three = {"predator": {"action": torch.zeros((2, 3), dtype=torch.int64)}, "prey": {"action": td["prey", "action"]}}
    with pytest.raises(ValueError, match=r"of shape \(2, 3\); expected \(2, 2\)"):
        env.step(TensorDict(three, batch_size=(2,)))
    with pytest.raises(ValueError, match="takes no options"):
        env.reset(seed=3)
    with pytest.raises(ValueError, match="one seed per arena"):
        PursuitTorchRLEnv("2p-high-shared", [], "cpu")
    with pytest.raises(ValueError, match="discrete task"):
        PursuitTorchRLEnv("2p-high-shared", [1], "cpu", continuous=True)
    with pytest.raises(ValueError, match="at most 32 where there are obstacles"):
        PursuitTorchRLEnv("1p-high", list(range(33)), "cpu", obstacles=1)
    assert PursuitTorchRLEnv("1p-high", list(range(33)), "cpu").batch_size == (33,)  # no walls to keep apart


def test_an_ended_arena_is_not_stepped_and_a_group_s_reset_keeps_the_live_arenas() -> None:
    env = PursuitTorchRLEnv("3p-low-shared", [5, 6, 7], "cpu")
    td = env.reset()
    generator = torch.Generator().manual_seed(0)
    while True:
        td["predator", "action"] = torch.randint(0, 24, (3, 3), generator=generator)
        td["prey", "action"] = torch.randint(0, 12, (3, 1), generator=generator)
        td = env.step(td)
        ended = td["next", "done"].reshape(-1)
        if ended.any() and not ended.all():
            break
        if ended.all():
            td = env.reset()
        else:
            td = td["next"].clone()
    with pytest.raises(ValueError, match=rf"arenas \[{', '.join(map(str, ended.nonzero().flatten().tolist()))}\]"):
        env.step(td)
    flags = td["next", "predator", "done"].clone().squeeze(-1)
    after = env.reset(td["next"].clone().set(("predator", "_reset"), flags))  # the group's mask only
    assert torch.equal(after["state"][~ended], td["next", "state"][~ended])
    assert torch.equal(after["predator", "observation"][~ended], td["next", "predator", "observation"][~ended])
    assert not after["done"].any() and (after["predator", "info", "mode"][ended] == -1).all()


def test_the_task_builds_one_batched_env_of_distinct_arenas() -> None:
    task = PursuitTask.PURSUIT_3P_HIGH_INDIVIDUAL.get_task(config={})
    env = task.get_env_fun(3, False, 4, "cpu")()
    assert env.batch_size == (3,) and first_seeds(4, 3) == [4001, 4002, 4003]
    state = env.reset()["state"]
    assert not torch.equal(state[0], state[1]) and not torch.equal(state[1], state[2])
    assert task.observation_spec(env)["predator", "observation"].shape == (3, 22)
    assert task.state_spec(env)["state"].shape == (16,)
    assert task.action_spec(env)["predator", "action"].space.n == 24
