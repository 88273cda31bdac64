"""The network and the double-DQN learner against hand computations, and a small MDP solved."""

import copy
import math

import numpy as np
import pytest
import torch
from reference.dqn_loss import double_dqn_targets

from pursuit_bench.agents.adam import FlatAdam
from pursuit_bench.agents.config import QUICK, AgentConfig
from pursuit_bench.agents.dqn import DQNLearner, wall_features
from pursuit_bench.agents.network import DuelingQNetwork
from pursuit_bench.agents.replay import Batch


def naive_forward(net: DuelingQNetwork, obs: np.ndarray, member: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The dueling MLP written out in numpy: returns (Q, V, A) for one member."""
    p = {k: v[member].detach().numpy().astype(np.float64) for k, v in net.state_dict().items()}

    def linear(name: str, x: np.ndarray) -> np.ndarray:
        return x @ p[f"{name}.weight"] + p[f"{name}.bias"][0]

    relu = lambda x: np.maximum(x, 0)  # noqa: E731
    h = relu(linear("trunk2", relu(linear("trunk1", obs))))
    v = linear("value2", relu(linear("value1", h)))
    a = linear("advantage2", relu(linear("advantage1", h)))
    return v + a - a.mean(axis=-1, keepdims=True), v[:, 0], a


def test_dueling_aggregation() -> None:
    net = DuelingQNetwork(10, 5, members=2, seed=3)
    obs = np.random.default_rng(0).normal(size=(2, 7, 10))
    q = net(torch.as_tensor(obs, dtype=torch.float32)).detach().numpy()
    for m in range(2):
        q_naive, v, _ = naive_forward(net, obs[m], m)
        np.testing.assert_allclose(q[m], q_naive, atol=1e-5)
        np.testing.assert_allclose(q[m].mean(axis=-1), v, atol=1e-5)  # mean-subtracted advantages
    _, value, _ = net.streams(torch.as_tensor(obs, dtype=torch.float32))
    np.testing.assert_allclose(value[0, :, 0].detach().numpy(), naive_forward(net, obs[0])[1], atol=1e-5)


def test_double_dqn_target_by_hand() -> None:
    online, target = DuelingQNetwork(4, 3, seed=1), DuelingQNetwork(4, 3, seed=2)
    next_obs = np.random.default_rng(1).normal(size=(1, 6, 4))
    rewards = np.array([[0.5, -1.0, 0.0, 1.0, 0.2, -0.1]])
    terminated = np.array([[0, 0, 1, 0, 1, 0]], dtype=np.float64)
    r, s_next, term = (torch.as_tensor(x, dtype=torch.float32) for x in (rewards, next_obs, terminated))
    y = double_dqn_targets(online(s_next), target, r, s_next, term, gamma=0.9).numpy()
    q_online, _, _ = naive_forward(online, next_obs[0])
    q_target, _, _ = naive_forward(target, next_obs[0])
    best = q_online.argmax(axis=1)  # the online net chooses, the target net evaluates
    expected = rewards[0] + 0.9 * (1 - terminated[0]) * q_target[np.arange(6), best]
    np.testing.assert_allclose(y[0], expected, atol=1e-5)
    assert not np.allclose(expected, rewards[0] + 0.9 * (1 - terminated[0]) * q_target.max(axis=1))


def test_only_termination_cuts_the_bootstrap() -> None:
    learner = DQNLearner(3, 2, QUICK, seed=0)
    obs = np.ones((1, 2, 3), dtype=np.float32)
    r = torch.tensor([[1.0, 1.0]])
    s_next = torch.as_tensor(obs)
    y_end = double_dqn_targets(learner.online(s_next), learner.target, r, s_next, torch.tensor([[1.0, 0.0]]), 0.9)
    q_next = learner.target(torch.as_tensor(obs))[0, 0]
    assert y_end[0, 0].item() == pytest.approx(1.0)  # terminated: no bootstrap
    bootstrap = 1.0 + 0.9 * q_next[learner.online(torch.as_tensor(obs))[0, 0].argmax()].item()
    assert y_end[0, 1].item() == pytest.approx(bootstrap, abs=1e-6)  # truncated: bootstraps


def chain_policy(prioritized: bool, seed: int = 0) -> np.ndarray:
    """Train on a 6-state chain (right moves on, left moves back, +1 for reaching the right end,
    which terminates; episodes truncated after 20 steps) and return the greedy actions."""
    n = 6
    config = AgentConfig(
        learning_rate=3e-3,
        buffer_size=2000,
        batch_size=32,
        learning_starts=100,
        target_update_every=100,
        epsilon_decay_steps=1000,
        beta_anneal_steps=3000,
        prioritized=prioritized,
    )
    learner = DQNLearner(n, 2, config, seed=seed)
    rng = np.random.default_rng(seed)
    eye = np.eye(n, dtype=np.float32)
    state, t = 0, 0
    for _ in range(3000):
        action = learner.act(eye[state][None, None], explore=True)[0, 0]
        nxt = min(state + 1, n - 1) if action == 1 else max(state - 1, 0)
        done = nxt == n - 1
        learner.store(
            eye[state][None, None],
            np.array([[action]]),
            np.array([[float(done)]]),
            eye[nxt][None, None],
            np.array([[float(done)]]),
        )
        learner.train()
        state, t = (0, 0) if done or t >= 19 else (nxt, t + 1)
        if state == 0 and t == 0:
            state = int(rng.integers(0, n - 1))
    return learner.act(eye[None, : n - 1], explore=False)[0]


@pytest.mark.parametrize("prioritized", [True, False])
def test_learner_solves_a_chain(prioritized: bool) -> None:
    np.testing.assert_array_equal(chain_policy(prioritized), np.ones(5))  # always right


def test_one_batched_update_equals_separate_updates() -> None:
    config = QUICK.replace(batch_size=8)
    stacked = DQNLearner(10, 2, config, members=3, seed=0)
    singles = [DQNLearner(10, 2, config, seed=s) for s in range(3)]
    for m, single in enumerate(singles):  # same starting weights, member by member
        for net, mine in ((single.online, stacked.online), (single.target, stacked.target)):
            net.load_state_dict({k: v[m : m + 1].clone() for k, v in mine.state_dict().items()})
    rng = np.random.default_rng(0)
    for _ in range(3):  # three steps, so that Adam's moments matter
        batches = [
            Batch(
                indices=np.arange(8),
                obs=rng.normal(size=(8, 10)).astype(np.float32),
                actions=rng.integers(0, 2, 8),
                rewards=rng.normal(size=8).astype(np.float32),
                next_obs=rng.normal(size=(8, 10)).astype(np.float32),
                terminated=rng.integers(0, 2, 8).astype(np.float32),
                weights=rng.random(8).astype(np.float32),
            )
            for _ in range(3)
        ]
        together = Batch(*(np.stack([getattr(b, f) for b in batches]) for f in Batch.__dataclass_fields__))
        stacked_losses = stacked.learn(together)
        single_losses = [
            single.learn(Batch(*(getattr(b, f)[None] for f in Batch.__dataclass_fields__)))[0]
            for single, b in zip(singles, batches, strict=True)
        ]
        np.testing.assert_allclose(stacked_losses, single_losses, rtol=1e-5)
    for m, single in enumerate(singles):
        for k, v in single.online.state_dict().items():
            np.testing.assert_allclose(stacked.online.state_dict()[k][m].numpy(), v[0].numpy(), atol=1e-6)


def test_target_network_starts_as_a_copy_and_is_copied_every_n_transitions() -> None:
    learner = DQNLearner(3, 2, QUICK.replace(target_update_every=10, learning_starts=0, batch_size=4), seed=0)

    def same() -> bool:
        return all(
            torch.equal(a, b) for a, b in zip(learner.online.parameters(), learner.target.parameters(), strict=True)
        )

    assert same()
    before = copy.deepcopy(learner.target.state_dict())
    x = np.zeros((1, 4, 3), dtype=np.float32)
    learner.store(x, np.zeros((1, 4), dtype=int), np.ones((1, 4)), x, np.zeros((1, 4)))
    learner.train()
    assert not same() and all(torch.equal(v, learner.target.state_dict()[k]) for k, v in before.items())
    y = np.zeros((1, 6, 3), dtype=np.float32)
    learner.store(y, np.zeros((1, 6), dtype=int), np.ones((1, 6)), y, np.zeros((1, 6)))  # 10 transitions
    assert same()


def test_flat_adam_equals_torch_adam() -> None:
    """The flat-buffer Adam makes torch's Adam steps, with every parameter and moment in place."""
    ours, theirs = DuelingQNetwork(6, 3, members=2, seed=4), DuelingQNetwork(6, 3, members=2, seed=4)
    flat = FlatAdam(ours, lr=1e-2)
    reference = torch.optim.Adam(theirs.parameters(), lr=1e-2, foreach=False)
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = torch.as_tensor(rng.normal(size=(2, 8, 6)), dtype=torch.float32)
        flat.zero_grad()
        (ours(x) ** 2).sum().backward()
        flat.step()
        reference.zero_grad()
        (theirs(x) ** 2).sum().backward()
        reference.step()
    assert flat.grad.abs().sum() > 0  # backward wrote into the flat gradient
    for (name, a), b in zip(ours.named_parameters(), theirs.parameters(), strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6, msg=name)
    for avg, p in zip(flat.exp_avg, theirs.parameters(), strict=True):
        torch.testing.assert_close(avg, reference.state[p]["exp_avg"], rtol=1e-5, atol=1e-7)


def test_wall_features_are_the_own_position_in_the_line_of_sight_frame() -> None:
    rng = np.random.default_rng(3)
    obs = rng.uniform(-1, 1, size=(50, 16)).astype(np.float32)
    obs[0, 4:6] = obs[0, 0:2]  # coincident disks: the LOS is +x
    got = wall_features(torch.as_tensor(obs)).numpy()
    assert got.shape == (50, 18) and np.array_equal(got[:, :16], obs)
    for row, (u, v) in zip(obs, got[:, 16:], strict=True):
        angle = math.atan2(row[5] - row[1], row[4] - row[0]) if not np.array_equal(row[4:6], row[0:2]) else 0.0
        # rotate the own position by -angle: its coordinates along and to the left of the LOS
        expected_u = row[0] * math.cos(angle) + row[1] * math.sin(angle)
        expected_v = -row[0] * math.sin(angle) + row[1] * math.cos(angle)
        assert (u, v) == pytest.approx((expected_u, expected_v), abs=1e-5)
    learner = DQNLearner(16, 12, QUICK.replace(wall_features=True), seed=0)
    assert learner.online.n_obs == 18 and learner.evaluate(obs[None])[0].shape == (1, 50, 12)


@pytest.mark.parametrize("prioritized", [True, False])
def test_the_one_call_update_makes_the_numbers_of_sample_then_learn(prioritized: bool) -> None:
    """``update`` (one compiled call: sample, loss and gradient, Adam, priorities) against the
    calls it fuses, made one by one, on twin learners: the same bits, update after update, and
    the target copies by the flat buffers the same as copying the state dict."""
    config = QUICK.replace(wall_features=True, prioritized=prioritized, target_update_every=60, batch_size=16)
    fused, parts = (DQNLearner(8, 5, config, members=3, seed=[4, 5, 6]) for _ in range(2))
    rng = np.random.default_rng(0)
    for step in range(12):
        obs, next_obs = rng.normal(size=(2, 3, 20, 8)).astype(np.float32)
        actions, rewards = rng.integers(0, 5, (3, 20)), rng.normal(size=(3, 20)).astype(np.float32)
        terminated = (rng.random((3, 20)) < 0.1).astype(np.float32)
        for learner in (fused, parts):
            learner.store(obs, actions, rewards, next_obs, terminated)
        if parts.steps % 60 == 0:  # store copied the target by the flat buffers: the state dict's copy agrees
            copied = parts._target_flat.clone()
            parts.target.load_state_dict(parts.online.state_dict())
            assert torch.equal(copied, parts._target_flat)
        if step < 2:
            continue
        losses = fused.update()
        expected = parts.learn(parts.replay.sample(config.batch_size, parts.beta, parts.rngs))
        np.testing.assert_array_equal(losses, expected)
        for a, b in [
            (fused.optimizer.flat, parts.optimizer.flat),
            (fused.optimizer._m, parts.optimizer._m),
            (fused.optimizer._v, parts.optimizer._v),
            (fused._target_flat, parts._target_flat),
        ]:
            assert torch.equal(a, b)
        for name in ("priorities", "tree", "max_priority"):
            np.testing.assert_array_equal(getattr(fused.replay, name), getattr(parts.replay, name))
    assert fused.updates == parts.updates == 10 and not torch.equal(
        fused.online.trunk1.weight, fused.target.trunk1.weight
    )


def test_the_one_call_update_refuses_an_action_the_learner_has_not_and_changes_nothing() -> None:
    learner = DQNLearner(8, 2, QUICK.replace(batch_size=16), members=2, seed=[1, 2])
    obs = np.random.default_rng(0).normal(size=(2, 40, 8)).astype(np.float32)
    actions = np.ones((2, 40), dtype=np.int64)
    actions[1] = 7  # member 1 stored actions of a learner with 12: any batch of its draws one
    learner.store(obs, actions, np.zeros((2, 40), dtype=np.float32), obs, np.zeros((2, 40), dtype=np.float32))
    flat, priorities = learner.optimizer.flat.clone(), learner.replay.priorities.copy()
    with pytest.raises(ValueError, match="stored actions"):
        learner.update()
    assert torch.equal(learner.optimizer.flat, flat) and learner.optimizer.step_count == learner.updates == 0
    np.testing.assert_array_equal(learner.replay.priorities, priorities)


@pytest.mark.parametrize("n_actions", [0, -2, 2.0, True])
def test_a_learner_needs_at_least_one_action(n_actions: object) -> None:
    with pytest.raises(ValueError, match="n_actions"):
        DQNLearner(4, n_actions, QUICK)  # type: ignore[arg-type]
