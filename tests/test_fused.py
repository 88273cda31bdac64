"""The compiled update and forward pass (agents/fused.py) against autograd and the torch network:
same losses, gradients and parameters after several steps to float rounding, and each member's
update the same bits alone as stacked beside others."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import torch
from reference import dqn_loss

from pursuit_bench.agents.config import QUICK, REPRODUCTION, AgentConfig
from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.fused import _column_sums
from pursuit_bench.agents.replay import Batch


def random_batch(rng: np.random.Generator, members: int, size: int, n_obs: int, n_actions: int) -> Batch:
    return Batch(
        indices=np.tile(np.arange(size), (members, 1)),
        obs=rng.uniform(-1, 1, size=(members, size, n_obs)).astype(np.float32),
        actions=rng.integers(0, n_actions, (members, size)),
        rewards=(3 * rng.normal(size=(members, size))).astype(np.float32),  # TD errors beyond the Huber δ too
        next_obs=rng.uniform(-1, 1, size=(members, size, n_obs)).astype(np.float32),
        terminated=rng.integers(0, 2, (members, size)).astype(np.float32),
        weights=rng.random((members, size)).astype(np.float32),
    )


def autograd_step(learner: DQNLearner, batch: Batch) -> np.ndarray:
    """The reference: tests/reference/dqn_loss.py's loss, autograd's backward, the same Adam."""
    losses, td = dqn_loss.loss(learner, batch)
    learner.optimizer.zero_grad()
    losses.sum().backward()
    learner.optimizer.step()
    learner.replay.update_priorities(batch.indices, td.detach().numpy())
    return losses.detach().numpy()


@pytest.mark.parametrize(
    ("config", "n_actions", "members"),
    [(QUICK, 2, 1), (REPRODUCTION, 12, 3), (QUICK.replace(huber_delta=0.3, gamma=0.99), 24, 2)],
)
def test_the_compiled_update_makes_autograds_steps(config: AgentConfig, n_actions: int, members: int) -> None:
    compiled = DQNLearner(10, n_actions, config, members=members, seed=5)
    reference = DQNLearner(10, n_actions, config, members=members, seed=5)
    rng = np.random.default_rng(0)
    for _ in range(6):  # several steps: Adam's moments and the moved weights matter
        batch = random_batch(rng, members, 64, 10, n_actions)
        expected = autograd_step(reference, batch)
        got = compiled.learn(batch)
        np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-7)
        torch.testing.assert_close(compiled.optimizer.grad, reference.optimizer.grad, rtol=1e-4, atol=1e-8)
        # the new priorities are the TD errors: the same to rounding
        np.testing.assert_allclose(compiled.replay.priorities, reference.replay.priorities, rtol=1e-5, atol=1e-7)
    assert reference.optimizer.grad.abs().max() > 1e-3  # gradients that say something
    # Adam divides by the gradients' root mean square: its first steps move a weight by ±lr whatever
    # the gradient's size, so parameters agree to a hundredth of the learning rate
    lr = config.learning_rate
    torch.testing.assert_close(compiled.optimizer.flat, reference.optimizer.flat, rtol=0, atol=1e-2 * lr)


def test_a_members_update_is_the_same_bits_alone_and_stacked() -> None:
    config = REPRODUCTION
    rng = np.random.default_rng(1)
    stacked = DQNLearner(14, 12, config, members=3, seed=[11, 12, 13])
    alone = DQNLearner(14, 12, config, members=1, seed=[12])
    for _ in range(3):
        batch = random_batch(rng, 3, 64, 14, 12)
        stacked_losses = stacked.learn(batch)
        alone_losses = alone.learn(Batch(*(getattr(batch, f)[1:2] for f in Batch.__dataclass_fields__)))
        assert stacked_losses[1] == alone_losses[0]
    for mine, theirs in zip(stacked.online.parameters(), alone.online.parameters(), strict=True):
        assert torch.equal(mine[1], theirs[0])


@pytest.mark.parametrize("wall", [False, True])
def test_the_compiled_forward_pass_gives_the_networks_values(wall: bool) -> None:
    learner = DQNLearner(14, 12, QUICK.replace(wall_features=wall), members=2, seed=3)
    obs = np.random.default_rng(2).uniform(-1, 1, size=(2, 40, 14)).astype(np.float32)
    obs[0, 0, 4:6] = obs[0, 0, 0:2]  # coincident disks: the line of sight is +x
    q, value = learner.act_values(obs)
    expected_q, expected_value = learner.evaluate(obs)  # torch's network, member by member
    np.testing.assert_allclose(q, expected_q, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(value, expected_value, rtol=1e-5, atol=1e-6)
    assert np.array_equal(q.argmax(-1), expected_q.argmax(-1))


def test_decisions_are_torchs_even_where_actions_tie() -> None:
    learner = DQNLearner(14, 12, REPRODUCTION, members=2, seed=4)
    obs = np.random.default_rng(5).uniform(-1, 1, size=(200, 14)).astype(np.float32)
    everyone = np.zeros((2, 200, 14), dtype=np.float32)
    everyone[1] = obs
    torch_q = learner.evaluate(everyone)[0][1]
    assert np.array_equal(learner.decisive_q(obs, 1).argmax(-1), torch_q.argmax(-1))
    with torch.no_grad():  # every action worth the same: too close to call, torch's numbers decide
        learner.online.advantage2.weight[1] = 0.0
        learner.online.advantage2.bias[1] = 0.0
    tied = learner.decisive_q(obs, 1)
    everyone_tied = learner.evaluate(everyone)[0][1]
    assert np.array_equal(tied, everyone_tied)  # torch's own values, bit for bit


def test_the_compiled_undecided_rows_are_numpys_expression_row_for_row() -> None:
    """``undecided_kernel`` against the expression it replaced (the two best Q-values by numpy's
    sort, :func:`decision_scale`, the comparison in float32), on rows with ties, rows at the
    threshold to the last bit either side, and random rows of 1, 2 and 12 actions."""
    from pursuit_bench.agents.dqn import DECISIVE_GAP, decision_scale
    from pursuit_bench.agents.fused import undecided_kernel

    def naive(q: np.ndarray, v: np.ndarray) -> np.ndarray:
        if q.shape[1] == 1:
            return np.zeros(len(q), dtype=bool)
        top = np.sort(q, axis=-1)[:, -2:]
        return top[:, 1] - top[:, 0] <= DECISIVE_GAP * decision_scale(q, v)

    rng = np.random.default_rng(5)
    gap = np.float32(DECISIVE_GAP)
    for actions in (1, 2, 12):
        q = rng.normal(0, 3, (4000, actions)).astype(np.float32)
        v = rng.normal(0, 3, 4000).astype(np.float32)
        if actions > 1:
            q[:500, 0] = q[:500, 1] = q[:500].max(axis=1)  # the two best tied
            scale = decision_scale(q, v)
            edge = np.float32(DECISIVE_GAP) * scale[500:1500]  # a gap of exactly the threshold, and a bit above
            q[500:1500, 1] = q[500:1500, :].max(axis=1) + edge
            q[1000:1500, 1] = np.nextafter(q[1000:1500, 1], np.float32(np.inf))
        expected = naive(q, v)
        assert np.array_equal(undecided_kernel(q, v, gap), expected)
        if actions > 1:
            assert expected[:500].all() and 0 < expected[500:1500].sum() < 1000  # both sides of the edge met


@pytest.mark.slow
@pytest.mark.parametrize("condition", ["1p-high", "3p-high-shared"])
def test_evaluation_by_the_fast_forward_pass_equals_torchs(condition: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The paper's protocol on the shipped agents, played with the compiled forward pass, gives the
    same result, figure for figure, as played with torch's network (what the committed evaluations
    used); and the two passes differ by far less than the gap at which decisions go to torch."""
    from pursuit_bench import pretrained
    from pursuit_bench.agents.dqn import DECISIVE_GAP, decision_scale
    from pursuit_bench.agents.fused import q_and_value_kernel
    from pursuit_bench.training.evaluate import evaluate_agents

    fast = evaluate_agents(condition, pretrained.load(condition), episodes=40, seed=3, num_envs=16)
    worst = [0.0]

    def torchs(self: DQNLearner, obs: np.ndarray, member: int, parts: np.ndarray | None = None) -> np.ndarray:
        everyone = np.zeros((self.members, *obs.shape), dtype=np.float32)
        everyone[member] = obs
        q = self.evaluate(everyone)[0][member]
        flat, stacked = self.optimizer.flat.numpy(), np.ascontiguousarray(obs, dtype=np.float32)[None]
        compiled_q, compiled_v = q_and_value_kernel(
            flat, self._offsets, self.n_actions, stacked, self.config.wall_features, member
        )
        scale = decision_scale(compiled_q[0], compiled_v[0])[:, None]
        worst[0] = max(worst[0], float((np.abs(compiled_q[0] - q) / scale).max()))
        return q

    monkeypatch.setattr(DQNLearner, "decisive_q", torchs)
    # fresh agents: the prey's exploration generator starts where it starts
    assert evaluate_agents(condition, pretrained.load(condition), episodes=40, seed=3, num_envs=16) == fast
    assert 0 < worst[0] < DECISIVE_GAP / 4


