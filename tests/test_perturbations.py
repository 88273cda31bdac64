"""Perturbed worlds and senses (pursuit_bench/env/perturbations.py), held-out opponents and the
robust command: neutral values change nothing, positive ones change what they should."""

import json
import subprocess
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from cli_helpers import cli_command, run_cli

from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.analysis import robustness
from pursuit_bench.env import task
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.perturbations import Perturbations, PerturbedEnv
from pursuit_bench.env.vector import VectorPursuitEnv
from pursuit_bench.env.world import DAMPING, DT
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey
from pursuit_bench.training.evaluate import evaluate_agents


def scripted(condition: str) -> dict:
    names = CONDITIONS[condition].agent_names
    agents = {n: ScriptedAgent(n, AlwaysChase() if i % 2 else AlwaysStalk()) for i, n in enumerate(names[:-1])}
    return {**agents, names[-1]: ScriptedAgent(names[-1], FleeingPrey())}


def random_actions(rng: np.random.Generator, env: VectorPursuitEnv) -> np.ndarray:
    actions = rng.integers(0, 12, (env.num_envs, env.n_agents, 2))
    actions[..., 0] %= 2
    actions[:, -1, 0] = 0
    return actions


def play(env, steps: int, seed: int = 0) -> list[tuple[np.ndarray, ...]]:
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=7)
    out = [(obs,)]
    for _ in range(steps):
        obs, rewards, terminated, truncated, info = env.step(random_actions(rng, env))
        out.append((obs, rewards, terminated, truncated, info["positions"], info["done"]))
    return out


def test_every_perturbation_at_its_neutral_value_is_the_plain_evaluation_bit_for_bit() -> None:
    plain = play(VectorPursuitEnv(8, "2p-high-shared"), 200)
    # the wrapper with every sense perturbation at its neutral value, and the world's factors at 1 given explicitly
    wrapped = PerturbedEnv(
        VectorPursuitEnv(8, "2p-high-shared", damping_factor=1.0, predator_accel_factor=1.0, prey_accel_factor=1.0),
        Perturbations(obs_noise=0.0, delay=0, act_noise=0.0, obstacles=0),
        seed=3,
    )
    for a, b in zip(plain, play(wrapped, 200), strict=True):
        for x, y in zip(a, b, strict=True):
            assert np.array_equal(x, y)
    agents = scripted("2p-high-shared")
    base = evaluate_agents("2p-high-shared", agents, episodes=24, seed=5, prey_epsilon=None, num_envs=8)
    neutral = evaluate_agents(
        "2p-high-shared", agents, episodes=24, seed=5, prey_epsilon=None, num_envs=8, perturbations=Perturbations()
    )
    assert json.dumps(base) == json.dumps(neutral)


def test_observation_noise_has_the_stated_spread_on_positions_and_velocities_only() -> None:
    sigma = 0.05
    clean = VectorPursuitEnv(64, "2p-high-shared", obstacles=2)  # range readings must stay clean
    noisy = PerturbedEnv(VectorPursuitEnv(64, "2p-high-shared", obstacles=2), Perturbations(obs_noise=sigma), seed=1)
    a, _ = clean.reset(seed=4)
    b, _ = noisy.reset(seed=4)
    moved = task.obs_size(3)
    diff = (b - a)[..., :moved].astype(np.float64)
    assert abs(diff.mean()) < 0.003 and diff.std() == pytest.approx(sigma, rel=0.05)
    assert np.array_equal(a[..., moved:], b[..., moved:])


def test_a_delayed_observation_is_the_one_k_steps_old() -> None:
    k = 3
    clean = play(VectorPursuitEnv(4, "1p-high"), 40)
    delayed = play(PerturbedEnv(VectorPursuitEnv(4, "1p-high"), Perturbations(delay=k), seed=0), 40)
    lengths = np.zeros(4, dtype=int)  # steps into the current episode, per arena
    for t in range(1, 41):
        seen, done = delayed[t][0], clean[t][5]
        lengths = np.where(done, 0, lengths + 1)
        for arena in range(4):
            back = min(k, lengths[arena])  # an episode younger than k shows its first observation
            assert np.array_equal(seen[arena], clean[t - back][0][arena])


