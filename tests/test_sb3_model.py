"""A Stable-Baselines3 model as an agent (issue 67): ``eval --agent NAME=MODEL.zip`` and ``score
MODEL.zip``, any algorithm, its actions those of SB3's own loader; wrong files refused in a line."""

import json
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from cli_helpers import run_cli

import pursuit_bench
from pursuit_bench.agents.sb3_model import SB3Policy

sb3 = pytest.importorskip("stable_baselines3")
gymnasium.register_envs(pursuit_bench)


def tiny_model(path: Path, algorithm: str, agent: str, condition: str) -> Path:
    """A model of ``algorithm`` on the single-agent view, trained a few steps (untrained is enough:
    what is tested is that its actions come through as they are)."""
    env = gymnasium.make("pursuit_bench/Pursuit-v0", agent=agent, condition=condition)
    if algorithm == "PPO":
        model = sb3.PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0)
        model.learn(64)
    else:
        model = sb3.DQN("MlpPolicy", env, learning_starts=16, train_freq=8, buffer_size=200, seed=0)
        model.learn(48)
    model.save(path)
    return path.with_suffix(".zip")


def observations(agent: str, condition: str, n: int = 64) -> np.ndarray:
    env = gymnasium.make("pursuit_bench/Pursuit-v0", agent=agent, condition=condition)
    env.reset(seed=3)
    return np.stack([env.observation_space.sample() for _ in range(n)]).astype(np.float32)


@pytest.mark.parametrize(("algorithm", "agent"), [("PPO", "predator_0"), ("DQN", "prey_0")])
def test_the_policy_acts_as_sb3_s_own_loader_s_model(tmp_path: Path, algorithm: str, agent: str) -> None:
    path = tiny_model(tmp_path / "model", algorithm, agent, "1p-high")
    obs = observations(agent, "1p-high")
    expected, _ = getattr(sb3, algorithm).load(path, device="cpu").predict(obs, deterministic=True)
    policy = SB3Policy(path)
    policy.check_role(predator=agent != "prey_0")
    assert np.array_equal(policy.act_batch(obs), expected)
    with pytest.raises(ValueError, match="a predator acts in MultiDiscrete" if agent == "prey_0" else "the prey acts"):
        policy.check_role(predator=agent == "prey_0")


def test_eval_and_score_take_a_model_file(tmp_path: Path) -> None:
    path = tiny_model(tmp_path / "ppo_predator", "PPO", "predator_0", "1p-high")
    out = tmp_path / "eval"
    code, output = run_cli(
        "eval", "--pretrained", "1p-high", "--agent", f"predator_0={path}", "--episodes", "4",
        "--num-envs", "4", "--no-record", "--out", str(out),
    )  # fmt: skip
    assert code == 0, output
    result = json.loads((out / "eval-predator_0.json").read_text())
    assert str(path) in json.dumps(result)
    code, output = run_cli(
        "score", str(path), "--role", "predator", "--conditions", "1p-high,1p-low", "--episodes", "2",
        "--out", str(tmp_path / "score"),
    )  # fmt: skip
    assert code == 0, output
    scored = json.loads((tmp_path / "score" / "score.json").read_text())
    assert {"1p-high", "1p-low"} <= set(json.dumps(scored).replace('"', " ").split())
    code, output = run_cli(
        "score", str(path), "--role", "predator", "--conditions", "2p-low-shared", "--out", str(tmp_path / "no"),
    )  # fmt: skip
    assert (
        code == 2
        and "cannot play 2p-low-shared: it observes 10 numbers; expected 2 predators observing 16 numbers each"
        in output
    )


def test_files_that_are_no_model_are_refused_in_one_line(tmp_path: Path) -> None:
    (tmp_path / "notes.zip").write_text("not a zip")
    prey = tiny_model(tmp_path / "prey", "DQN", "prey_0", "1p-high")
    two = tiny_model(tmp_path / "two", "PPO", "predator_0", "2p-low-shared")
    cases = [
        (f"predator_0={tmp_path / 'missing.zip'}", "no such model file"),
        (f"predator_0={tmp_path / 'notes.zip'}", "not a Stable-Baselines3 model"),
        (f"predator_0={prey}", "a predator acts in MultiDiscrete"),
        (f"predator_0={two}", "the model observes 16 numbers, this agent 10"),
    ]
    for spec, message in cases:
        code, output = run_cli(
            "eval", "--pretrained", "1p-high", "--agent", spec, "--episodes", "2", "--no-record",
            "--out", str(tmp_path / "eval"),
        )  # fmt: skip
        assert code == 2 and message in output and "Traceback" not in output, (spec, output)
        assert len(output.strip().splitlines()) == 1, output
