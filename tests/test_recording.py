"""Recordings read back with Rerun's own reader and checked against the env."""

import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
import rerun
import rerun.chunk as rc

from pursuit_bench import parallel_env
from pursuit_bench.agents import QUICK, DQNLearner, HierarchicalPredator, ScriptedAgent
from pursuit_bench.rules.navigation import parallel_navigation
from pursuit_bench.rules.policies import FleeingPrey
from pursuit_bench.training.evaluate import run_episodes
from pursuit_bench.training.train import TrainConfig, Trainer
from pursuit_bench.trajectories.recording import RecordEpisodes, Recorder

NAMES = ["predator_0", "predator_1", "prey_0"]


class CloseChaser:
    """Chases within 0.3 of the prey and stalks beyond: a predator whose mode switches."""

    def act_batch(self, obs, *, explore=False, epsilon=None):
        obs = np.asarray(obs)
        mode = (np.hypot(obs[:, 6], obs[:, 7]) < 0.3).astype(np.int64)
        return np.stack([mode, parallel_navigation(obs, mode)], axis=-1)


def actors() -> dict:
    learner = DQNLearner(16, 2, QUICK, seed=4)
    return {
        "predator_0": CloseChaser(),
        "predator_1": HierarchicalPredator("predator_1", learner),
        "prey_0": ScriptedAgent("prey_0", FleeingPrey()),
    }


def expected_episodes(seed: int, episodes: int) -> list[dict]:
    """The same episodes replayed in the PettingZoo env: positions, modes, rewards."""
    env = parallel_env("2p-high-shared")
    env.np_random = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])  # arena 0's generator
    agents = actors()
    result = []
    for _ in range(episodes):
        obs, _ = env.reset()
        positions, modes, rewards = [env.state().reshape(3, 4)[:, :2]], [], []
        while env.agents:
            actions = {a: np.asarray(agents[a].act_batch(obs[a][None]))[0] for a in env.agents}
            modes.append([actions["predator_0"][0], actions["predator_1"][0]])
            obs, reward, *_ = env.step({a: (int(v) if a == "prey_0" else v) for a, v in actions.items()})
            positions.append(env.state().reshape(3, 4)[:, :2])
            rewards.append([reward[a] for a in NAMES])
        result.append({"positions": np.array(positions), "modes": np.array(modes), "rewards": np.array(rewards)})
    return result


def read_back(path: Path) -> dict[str, list]:
    """Every non-static row per entity path, in file order: (episode, step, value)."""
    rows: dict[str, list] = defaultdict(list)
    for chunk in rc.RrdReader(path).store().stream():
        batch = chunk.to_record_batch()
        path_name = str(chunk.entity_path)
        if chunk.is_static:
            rows[path_name].append(("static", None, batch.schema.names))
            continue
        columns = [n for n in batch.schema.names if ":" in n]
        values = [batch.column(c).to_pylist() for c in columns]
        episodes, steps = batch.column("episode").to_pylist(), batch.column("step").to_pylist()
        for r, (episode, step) in enumerate(zip(episodes, steps, strict=True)):
            rows[path_name].append((episode, step, {c: v[r] for c, v in zip(columns, values, strict=True)}))
    return rows


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[Path, object]:
    path = tmp_path_factory.mktemp("rec") / "eval.rrd"
    with Recorder(path, NAMES, {"condition": "2p-high-shared"}) as recorder:
        episodes = run_episodes("2p-high-shared", actors(), 6, seed=5, num_envs=1, recorder=recorder)
    return path, episodes