def test_action_noise_turns_a_direction_to_a_neighbour_as_often_as_asked() -> None:
    env = VectorPursuitEnv(256, "1p-high")
    taken = []
    original_step = env.step
    env.step = lambda actions: (taken.append(actions.copy()), original_step(actions))[1]  # type: ignore[method-assign]
    noisy = PerturbedEnv(env, Perturbations(act_noise=0.3), seed=2)
    noisy.reset(seed=0)
    chosen = np.zeros((256, 2, 2), dtype=np.int64)
    chosen[..., 1] = 5
    for _ in range(20):
        noisy.step(chosen)
    directions = np.array(taken)[..., 1]
    changed = directions != 5
    assert set(np.unique(directions[changed])) == {4, 6}  # neighbours only
    assert changed.mean() == pytest.approx(0.3, abs=0.02)


@pytest.mark.parametrize(
    ("options", "predator", "prey", "damping"),
    [
        ({"damping_factor": 2.0}, 1.0, 1.0, 2.0),
        ({"predator_accel_factor": 0.5, "prey_accel_factor": 1.5}, 0.5, 1.5, 1.0),
    ],
)
def test_shifted_dynamics_against_a_hand_computation(options, predator, prey, damping) -> None:
    env = VectorPursuitEnv(4, "2p-high-shared", **options)
    ref = VectorPursuitEnv(4, "2p-high-shared")
    env.reset(seed=9)
    ref.reset(seed=9)
    rng = np.random.default_rng(0)
    for _ in range(5):  # some velocity first, away from the walls' influence
        actions = random_actions(rng, env)
        v0 = env.core.world.velocities.copy()
        los = env.core._los.copy()
        env.step(actions)
        acc = task.accelerations(los, actions[:, :-1, 0], actions[..., 1])
        acc[:, :-1] *= predator
        acc[:, -1] *= prey
        expected = (1 - damping * DAMPING) * v0 + acc * DT
        inside = ~env.core.world.positions.__abs__().max(axis=(1, 2)).__ge__(0.9)
        assert np.allclose(env.core.world.velocities[inside], expected[inside], atol=1e-12)


def test_hidden_obstacles_hold_agents_back_and_leave_their_observations_as_trained() -> None:
    env = PerturbedEnv(VectorPursuitEnv(16, "1p-high", obstacles=4), Perturbations(obstacles=4), seed=0)
    obs, _ = env.reset(seed=1)
    assert obs.shape[-1] == task.obs_size(2) == env.obs_size
    rng = np.random.default_rng(1)
    for _ in range(300):
        obs, *_ = env.step(random_actions(rng, env.env))
        centres = env.core.world.obstacles
        gap = np.linalg.norm(env.core.world.positions[:, :, None] - centres[:, None, :, :2], axis=-1)
        assert (gap >= centres[:, None, :, 2] + 0.05 - 1e-9).all()
    agents = scripted("1p-high")
    plain = evaluate_agents("1p-high", agents, episodes=32, seed=0, prey_epsilon=None, num_envs=16)
    hidden = evaluate_agents(
        "1p-high", agents, episodes=32, seed=0, prey_epsilon=None, num_envs=16, perturbations=Perturbations(obstacles=4)
    )
    assert hidden["perturbations"] == {"obstacles": 4} and hidden["panels"] != plain["panels"]


def test_bad_perturbations_are_one_line_errors_naming_the_accepted_ones() -> None:
    with pytest.raises(ValueError, match="obs-noise, delay, act-noise, damping, predator-accel, prey-accel, obstacles"):
        Perturbations.parse(["wind=2"])
    with pytest.raises(ValueError, match="not an integer"):
        Perturbations.parse(["delay=0.5"])
    with pytest.raises(ValueError, match=r"from 0\.0 to 1\.0"):
        Perturbations.parse(["act-noise=1.5"])
    with pytest.raises(ValueError, match="given twice"):
        Perturbations.parse(["delay=1", "delay=2"])
    assert Perturbations.parse(["delay=2", "obs-noise=0.05"]).tag == "obs-noise0.05_delay2"
    code, output = run_cli("eval", "--pretrained", "1p-high", "--perturb", "wind=2")
    assert code == 2 and "obs-noise" in output and "Traceback" not in output and len(output.strip().splitlines()) == 1


