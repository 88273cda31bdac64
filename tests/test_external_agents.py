"""Other people's agents evaluated by the paper's protocol: `eval --agent NAME=MODULE:FACTORY`."""

import json
import textwrap
from pathlib import Path

from cli_helpers import run_cli

FACTORIES = textwrap.dedent(
    '''
    import gymnasium
    import numpy as np
    from stable_baselines3 import PPO

    import pursuit_bench  # registers the env


    def ppo_predator():
        """A small Stable-Baselines3 model, trained a few hundred steps, behind act()."""
        env = gymnasium.make("pursuit_bench/Pursuit-v0", agent="predator_0", condition="1p-low")
        model = PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
        model.learn(128)

        class Agent:
            def act(self, observation):
                return model.predict(observation, deterministic=True)[0]

        return Agent()


    def straight_prey():
        class Prey:
            def act_batch(self, observations):
                return np.full(len(observations), 6)  # always directly away from the predator

        return Prey()
    '''
)


def test_a_stable_baselines3_agent_is_evaluated_like_a_trained_one(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "my_agents.py").write_text(FACTORIES)
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "eval"
    args = ["eval", "--pretrained", "1p-low", "--out", str(out), "--episodes", "6", "--num-envs", "3", "--no-record"]
    code, output = run_cli(
        *args, "--agent", "predator_0=my_agents:ppo_predator", "--agent", "prey_0=my_agents:straight_prey"
    )
    assert code == 0, output
    result = json.loads((out / "eval-predator_0-prey_0.json").read_text())
    assert result["predator_kind"] == "external (my_agents:ppo_predator)"
    assert result["external_agents"] == {"predator_0": "my_agents:ppo_predator", "prey_0": "my_agents:straight_prey"}
    assert result["protocol"]["prey_epsilon"] is None  # an external prey acts as it is: no ε of ours
    panel = result["panels"][0]
    assert set(panel["episode_returns"]) == {"trained", "always_chase", "always_stalk"}
    assert len(panel["episode_returns"]["trained"]) == 6 and "fleeing_prey" in result["prey_check"]
    assert (out / "eval-predator_0-prey_0.png").exists() and not (out / "eval.json").exists()


def test_a_bad_factory_is_a_one_line_error(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.syspath_prepend(str(tmp_path))
    (tmp_path / "broken.py").write_text("def not_an_agent():\n    return 42\n")
    base = ["eval", "--pretrained", "1p-low", "--out", str(tmp_path / "e"), "--episodes", "2"]
    for spec, message in [
        ("predator_0=nowhere_module:make", "cannot import 'nowhere_module'"),
        ("predator_0=broken:missing", "broken has no callable 'missing'"),
        ("predator_0=broken:not_an_agent", "returned int, which has neither act nor act_batch"),
        ("predator_7=broken:not_an_agent", "no such agent here"),
        ("predator_0", "expected NAME=MODULE:FACTORY"),
    ]:
        code, output = run_cli(*base, "--agent", spec)
        assert code == 2 and message in output and len(output.strip().splitlines()) == 1, (spec, output)