def test_entities_and_blueprint(recording) -> None:
    path, _ = recording
    rows = read_back(path)
    expected = {"/arena/walls", "/events", "/config"}
    for name in NAMES:
        expected |= {f"/arena/agents/{name}", f"/arena/trails/{name}", f"/rewards/{name}", f"/returns/{name}"}
    expected |= {"/modes/predator_0", "/modes/predator_1", "/values/predator_1/q_stalk", "/values/predator_1/q_chase"}
    expected |= {"/values/predator_1/v"}
    assert expected <= set(rows), expected - set(rows)
    assert "/values/predator_0/v" not in rows  # a scripted predator has no values
    assert rc.RrdReader(path).blueprints(), "no default blueprint in the file"
    verify = subprocess.run([sys.executable, "-m", "rerun", "rrd", "verify", str(path)], capture_output=True, text=True)
    assert verify.returncode == 0, verify.stdout + verify.stderr


def test_trajectories_modes_and_rewards_match_the_env(recording) -> None:
    path, episodes = recording
    rows = read_back(path)
    expected = expected_episodes(5, 6)
    for k, exp in enumerate(expected, start=1):
        for i, name in enumerate(NAMES):
            got = np.array([v["Points2D:positions"][0] for e, s, v in rows[f"/arena/agents/{name}"] if e == k])
            np.testing.assert_allclose(got, exp["positions"][:, i], atol=1e-6)  # stored as float32
            trails = [v["LineStrips2D:strips"][0] for e, s, v in rows[f"/arena/trails/{name}"] if e == k]
            assert len(trails) == len(got)
            for t, trail in enumerate(trails):  # the last 15 positions up to each step
                np.testing.assert_allclose(trail, got[max(0, t - 14) : t + 1], atol=1e-6)
            rewards = [v["Scalars:scalars"][0] for e, s, v in rows[f"/rewards/{name}"] if e == k]
            np.testing.assert_allclose(rewards, exp["rewards"][:, i], atol=1e-6)
            assert sum(rewards) == pytest.approx(episodes.returns[k - 1, i])
        for j, name in enumerate(NAMES[:2]):
            modes = exp["modes"][:, j]
            switches = [0] + [t for t in range(1, len(modes)) if modes[t] != modes[t - 1]]
            logged = [(s, v["StateChange:state"][0]) for e, s, v in rows[f"/modes/{name}"] if e == k]
            assert logged == [(t, ("stalk", "chase")[modes[t]]) for t in switches]
        texts = [v["TextLog:text"][0] for e, s, v in rows["/events"] if e == k]
        n_switches = sum(len([t for t in range(1, len(m)) if m[t] != m[t - 1]]) for m in exp["modes"].T)
        assert sum("switches to" in t for t in texts) == n_switches
    assert any("switches to" in v["TextLog:text"][0] for _, _, v in rows["/events"])  # the test saw switches


def test_no_rerun_call_when_recording_is_off(monkeypatch) -> None:
    def forbidden(*args, **kwargs):
        raise AssertionError("a Rerun call was made with recording off")

    for name in ("RecordingStream", "log", "send_columns", "init", "save", "set_time"):
        monkeypatch.setattr(rerun, name, forbidden)
    monkeypatch.setattr("pursuit_bench.trajectories.recording.rr", rerun)
    Trainer(TrainConfig(condition="1p-low", episodes=5, num_envs=2)).run()
    run_episodes("1p-low", {"predator_0": CloseChaser(), "prey_0": ScriptedAgent("prey_0", FleeingPrey())}, 3, seed=0)


def test_the_env_wrapper_records_every_episode(tmp_path: Path) -> None:
    env = RecordEpisodes(parallel_env("1p-low", max_steps=40), tmp_path / "env.rrd")
    states = []
    for episode in range(2):
        env.reset(seed=episode)
        states.append([env.unwrapped.state().reshape(2, 4)[:, :2].copy()])
        while env.agents:
            env.step({"predator_0": np.array([0, 1]), "prey_0": 6})
            states[-1].append(env.unwrapped.state().reshape(2, 4)[:, :2].copy())
    env.close()
    rows = read_back(tmp_path / "env.rrd")
    for k, expected in enumerate(states, start=1):
        got = np.array([v["Points2D:positions"][0] for e, s, v in rows["/arena/agents/prey_0"] if e == k])
        np.testing.assert_allclose(got, np.array(expected)[:, 1], atol=1e-6)