def test_cross_play_pairs_each_seeds_predators_with_every_seeds_prey() -> None:
    sources = [
        {"name": f"r{s}", "condition": "1p-high", "kind": "hierarchical", "seed": s, "source": f"r{s}"}
        for s in range(3)
    ]
    jobs = [j for j in robustness._jobs([{**s, "config": _Config()} for s in sources], 10, 0, True) if "|vs|" in j[0]]
    assert sorted((j[1][0], j[1][1]) for j in jobs) == sorted(
        (f"r{i}", f"r{j}") for i in range(3) for j in range(3) if i != j
    )
    done = {f"r{i}|vs|r{j}": {"margin": 10 * i + j, "always_chase": 0.0} for i in range(3) for j in range(3) if i != j}
    done |= {f"r{i}|none": {"margin": 11 * i + 5, "always_chase": 0.0} for i in range(3)}
    result = robustness.summarise(sources, done, 10, 0)["crossplay"]["1p-high"]["hierarchical"]
    assert result["matrix"] == [[5, 1, 2], [10, 16, 12], [20, 21, 27]]  # row: predators' seed, column: prey's
    assert result["gap"]["differences"] == pytest.approx([5 - 1.5, 16 - 11, 27 - 20.5])


class _Config:
    """What the job planner reads of a run's configuration."""

    task_options: ClassVar[dict] = {}


def test_held_out_opponents_play_the_other_runs_prey(tmp_path: Path) -> None:
    for seed in (0, 1):
        code, output = run_cli(
            "train", "--condition", "1p-high", "--seed", str(seed), "--episodes", "6", "--no-record",
            "--out", str(tmp_path / f"r{seed}"),
        )  # fmt: skip
        assert code == 0, output
    code, output = run_cli(
        "eval", str(tmp_path / "r0"), "--episodes", "12", "--no-record", "--opponents", str(tmp_path / "r1")
    )
    assert code == 0, output
    result = json.loads((tmp_path / "r0" / "eval-vs-r1.json").read_text())
    from pursuit_bench.training import runs

    _, mine, _ = runs.described(tmp_path / "r0")
    _, theirs, _ = runs.described(tmp_path / "r1")
    direct = evaluate_agents("1p-high", {**mine, "prey_0": theirs["prey_0"]}, episodes=12, seed=12345)
    assert result["panels"] == direct["panels"]
    other_side = evaluate_agents(
        "1p-high", {"predator_0": theirs["predator_0"], "prey_0": mine["prey_0"]}, episodes=12, seed=12345
    )
    assert result["opponents"]["prey_side"]["prey_check"] == other_side["prey_check"]
    code, output = run_cli("eval", str(tmp_path / "r0"), "--opponents", str(tmp_path / "nothing"))
    assert code == 2 and "--opponents" in output


@pytest.mark.slow
@pytest.mark.long
def test_robust_on_the_shipped_agents_writes_its_files(tmp_path: Path) -> None:
    out = tmp_path / "robust"
    command = cli_command("robust", "--pretrained", "1p-high", "--episodes", "4", "--workers", "2", "--out", str(out))
    finished = subprocess.run(command, capture_output=True, text=True, timeout=600)  # two worker processes
    assert finished.returncode == 0, finished.stderr
    result = json.loads((out / "robust.json").read_text())
    entry = result["summary"]["1p-high"]["hierarchical"]
    assert set(entry) == {"none", *robustness.LADDERS}
    assert all(len(entry[name]) == 3 for name in robustness.LADDERS)
    assert (out / "robust.png").stat().st_size > 20_000 and "obs-noise=0.1" in (out / "robust.md").read_text()
    parts = sorted((out / "robust-parts").glob("*.json"))
    assert len(parts) == 1 + 3 * len(robustness.LADDERS)
    parts[0].unlink()  # a rerun evaluates only what is missing, in this process
    code, output = run_cli("robust", "--pretrained", "1p-high", "--episodes", "4", "--workers", "1", "--out", str(out))
    assert code == 0 and "21 of 22 evaluations" in output and json.loads((out / "robust.json").read_text()) == result
