"""The field's MARL algorithms on pursuit-bench: the joint-action view, team files, BenchMARL's task
and ``pursuit-bench marl train`` (the BenchMARL parts skipped where the marl extra is absent)."""

import itertools
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import torch
from cli_helpers import cli_command, run_cli

import pursuit_bench
from pursuit_bench.agents import team_file
from pursuit_bench.agents.external import replaced
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.joint_actions import N_JOINT, JointActionParallelEnv, split

# ---------------------------------------------------------------- joint actions


def test_a_joint_action_is_mode_times_twelve_plus_direction() -> None:
    pairs = split(np.arange(N_JOINT))
    assert [tuple(p) for p in pairs.tolist()] == [(a // 12, a % 12) for a in range(24)]
    for bad in (np.array(24), np.array(-1), np.array(1.5)):
        with pytest.raises(ValueError, match=r"0\.\.23"):
            split(bad)


def test_the_joint_action_view_plays_the_env_s_own_episodes() -> None:
    plain, joint = (
        pursuit_bench.parallel_env("2p-high-shared"),
        JointActionParallelEnv(pursuit_bench.parallel_env("2p-high-shared")),
    )
    assert joint.action_space("predator_1").n == 24 and joint.action_space("prey_0").n == 12
    rng = np.random.default_rng(3)
    a, _ = plain.reset(seed=7)
    b, _ = joint.reset(seed=7)
    steps = 0
    while plain.agents:
        steps += 1
        for name in a:
            np.testing.assert_array_equal(a[name], b[name])
        flat = {n: int(rng.integers(24)) for n in ("predator_0", "predator_1")} | {"prey_0": int(rng.integers(12))}
        pairs = {n: np.array(divmod(v, 12), dtype=np.int64) for n, v in flat.items() if n != "prey_0"}
        a, ra, ta, ua, _ = plain.step(pairs | {"prey_0": flat["prey_0"]})
        b, rb, tb, ub, _ = joint.step(flat)
        assert (ra, ta, ua) == (rb, tb, ub)
    assert not joint.agents and steps > 1
    with pytest.raises(ValueError, match="continuous=False"):
        JointActionParallelEnv(pursuit_bench.parallel_env("1p-high", continuous=True))


# ---------------------------------------------------------------- team files


def _random_team(path: Path, role: str, agents: list[str], observes: int, seed: int = 0) -> dict:
    generator = torch.Generator().manual_seed(seed)
    outputs = 24 if role == "predator" else 12
    sizes = [observes, 32, 32, outputs]
    layers = {
        agent: [
            (torch.randn(o, i, generator=generator), torch.randn(o, generator=generator))
            for i, o in itertools.pairwise(sizes)
        ]
        for agent in agents
    }
    team_file.write(path, layers, {"role": role, "condition": "2p-low-shared", "activation": "tanh", "algorithm": "x"})
    return layers


def naive_greedy(layers: list, obs: np.ndarray) -> np.ndarray:
    """The reference forward pass: float64 numpy, tanh between the layers, the largest score."""
    x = obs.astype(np.float64)
    for k, (w, b) in enumerate(layers):
        x = x @ w.double().numpy().T + b.double().numpy()
        x = np.tanh(x) if k < len(layers) - 1 else x
    return x.argmax(axis=1)


def test_a_team_file_acts_as_its_networks_do(tmp_path: Path) -> None:
    path = tmp_path / "team.safetensors"
    layers = _random_team(path, "predator", ["predator_0", "predator_1"], 16)
    team = team_file.Team(path)
    assert (team.role, team.observes, team.agents) == ("predator", 16, ["predator_0", "predator_1"])
    obs = np.random.default_rng(0).uniform(-1, 1, (500, 16)).astype(np.float32)
    for slot, name in enumerate(team.agents):
        pairs = team.member(slot).act_batch(obs)
        expected = naive_greedy(layers[name], obs)
        np.testing.assert_array_equal(pairs[:, 0] * 12 + pairs[:, 1], expected)
    with pytest.raises(ValueError, match="another number of agents"):
        team.member(0).act_batch(obs[:, :10])
    with pytest.raises(ValueError, match="no agent for slot 2"):
        team.member(2)


def test_a_team_file_is_refused_in_one_line_when_it_is_not_one(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="no such team file"):
        team_file.Team(tmp_path / "missing.safetensors")
    (tmp_path / "junk.safetensors").write_bytes(b"not safetensors")
    with pytest.raises(ValueError, match="not a readable safetensors file"):
        team_file.Team(tmp_path / "junk.safetensors")
    from safetensors.torch import save_file

    save_file({"w": torch.zeros(2)}, str(tmp_path / "other.safetensors"), metadata={"format": "something else"})
    with pytest.raises(ValueError, match="not a pursuit-bench team file"):
        team_file.Team(tmp_path / "other.safetensors")
    header = {"format": team_file.FORMAT, "role": "prey", "activation": "tanh"}
    save_file({"w": torch.zeros(2)}, str(tmp_path / "no-agents.safetensors"), metadata=header)
    with pytest.raises(ValueError, match="names its agents"):
        team_file.Team(tmp_path / "no-agents.safetensors")
    no_bias = {"prey_0.0.weight": torch.zeros(12, 10)}
    save_file(no_bias, str(tmp_path / "no-bias.safetensors"), metadata=header | {"agents": '["prey_0"]'})
    with pytest.raises(ValueError, match="with its bias"):
        team_file.Team(tmp_path / "no-bias.safetensors")


def test_eval_and_score_play_a_team_file_in_its_slots_and_refuse_the_other_role(tmp_path: Path) -> None:
    predators, prey = tmp_path / "predator.safetensors", tmp_path / "prey.safetensors"
    _random_team(predators, "predator", ["predator_0", "predator_1"], 16)
    _random_team(prey, "prey", ["prey_0"], 16, seed=1)
    agents = replaced(
        dict.fromkeys(("predator_0", "predator_1", "prey_0")), {"predator_1": str(predators), "prey_0": str(prey)}
    )
    obs = np.random.default_rng(1).uniform(-1, 1, (50, 16)).astype(np.float32)
    np.testing.assert_array_equal(
        agents["predator_1"].act_batch(obs), team_file.Team(predators).member(1).act_batch(obs)
    )
    with pytest.raises(ValueError, match="a prey team; it cannot play the predator"):
        replaced(dict.fromkeys(("predator_0", "predator_1", "prey_0")), {"predator_0": str(prey)})
    code, out = run_cli("score", str(predators), "--role", "predator", "--episodes", "2", "--out", str(tmp_path / "s"))
    assert code == 0, out
    scored = json.loads((tmp_path / "s" / "score.json").read_text())
    assert sorted(scored["conditions"]) == sorted(c for c in CONDITIONS if CONDITIONS[c].n_predators == 2)
    code, out = run_cli("score", str(prey), "--role", "predator", "--out", str(tmp_path / "t"))
    assert code == 2 and "cannot play the predator" in out and "Traceback" not in out


# ---------------------------------------------------------------- BenchMARL


def test_every_condition_is_a_benchmarl_task() -> None:
    pytest.importorskip("benchmarl", reason="the marl extra is not installed (pip install -e '.[marl]')")
    from pursuit_bench.marl.benchmarl_task import PursuitTask, condition_of

    assert [condition_of(t.name) for t in PursuitTask] == list(CONDITIONS)
    task = PursuitTask.PURSUIT_3P_HIGH_INDIVIDUAL.get_task(config={})
    env = task.get_env_fun(1, False, 0, "cpu")()
    assert task.group_map(env) == {"predator": ["predator_0", "predator_1", "predator_2"], "prey": ["prey_0"]}
    assert task.observation_spec(env)["predator", "observation"].shape == (3, 22)
    assert task.state_spec(env)["state"].shape == (16,)
    assert task.action_spec(env)["predator", "action"].space.n == 24
    rollout = env.rollout(3)
    assert rollout["next", "predator", "reward"].shape == (1, 3, 3, 1)


@pytest.mark.slow
def test_marl_train_writes_teams_that_act_as_benchmarl_s_policies_and_resumes(tmp_path: Path) -> None:
    pytest.importorskip("benchmarl", reason="the marl extra is not installed (pip install -e '.[marl]')")
    out = tmp_path / "iql"
    command = cli_command(
        "marl", "train", "--algorithm", "iql", "--condition", "2p-low-shared", "--frames", "200",
        "--set", "off_policy_n_optimizer_steps=2", "--out", str(out),
    )  # fmt: skip
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    summary = json.loads((out / "marl.json").read_text())
    assert summary["export_disagreements"] == {"predator": 0, "prey": 0} and summary["frames"] == 200
    assert team_file.Team(out / "predator.safetensors").header["algorithm"] == "iql"
    again = subprocess.run(command, capture_output=True, text=True, timeout=600)  # finished: nothing to do
    assert again.returncode == 0, again.stderr[-2000:]
    assert json.loads((out / "marl.json").read_text()) == summary
    assert len(list((out / "benchmarl").iterdir())) == 1  # no second experiment was started
    (out / "marl.json").unlink()  # as if stopped after its last checkpoint: resumed from it, not from scratch
    resumed = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert len(list((out / "benchmarl").iterdir())) == 1
    assert json.loads((out / "marl.json").read_text())["export_disagreements"] == {"predator": 0, "prey": 0}
    other = subprocess.run(
        [*command[:-6], "--algorithm", "ippo", *command[-6:]], capture_output=True, text=True, timeout=600
    )
    assert other.returncode == 2 and "holds another run" in other.stderr


def test_marl_train_refuses_a_setting_it_owns_or_does_not_know(tmp_path: Path) -> None:
    pytest.importorskip("benchmarl", reason="the marl extra is not installed (pip install -e '.[marl]')")
    base = ["marl", "train", "--algorithm", "ippo", "--condition", "1p-high", "--frames", "10", "--out", str(tmp_path)]
    refused = {
        "max_n_frames=5": "not an experiment setting",
        "lr=fast": "expected a value of type float",
        "nothing": "expected KEY=VALUE",
        "adam_extra_kwargs=x": "a dict setting",
        "no_such=1": "not an experiment setting",
    }
    for setting, said in refused.items():
        code, out = run_cli(*base, "--set", setting)
        assert code == 2 and said in out and "Traceback" not in out, out