def test_a_groups_predators_steer_in_one_call_as_each_alone() -> None:
    from pursuit_bench.agents.kinds import HierarchicalPredator, members_to_env

    learner = DQNLearner(14, 2, QUICK, members=3, seed=0)
    agents = [HierarchicalPredator(f"predator_{m}", learner, m) for m in range(3)]
    rng = np.random.default_rng(6)
    obs = rng.uniform(-1, 1, size=(3, 32, 14)).astype(np.float32)
    choices = rng.integers(0, 2, (3, 32))
    together = members_to_env(agents, choices, obs)
    for m, agent in enumerate(agents):
        np.testing.assert_array_equal(together[m], agent.to_env(choices[m], obs[m]))


def test_the_compiled_passes_refuse_what_would_read_past_a_members_parameters() -> None:
    learner = DQNLearner(10, 12, REPRODUCTION, members=2, seed=0)
    with pytest.raises(ValueError, match=r"obs of shape \(2, 4, 11\): expected \(2, B, 10\)"):
        learner.act_values(np.zeros((2, 4, 11), dtype=np.float32))
    with pytest.raises(ValueError, match="member=2"):
        learner.decisive_q(np.zeros((4, 10), dtype=np.float32), 2)
    batch = random_batch(np.random.default_rng(0), 2, 8, 10, 12)
    batch.actions[0, 0] = 12
    with pytest.raises(ValueError, match=r"values in \[0, 12\)"):
        learner.learn(batch)


