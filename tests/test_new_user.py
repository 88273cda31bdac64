"""What a new user hit (the second round): outside agents' errors, working-directory imports,
folders left by a failed evaluation, resume targets, stale evaluations, and errors in the words
of the options typed."""

import json
import subprocess
import textwrap
from pathlib import Path

import pytest
from cli_helpers import cli_command, run_cli

AGENTS = textwrap.dedent(
    """
    import numpy as np


    def raising_factory():
        raise RuntimeError("no model file here")


    class _Agent:
        def __init__(self, act):
            self.act_batch = act


    def wrong_shape():
        return _Agent(lambda obs: np.zeros(len(obs)))  # a predator needs (mode, direction)


    def raising_act():
        def act(obs):
            raise KeyError("weights missing")
        return _Agent(act)


    def out_of_range():
        return _Agent(lambda obs: np.tile([0, 12], (len(obs), 1)))


    def fractional():
        return _Agent(lambda obs: np.full((len(obs), 2), 0.5))


    def away_prey():
        return _Agent(lambda obs: np.full(len(obs), 6))
    """
)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("predator_0=user_agents:raising_factory", "the factory raised RuntimeError: no model file here"),
        ("predator_0=user_agents:wrong_shape", "act_batch returned shape (12,); expected (mode, direction)"),
        ("predator_0=user_agents:raising_act", "act_batch raised KeyError: 'weights missing'"),
        ("predator_0=user_agents:out_of_range", "out of range; expected mode 0 or 1 and direction 0..11"),
        ("predator_0=user_agents:fractional", "non-integer actions"),
    ],
)
def test_every_error_an_outside_agent_raises_is_one_line_and_leaves_no_folder(
    tmp_path: Path, monkeypatch, spec: str, message: str
) -> None:
    (tmp_path / "user_agents.py").write_text(AGENTS)
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "results"
    args = ["eval", "--pretrained", "1p-low", "--out", str(out), "--episodes", "4", "--num-envs", "4", "--no-record"]
    code, output = run_cli(*args, "--agent", spec)
    assert code == 2 and message in output and len(output.strip().splitlines()) == 1, output
    assert spec.split("=")[0] in output or "factory" in output
    assert not out.exists()  # the folder this evaluation made is gone, lock and all


def test_a_repeated_agent_is_refused_and_an_outside_prey_is_named(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "user_agents.py").write_text(AGENTS)
    monkeypatch.syspath_prepend(str(tmp_path))
    out = tmp_path / "results"
    args = ["eval", "--pretrained", "1p-low", "--out", str(out), "--episodes", "4", "--num-envs", "4", "--no-record"]
    code, output = run_cli(*args, "--agent", "prey_0=user_agents:away_prey", "--agent", "prey_0=user_agents:away_prey")
    assert code == 2 and "--agent prey_0: given twice" in output
    code, output = run_cli(*args, "--agent", "prey_0=user_agents:away_prey")
    assert code == 0, output
    result = json.loads((out / "eval-prey_0.json").read_text())
    assert result["prey_kind"] == "external (user_agents:away_prey)"
    assert "prey_0 (external (user_agents:away_prey)), greedy" in output


@pytest.mark.slow
def test_an_outside_agent_is_imported_from_the_working_directory(tmp_path: Path) -> None:
    (tmp_path / "user_agents.py").write_text(AGENTS)
    command = cli_command(
        "eval", "--pretrained", "1p-low", "--episodes", "4", "--num-envs", "4", "--no-record",
        "--agent", "prey_0=user_agents:away_prey",
    )  # fmt: skip
    done = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "runs" / "pretrained-1p-low" / "eval-prey_0.json").exists()


def test_resume_targets_and_stale_evaluations(tmp_path: Path) -> None:
    run = tmp_path / "run"
    code, output = run_cli(
        "train",
        "--condition",
        "1p-high",
        "--episodes",
        "8",
        "--checkpoint-every",
        "4",
        "--no-record",
        "--out",
        str(run),
    )
    assert code == 0, output
    code, output = run_cli("train", "--out", str(run), "--resume", "--episodes", "4")
    assert code == 2 and "--episodes 4" in output and "already trained 8" in output, output
    assert json.loads((run / "config.json").read_text())["train"]["episodes"] == 8  # untouched
    code, output = run_cli("eval", str(run), "--episodes", "4", "--no-record")
    assert code == 0, output
    code, output = run_cli("report", str(run))
    assert code == 0 and "stale," not in output
    code, output = run_cli("train", "--out", str(run), "--resume", "--episodes", "12", "--no-record")
    assert code == 0, output
    code, output = run_cli("report", str(run))
    assert "eval.json: stale, evaluated after 8 episodes; the run has trained 12" in output, output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["train", "--learning-rate", "-1", "--out", "OUT"], "--learning-rate -1.0: expected"),
        (
            ["sweep", "--keep-checkpoints", "500", "--episodes", "10", "--out", "OUT"],
            "--keep-checkpoints 500: expected",
        ),
        (["eval", "FILE"], "FILE: a file, not a run folder"),
        (["report", "MISSING"], "MISSING: no such folder"),
    ],
)
def test_errors_speak_of_what_was_typed(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "FILE").write_text("not a run")
    paths = {"OUT": str(tmp_path / "out"), "FILE": str(tmp_path / "FILE"), "MISSING": str(tmp_path / "MISSING")}
    code, output = run_cli(*[paths.get(a, a) for a in args])
    expected = message
    for name, path in paths.items():
        expected = expected.replace(name, path) if message.startswith(name) else expected
    assert code == 2 and expected in output and len(output.strip().splitlines()) == 1, output
