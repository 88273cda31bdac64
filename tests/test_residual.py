"""The residual predator (issue 40): the rule's direction corrected by a learned k × 30°, starting
as the rule."""

import json
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run_cli

from pursuit_bench.agents import QUICK, DQNLearner, HierarchicalPredator, ResidualPredator
from pursuit_bench.agents.kinds import CORRECTION_TIE_BREAK, CORRECTIONS
from pursuit_bench.env import task
from pursuit_bench.env.vector import VectorPursuitEnv
from pursuit_bench.rules.navigation import navigate
from pursuit_bench.training.train import TrainConfig, build_agents

pytestmark = pytest.mark.usefixtures("one_thread")


def observations(n: int = 64, agents: int = 2, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    p = rng.uniform(-0.8, 0.8, size=(n, agents, 2))
    v = rng.uniform(-1, 1, size=(n, agents, 2))
    return task.observations(p, v)


def test_actions_split_into_a_mode_and_a_correction_of_the_rule() -> None:
    obs = observations()[:, 0]
    residual = ResidualPredator("predator_0", DQNLearner(obs.shape[-1], 10, QUICK))
    modes = np.arange(10) // 5
    assert [int(k) for k in ResidualPredator.split(np.arange(10))[1]] == [0, -1, 1, -2, 2] * 2
    np.testing.assert_array_equal(ResidualPredator.split(np.arange(10))[0], modes)
    choices = np.arange(len(obs)) % 10
    np.testing.assert_array_equal(ResidualPredator.action(*ResidualPredator.split(choices)), choices)
    actions = residual.to_env(choices, obs)
    m, k = ResidualPredator.split(choices)
    np.testing.assert_array_equal(actions[:, 0], m)
    np.testing.assert_array_equal(actions[:, 1], (navigate(obs, m) + k) % 12)
    # by hand: a +2 correction of a rule direction 11 wraps to 1, a -1 of 0 to 11
    rule = navigate(obs[:2], np.array([1, 1]))
    crafted = residual.to_env(ResidualPredator.action(np.array([1, 1]), np.array([2, -1])), obs[:2])
    assert crafted[:, 1].tolist() == [(rule[0] + 2) % 12, (rule[1] - 1) % 12]
    with pytest.raises(ValueError, match="10 actions"):
        ResidualPredator("predator_0", DQNLearner(obs.shape[-1], 2, QUICK))


@pytest.mark.parametrize("obstacles", [0, 4])
def test_zero_correction_moves_exactly_as_the_hierarchical_predator(obstacles: int) -> None:
    """A fixed sequence of modes, played once through the hierarchical predator and once through
    the residual one with zero correction: the same env actions, the same trajectories."""
    modes = np.random.default_rng(3).integers(0, 2, size=(60, 8))
    runs = []
    for kind in (HierarchicalPredator, ResidualPredator):
        env = VectorPursuitEnv(8, "1p-high", obstacles=obstacles)
        obs, _ = env.reset(seed=11)
        agent = kind("predator_0", DQNLearner(env.obs_size, kind.n_actions, QUICK), avoidance=obstacles > 0)
        positions, sent = [], []
        for step_modes in modes:
            choices = step_modes if kind is HierarchicalPredator else ResidualPredator.action(step_modes, 0)
            actions = np.zeros((8, 2, 2), dtype=np.int64)
            actions[:, 0] = agent.to_env(choices, obs[:, 0])
            actions[:, 1] = [0, 3]  # the prey: a fixed push
            sent.append(actions.copy())
            obs, *_ = env.step(actions)
            positions.append(env.core.world.positions.copy())
        runs.append((np.array(sent), np.array(positions)))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])