def test_acting_in_one_call_chooses_as_the_forward_pass_and_epsilon_greedy_do() -> None:
    """``act_members`` (forward pass and ε-greedy in one compiled call) against ``act_values`` and
    a naive ε-greedy on copies of the members' generators (each member: B uniforms, then B random
    actions): the same Q-values, values and actions, the generators left in the same state."""
    config = REPRODUCTION.replace(epsilon_start=0.5, epsilon_end=0.5)
    learner = DQNLearner(14, 12, config, members=3, seed=[5, 6, 7])
    copies = [np.random.default_rng(s) for s in (5, 6, 7)]
    for rng, copy in zip(learner.rngs, copies, strict=True):
        copy.bit_generator.state = rng.bit_generator.state
    obs = np.random.default_rng(8).uniform(-1, 1, size=(3, 32, 14)).astype(np.float32)
    for _ in range(5):
        chosen, q, value = learner.act_members(obs, explore=True)
        expected_q, expected_value = learner.act_values(obs)
        np.testing.assert_array_equal(q, expected_q)
        np.testing.assert_array_equal(value, expected_value)
        for m, copy in enumerate(copies):
            explore, random = copy.random(32) < 0.5, copy.integers(0, 12, size=32)
            np.testing.assert_array_equal(chosen[m], np.where(explore, random, q[m].argmax(-1)))
    for rng, copy in zip(learner.rngs, copies, strict=True):
        assert rng.bit_generator.state == copy.bit_generator.state
    greedy, q, _ = learner.act_members(obs, explore=False)
    np.testing.assert_array_equal(greedy, q.argmax(-1))
    np.testing.assert_array_equal(learner.choose(q, explore=False), greedy)
    with pytest.raises(ValueError, match="expected"):
        learner.act_members(obs[:2], explore=True)


def test_column_sums_add_each_column_in_the_order_of_a_loop_down_it() -> None:
    x = (np.random.default_rng(0).normal(size=(64, 48)) * 10.0 ** np.arange(-3, 3).repeat(8)).astype(np.float32)
    out = np.empty(48, dtype=np.float32)
    _column_sums(x, out)
    for j in range(48):
        total = np.float32(0.0)
        for i in range(64):
            total = np.float32(total + x[i, j])
        assert out[j] == total
    backwards = np.zeros(48, dtype=np.float32)
    for i in reversed(range(64)):
        backwards += x[i]
    assert not np.array_equal(out, backwards)  # the data tell the orders apart: the test can see one


@pytest.mark.slow
def test_importing_the_kernels_leaves_the_threads_alone_and_a_learner_limits_scipys_blas() -> None:
    """fused.py has no import side effect: SciPy's BLAS keeps its threads until a learner is made,
    which gives it one (a process per core trains; more threads only wait on each other)."""
    if len(os.sched_getaffinity(0)) < 2:
        # OpenBLAS caps its threads at the CPUs the process may use (found under `taskset -c 0`).
        pytest.skip("needs two CPUs: OpenBLAS never starts more threads than the process may use")
    code = (
        "import os\n"
        "os.environ['OPENBLAS_NUM_THREADS'] = '2'\n"
        "from pathlib import Path\n"
        "from threadpoolctl import threadpool_info\n"
        "import pursuit_bench.agents.fused\n"
        "def scipys():\n"
        "    return [i['num_threads'] for i in threadpool_info() if 'scipy' in Path(i['filepath']).parent.name]\n"
        "before = scipys()\n"
        "from pursuit_bench.agents.config import QUICK\n"
        "from pursuit_bench.agents.dqn import DQNLearner\n"
        "DQNLearner(4, 3, QUICK)\n"
        "print(before, scipys())\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[2] [1]", done.stdout
