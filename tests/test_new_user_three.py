"""What a new user hit (the third round): the shipped agents as opponents, prey lines that say
which prey they describe, a prey's outcomes that add up, and mismatches that say what differs."""

import json
from pathlib import Path

import numpy as np
from cli_helpers import run_cli

from pursuit_bench import pretrained
from pursuit_bench.training.evaluate import Episodes, evaluate_agents, prey_outcomes


def test_the_shipped_agents_are_opponents_and_every_prey_line_names_its_prey(tmp_path: Path) -> None:
    out = tmp_path / "shipped"
    args = ["eval", "--pretrained", "2p-high-shared", "--out", str(out), "--episodes", "20", "--no-record"]
    code, output = run_cli(*args, "--opponents", "pretrained:2p-high-individual")
    assert code == 0, output
    result = json.loads((out / "eval-vs-pretrained-2p-high-individual.json").read_text())
    assert result["opponents"]["prey"] == "pretrained:2p-high-individual"
    assert "prey_0 (pretrained:2p-high-individual's learned prey), greedy:" in output
    assert "the evaluated agents' own prey against pretrained:2p-high-individual's predators, greedy:" in output
    code, output = run_cli(*args, "--opponents", "scripted")
    assert code == 0, output
    assert "prey_0: FleeingPrey (scripted)" in output and "learned" not in output
    assert json.loads((out / "eval-vs-scripted.json").read_text())["prey_check"] is None
    code, output = run_cli(*args, "--opponents", "pretrained:9p-nothing")
    assert code == 2 and "pretrained:CONDITION, one of 1p-low" in output


def test_a_mismatch_says_what_differs_and_how_to_train_a_match(tmp_path: Path) -> None:
    run = tmp_path / "r"
    code, output = run_cli("train", "--condition", "1p-high", "--episodes", "2", "--no-record", "--out", str(run))
    assert code == 0, output
    saved = json.loads((run / "config.json").read_text())["train"]
    assert saved["episodes"] == saved["agent"]["episodes"] == 2  # one training length, the run's
    code, output = run_cli("eval", str(run), "--episodes", "4", "--no-record", "--opponents", "pretrained:1p-high")
    assert code == 2, output
    assert "wall features off in the run, on in pretrained:1p-high" in output
    assert "train with --wall-features (the reproduction preset's) to meet pretrained:1p-high" in output
    code, output = run_cli(
        "eval", str(run), "--episodes", "4", "--no-record", "--opponents", "pretrained:2p-low-shared"
    )
    assert code == 2 and "has 1 predators and pretrained:2p-low-shared (2p-low-shared) 2" in output


def test_a_prey_s_outcomes_add_up_to_its_episodes() -> None:
    # five episodes of 300 steps at most: caught on the last step, caught against a wall, the prey
    # into a wall, a predator into a wall, the time limit
    played = Episodes(
        returns=np.zeros((5, 2)),
        lengths=np.array([300, 40, 120, 80, 300]),
        captured=np.array([True, True, False, False, False]),
        chase_fraction=np.zeros((5, 1)),
        distance=np.zeros((5, 2)),
        left_area=np.array([[False, False], [False, True], [False, True], [True, False], [False, False]]),
        collisions=np.zeros((5, 2)),
        contact_steps=np.zeros((5, 2)),
    )
    outcomes = prey_outcomes(played, 300)
    assert (outcomes["captured"], outcomes["left_area"], outcomes["survived"]) == (0.4, 0.2, 0.2)
    config, agents, _ = pretrained.described("1p-high")
    result = evaluate_agents("1p-high", agents, episodes=60, seed=3, **config.protocol)
    for check in result["prey_check"].values():
        assert check["captured"] + check["left_area"] + check["survived"] <= 1.0 + 1e-12  # exclusive


def test_robust_on_an_unreadable_checkpoint_stops_at_once_and_leaves_nothing(tmp_path: Path) -> None:
    run = tmp_path / "r"
    code, output = run_cli("train", "--condition", "1p-low", "--episodes", "2", "--no-record", "--out", str(run))
    assert code == 0, output
    checkpoint = run / "checkpoint.pt"
    checkpoint.write_bytes(checkpoint.read_bytes()[:1000])
    before = sorted(p.name for p in run.iterdir())
    code, output = run_cli("robust", str(run), "--episodes", "2", "--workers", "2")
    assert code == 2 and "not a readable pursuit-bench checkpoint (truncated or corrupted)" in output
    assert "evaluations" not in output and sorted(p.name for p in run.iterdir()) == before


def test_the_batched_env_s_action_space_is_what_step_takes() -> None:
    from pursuit_bench import VectorPursuitEnv

    for continuous in (False, True):
        env = VectorPursuitEnv(5, "2p-high-shared", continuous=continuous)
        env.action_space.seed(0)
        env.reset(seed=0)
        for _ in range(40):
            action = env.action_space.sample()
            assert action.shape == (5, 3, 2)
            _, _, _, _, info = env.step(action)
        assert info["final_obs"].shape == (5, 3, env.obs_size)


def test_the_eta_waits_for_a_tenth_of_the_work_and_follows_the_recent_rate(monkeypatch) -> None:
    import io

    from pursuit_bench.cli import progress

    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    log = io.StringIO()
    bar = progress.Progress("train", 1000, 0, lambda: "", every_episodes=50, file=log, eta=True)
    for done in range(50, 1001, 50):
        clock[0] += 1.0 if done <= 100 else 10.0  # short episodes first, then ten times longer ones
        bar.update(done)
    lines = log.getvalue().splitlines()
    assert lines[0].endswith("ETA after 10% | ")  # 50 of 1000
    # at 500: 5 episodes a second lately, so 500 left take 100 s (the average since the start, 6.1 a
    # second, would say 82 s)
    assert "6.1 episodes/s | ETA 00:01:40" in lines[9]


def test_every_refusal_is_one_line_click_s_own_too() -> None:
    for args in (["eval", "--episodes", "x"], ["nosuch"], ["train", "--condition", "9p"], ["eval"]):
        code, output = run_cli(*args)
        assert code == 2 and output.startswith("Error: ") and len(output.strip().splitlines()) == 1, output
        assert "--help')" in output