def test_it_starts_as_the_rule_in_every_state() -> None:
    """At initialisation, built as training builds it (stacked members, their own seeds), the
    greedy action is the zero correction in every state, and each correction's Q-value is the
    zero correction's less the tie-break per step of 30°."""
    configs = [TrainConfig(condition="3p-high-shared", predator="residual", seed=s) for s in (0, 1)]
    n_obs = task.obs_size(4, False)
    groups, agents = build_agents(configs, [n_obs, n_obs])
    learner = next(g.learner for g in groups if g.learner.n_actions == 10)
    assert learner.members == 6
    obs = np.stack([observations(500, 4, seed=m)[:, m % 3] for m in range(6)])
    q, _ = learner.evaluate(obs)
    _, corrections = ResidualPredator.split(q.argmax(axis=-1))
    assert (corrections == 0).all()
    by_mode = q.reshape(6, 500, 2, 5)
    expected = by_mode[..., :1] - CORRECTION_TIE_BREAK * np.abs(np.array(CORRECTIONS))
    np.testing.assert_allclose(by_mode, expected, atol=1e-6)
    # the fast forward pass acting uses agrees
    predator = agents[0]["predator_0"]
    assert isinstance(predator, ResidualPredator)
    _, fast = ResidualPredator.split(learner.decisive_q(obs[0], 0).argmax(axis=-1))
    assert (fast == 0).all()
    # the online and target networks start alike, and the modes' Q-values are still the network's
    np.testing.assert_array_equal(
        learner.online.advantage2.bias.detach().numpy(), learner.target.advantage2.bias.detach().numpy()
    )
    assert np.ptp(by_mode[..., 0, 0] - by_mode[..., 1, 0]) > 0
    with pytest.raises(ValueError, match="10 rows"):
        learner.tie_initial_advantages([0] * 3, [0.0] * 3)


def test_learning_can_separate_the_corrections() -> None:
    """The tie is a starting point, not a constraint: updates on transitions that reward a
    correction raise its Q-value above the zero correction's."""
    n_obs = 10
    learner = DQNLearner(n_obs, 10, QUICK.replace(learning_starts=1, batch_size=16, learning_rate=1e-2))
    ResidualPredator.prepare(learner)
    obs = np.random.default_rng(0).normal(size=(1, 64, n_obs)).astype(np.float32)
    good = int(ResidualPredator.action(1, 2))
    for _ in range(30):
        actions = np.full((1, 64), good)
        learner.store(obs, actions, np.ones((1, 64)), obs, np.ones((1, 64)))
        learner.update()
    q, _ = learner.evaluate(obs)
    assert (q.argmax(axis=-1) == good).mean() > 0.9
    with pytest.raises(ValueError, match="already"):
        ResidualPredator.prepare(learner)


@pytest.mark.slow
def test_train_and_eval_a_residual_run(tmp_path: Path) -> None:
    out = tmp_path / "run"
    code, text = run_cli(
        "train", "--condition", "1p-high", "--predator", "residual", "--episodes", "6", "--num-envs", "2",
        "--no-record", "--out", str(out),
    )  # fmt: skip
    assert code == 0, text
    config = json.loads((out / "config.json").read_text())
    assert config["train"]["predator"] == "residual"
    code, text = run_cli("eval", str(out), "--episodes", "4", "--no-record")
    assert code == 0, text
    evaluation = json.loads((out / "eval.json").read_text())
    panel = evaluation["panels"][0]
    assert {"trained", "always_chase", "always_stalk"} <= set(panel)
    assert evaluation["predator_kind"] == "residual"
    code, text = run_cli("train", "--resume", "--episodes", "8", "--out", str(out), "--no-record")
    assert code == 0, text


def test_analysis_reads_back_the_correction_taken() -> None:
    """`analyze`'s states of a residual predator: the correction is the direction taken minus the
    rule's, by mode and distance; zero for a fresh one, +1 for one forced to turn a step."""
    from pursuit_bench.agents import Prey
    from pursuit_bench.study import analysis

    n_obs = task.obs_size(2, False)

    class TurnsOneStep(ResidualPredator):
        def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> np.ndarray:
            return self.to_env(ResidualPredator.action(np.ones(len(obs), dtype=int), 1), obs)

    used = []
    for kind in (ResidualPredator, TurnsOneStep):
        learner = DQNLearner(n_obs, 10, QUICK)
        ResidualPredator.prepare(learner)
        agents = {"predator_0": kind("predator_0", learner), "prey_0": Prey("prey_0", DQNLearner(n_obs, 12, QUICK))}
        states = analysis.collect("1p-high", agents, episodes=4, seed=0, num_envs=4)["predator_0"]
        assert states.correction is not None and len(states.correction) == len(states.mode)
        summary = analysis.correction_by_distance(states.distance, states.mode, states.correction)
        used.append(summary["used"])
        shares = [v for v in summary["chase"]["corrected"] + summary["stalk"]["corrected"] if v is not None]
        assert set(shares) == ({0.0} if kind is ResidualPredator else {1.0})
    assert list(used[0]) == [0] and list(used[1]) == [1]
