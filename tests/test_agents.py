"""The agents: what they do, that training helps, that it repeats, and that checkpoints are safe."""

import os
import pickle

import numpy as np
import pytest
import torch

from pursuit_bench.agents import QUICK, DQNLearner, FlatPredator, HierarchicalPredator, Prey, ScriptedAgent
from pursuit_bench.agents.checkpoint import load_agent, save_agent
from pursuit_bench.env import task
from pursuit_bench.rules.navigation import parallel_navigation
from pursuit_bench.rules.policies import AlwaysChase, FleeingPrey
from pursuit_bench.training.evaluate import run_episodes
from pursuit_bench.training.train import TrainConfig, Trainer

pytestmark = pytest.mark.usefixtures("one_thread")


def observations(n: int = 32, agents: int = 2) -> np.ndarray:
    rng = np.random.default_rng(0)
    p = rng.uniform(-0.5, 0.5, size=(n, agents, 2))
    v = rng.uniform(-1, 1, size=(n, agents, 2))
    return task.observations(p, v)


def test_agent_kinds_map_choices_to_env_actions() -> None:
    obs = observations()[:, 0]
    hierarchical = HierarchicalPredator("predator_0", DQNLearner(10, 2, QUICK))
    choices, actions, q, v = hierarchical.decide(obs, explore=False)
    assert set(np.unique(choices)) <= {0, 1}
    np.testing.assert_array_equal(actions[:, 0], choices)  # the network picks the mode ...
    np.testing.assert_array_equal(actions[:, 1], parallel_navigation(obs, choices))  # ... the rule the direction
    np.testing.assert_array_equal(choices, q.argmax(axis=1))
    np.testing.assert_allclose(q.mean(axis=1), v, atol=1e-6)
    flat = FlatPredator("predator_0", DQNLearner(10, 24, QUICK))
    choices, actions, *_ = flat.decide(obs, explore=True, epsilon=1.0)
    np.testing.assert_array_equal(actions[:, 0] * 12 + actions[:, 1], choices)
    prey = Prey("prey_0", DQNLearner(10, 12, QUICK))
    choices, actions, *_ = prey.decide(obs, explore=False)
    np.testing.assert_array_equal(actions, choices)
    assert isinstance(prey.act(obs[0]), (int, np.integer))
    with pytest.raises(ValueError, match="2 actions"):
        HierarchicalPredator("predator_0", DQNLearner(10, 12, QUICK))
    hidden, value = hierarchical.value_features(obs)
    assert hidden.shape == (32, 32) and value.shape == (32,)
    np.testing.assert_allclose(hierarchical.q_values(obs).mean(axis=1), value, atol=1e-5)
    scripted = ScriptedAgent("predator_0", AlwaysChase())
    assert scripted.act_batch(obs).shape == (32, 2) and (scripted.act_batch(obs)[:, 0] == 1).all()


@pytest.mark.slow
def test_hierarchical_predator_learns_to_beat_always_chase() -> None:
    config = TrainConfig(condition="1p-high", prey="scripted", episodes=250, num_envs=8, seed=0)
    trainer = Trainer(config)
    prey = ScriptedAgent("prey_0", FleeingPrey())
    predator = trainer.agents["predator_0"]

    def mean_return(agent) -> float:
        return float(run_episodes("1p-high", {"predator_0": agent, "prey_0": prey}, 200, seed=99).returns[:, 0].mean())

    untrained = mean_return(predator)
    trainer.run()
    trained = mean_return(predator)
    chase = mean_return(ScriptedAgent("predator_0", AlwaysChase()))
    assert trained > chase + 0.2, (trained, chase)
    assert trained > untrained + 0.2, (trained, untrained)


def short_training(seed: int) -> Trainer:
    trainer = Trainer(
        TrainConfig(
            condition="2p-low-shared", episodes=30, num_envs=4, seed=seed, agent=QUICK.replace(learning_starts=64)
        )
    )
    trainer.run()
    return trainer


def test_same_seed_same_weights() -> None:
    a, b, c = short_training(5), short_training(5), short_training(6)
    assert a.agents["predator_0"].learner.updates > 0
    for name in a.agents:
        ga, gb, gc = (t.agents[name] for t in (a, b, c))
        for (key, pa), pb, pc in zip(
            ga.learner.online.state_dict().items(),
            gb.learner.online.state_dict().values(),
            gc.learner.online.state_dict().values(),
            strict=True,
        ):
            assert torch.equal(pa, pb), (name, key)
            assert not torch.equal(pa, pc)


def test_save_load_gives_identical_greedy_actions(tmp_path) -> None:
    trainer = short_training(1)
    agent = trainer.agents["predator_1"]
    path = tmp_path / "agent.pt"
    save_agent(agent, path, condition="2p-low-shared")
    fresh = Trainer(TrainConfig(condition="2p-low-shared", episodes=1, num_envs=4, seed=9))
    other = fresh.agents["predator_1"]
    obs = observations(64, 3)[:, 1]
    assert not np.array_equal(other.q_values(obs), agent.q_values(obs))
    load_agent(other, path, condition="2p-low-shared")
    np.testing.assert_array_equal(other.q_values(obs), agent.q_values(obs))
    np.testing.assert_array_equal(other.act_batch(obs), agent.act_batch(obs))
    assert other.learner.steps == agent.learner.steps
    assert len(other.learner.replay) == len(agent.learner.replay)
    # a checkpoint refuses another condition or another kind of agent
    with pytest.raises(ValueError, match="condition '2p-low-shared', not '2p-high-shared'"):
        load_agent(other, path, condition="2p-high-shared")
    flat = FlatPredator("predator_1", DQNLearner(16, 24, QUICK))
    with pytest.raises(ValueError, match="'hierarchical' agent, not 'flat'"):
        load_agent(flat, path, condition="2p-low-shared")


class Exploit:
    def __init__(self, marker: str) -> None:
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


# the bare pickle is protocol 4, which torch's weights-only reader warns of before refusing it: expected here
@pytest.mark.filterwarnings("ignore:Detected pickle protocol:UserWarning")
def test_a_checkpoint_crafted_to_run_code_does_not(tmp_path) -> None:
    marker = tmp_path / "pwned"
    path = tmp_path / "evil.pt"
    torch.save({"format": "pursuit-bench-checkpoint-1", "agents": Exploit(str(marker))}, path)
    with open(tmp_path / "evil.pkl", "wb") as f:  # the same payload as a bare pickle
        pickle.dump(Exploit(str(marker)), f)
    agent = HierarchicalPredator("predator_0", DQNLearner(10, 2, QUICK))
    for p in (path, tmp_path / "evil.pkl"):
        with pytest.raises(ValueError, match="not a readable pursuit-bench checkpoint"):
            load_agent(agent, p, condition="1p-low")
    assert not marker.exists()
    truncated = tmp_path / "truncated.pt"
    save_agent(agent, truncated, condition="1p-low")
    truncated.write_bytes(truncated.read_bytes()[:100])
    with pytest.raises(ValueError, match=r"truncated\.pt"):
        load_agent(agent, truncated, condition="1p-low")
