"""Run folders under failure: bad input, signals, a second process, resuming, recordings."""

import functools
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import rerun.chunk as rc
import torch
from cli_helpers import cli_command, lines, run_cli, wait_for, wait_until

import pursuit_bench
from pursuit_bench.training import runs
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.trajectories.recording import TRAIL_ROWS_PER_CHUNK, EpisodeTrace, Recorder

TINY = ["--num-envs", "4", "--learning-starts", "32", "--batch-size", "16", "--checkpoint-every", "5"]


def train_tiny(out: Path, *extra: str, episodes: int = 10) -> str:
    code, output = run_cli(
        "train", "--condition", "1p-low", "--out", str(out), "--episodes", str(episodes), *TINY, *extra
    )
    assert code == 0, output
    return output


def recording_ids(path: Path) -> set[str]:
    return {entry.recording_id for entry in rc.RrdReader(path).recordings()}


def test_a_negative_seed_is_one_line_and_leaves_no_folder(tmp_path: Path) -> None:
    out = tmp_path / "run"
    code, output = run_cli("train", "--seed", "-1", "--out", str(out))
    assert code == 2 and "-1 is not in the range x>=0" in output and "Traceback" not in output
    assert not out.exists()
    code, output = run_cli("eval", str(out), "--seed", "-3")
    assert code == 2 and "-3 is not in the range" in output


def test_a_failure_before_the_first_checkpoint_leaves_no_folder(tmp_path: Path, monkeypatch) -> None:
    def broken(*args, **kwargs):
        raise RuntimeError("the arenas could not be built")

    monkeypatch.setattr("pursuit_bench.training.train.Trainer.__init__", broken)
    out = tmp_path / "run"
    code, _ = run_cli("train", "--condition", "1p-low", "--out", str(out), *TINY)
    assert code == 1 and not out.exists()


def test_a_run_that_never_reached_a_checkpoint_is_taken_by_a_rerun_or_a_resume(tmp_path: Path) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--no-record")
    (out / "checkpoint.pt").unlink()  # as if killed before its first checkpoint
    train_tiny(out, "--no-record", "--seed", "4")  # a plain re-run, another seed: accepted
    assert runs.read_config(out)[0].seed == 4
    (out / "checkpoint.pt").unlink()
    code, output = run_cli("train", "--out", str(out), "--resume", "--no-record")
    assert code == 0 and "no checkpoint yet" in output, output
    assert len((out / "metrics.jsonl").read_text().splitlines()) == 10


def test_resume_alone_takes_the_saved_configuration(tmp_path: Path) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--record-every", "2", "--learning-rate", "0.0005", episodes=8)
    before = json.loads((out / "config.json").read_text())
    code, output = run_cli("train", "--out", str(out), "--resume")
    assert code == 0 and "nothing to do" in output, output
    assert json.loads((out / "config.json").read_text()) == before  # target kept, not the preset's
    assert sorted(p.name for p in out.glob("*.rrd")) == ["train.rrd"]  # no empty piece

    code, output = run_cli("train", "--out", str(out), "--resume", "--learning-rate", "0.001")
    assert code == 2 and "--learning-rate 0.001 disagrees with the run's 0.0005" in output, output
    code, output = run_cli("train", "--out", str(out), "--resume", "--condition", "1p-high")
    assert code == 2 and "--condition 1p-high disagrees with the run's 1p-low" in output
    code, output = run_cli("train", "--out", str(out), "--resume", "--physics", "numpy")
    assert code == 2 and "--physics numpy disagrees with the run's pymunk" in output
    code, output = run_cli("train", "--out", str(out), "--resume", "--physics", "pymunk", "--seed", "0")
    assert code == 0 and "nothing to do" in output, output

    code, output = run_cli("train", "--out", str(out), "--resume", "--episodes", "14", "--learning-rate", "0.0005")
    assert code == 0 and "extending the run from 8 to 14 episodes" in output, output
    # not a terminal: progress comes as lines with every agent's return, the capture rate and ε
    assert "episode 14/14 (100%)" in output and "return predator_0 " in output and "prey_0 " in output
    assert "capture " in output and "ε " in output
    assert runs.read_config(out)[0].episodes == 14
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert [r["episode"] for r in rows] == list(range(1, 15))
    pieces = runs.recordings(out)
    assert [p.name for p in pieces] == ["train.rrd", "train.resume1.rrd"]
    assert len(recording_ids(pieces[0]) | recording_ids(pieces[1])) == 1  # one recording in two files


def test_sigterm_during_training_checkpoints_and_exits_143(tmp_path: Path, processes) -> None:
    out = tmp_path / "run"
    process = processes(cli_command("train", "--condition", "1p-low", "--out", str(out), "--episodes", "100000"))
    wait_until(lambda: lines(out / "metrics.jsonl") >= 20, "20 episodes trained")
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 143, stderr
    assert "SIGTERM: stopped at episode" in stderr and "Traceback" not in stderr
    done = runs.load_checkpoint(out)["episodes_done"]
    assert done == len((out / "metrics.jsonl").read_text().splitlines())
    verify = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(out / "train.rrd")], capture_output=True
    )
    assert verify.returncode == 0, verify.stderr


def test_a_second_process_cannot_use_a_busy_folder(tmp_path: Path) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--no-record")
    config = (out / "config.json").read_bytes()
    with runs.locked(out):  # as a running `train` holds it
        code, output = run_cli("train", "--condition", "1p-low", "--out", str(out), "--force", "--seed", "9", *TINY)
        assert code == 2 and "in use by another pursuit-bench process" in output, output
        assert len(output.strip().splitlines()) == 1
        code, output = run_cli("eval", str(out), "--episodes", "4")
        assert code == 2 and "in use" in output
    assert (out / "config.json").read_bytes() == config
    code, output = run_cli("eval", str(out), "--episodes", "4", "--no-record")
    assert code == 0, output  # released
    assert not (out / runs.LOCK).exists()  # and the holder removed its lock file as it left (issue 67)


def test_the_lock_file_goes_with_its_holder_and_a_removed_one_is_not_held(tmp_path: Path, monkeypatch) -> None:
    """The holder removes ``.lock`` on leaving; one killed outright leaves it, and it blocks no
    one. A process that opened ``.lock`` just before its holder removed it locks a file no other
    process will open: it must see that and lock the new one, or two would hold the folder."""
    import fcntl
    import os

    from pursuit_bench.io import files

    with runs.locked(tmp_path):
        assert (tmp_path / runs.LOCK).read_text() == f"{os.getpid()}\n"
    assert list(tmp_path.iterdir()) == []
    (tmp_path / runs.LOCK).write_text("12345\n")  # left by a process killed outright
    with runs.locked(tmp_path):
        pass
    assert list(tmp_path.iterdir()) == []

    opened, real_open = [], os.open

    def open_then_removed(path, *args):  # the last holder removes the file just after it is opened
        fd = real_open(path, *args)
        if not opened:
            os.unlink(path)
        opened.append(fd)
        return fd

    monkeypatch.setattr(files.os, "open", open_then_removed)
    with runs.locked(tmp_path):
        assert len(opened) == 2  # the removed file's lock let go, the new file locked
        monkeypatch.undo()
        other = os.open(tmp_path / runs.LOCK, os.O_RDWR)
        with pytest.raises(BlockingIOError):  # a second process opening .lock now finds it held
            fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
        os.close(other)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_interrupted_eval_keeps_the_previous_results_and_tags_keep_apart(tmp_path: Path, processes) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--no-record")
    code, output = run_cli("eval", str(out), "--episodes", "6", "--num-envs", "3")
    assert code == 0, output
    before = {name: (out / name).read_bytes() for name in ("eval.json", "eval.png", "eval.rrd")}

    process = processes(cli_command("eval", str(out), "--episodes", "1000000"))
    wait_for(out / ".eval.rrd.tmp")
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "keeps its previous results" in stderr and "Aborted" not in stderr
    assert {name: (out / name).read_bytes() for name in before} == before
    assert not list(out.glob(".*.tmp"))

    code, output = run_cli("eval", str(out), "--episodes", "5", "--num-envs", "5", "--seed", "7", "--tag", "seed7")
    assert code == 0, output
    assert json.loads((out / "eval-seed7.json").read_text())["seed"] == 7
    assert (out / "eval-seed7.png").exists() and (out / "eval-seed7.rrd").exists()
    assert {name: (out / name).read_bytes() for name in before} == before
    code, output = run_cli("eval", str(out), "--tag", "../x")
    assert code == 2 and "tag='../x'" in output


def test_a_flat_or_scripted_predator_is_named_by_its_kind(tmp_path: Path) -> None:
    for kind in ("flat", "always_stalk"):
        out = tmp_path / kind
        train_tiny(out, "--no-record", "--predator", kind)
        code, output = run_cli("eval", str(out), "--episodes", "4", "--num-envs", "4", "--no-record")
        assert code == 0 and f"predator_0: {kind} " in output and "hierarchical" not in output, output
        result = json.loads((out / "eval.json").read_text())
        panel = result["panels"][0]
        assert result["predator_kind"] == kind and result["training"]["predator"] == kind
        assert set(panel) == {"predator", "trained", "always_chase", "always_stalk", "stderr", "episode_returns"}
        check = result["prey_check"]  # the learned prey, greedy, beside FleeingPrey in its place
        assert set(check) == {"learned_greedy", "fleeing_prey"}
        for row in check.values():
            assert -2.0 <= row["return"] <= 0.0 and 0.0 <= row["left_area"] <= 1.0
            assert row["return"] <= -max(row["left_area"], row["captured"]) + 1e-9  # −1 per capture or exit
        for variant in ("trained", "always_chase", "always_stalk"):
            assert len(panel["episode_returns"][variant]) == 4
            assert abs(sum(panel["episode_returns"][variant]) / 4 - panel[variant]) < 1e-5


def test_view_opens_a_folder_and_refuses_what_is_not_a_recording(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "run"
    train_tiny(out)
    code, output = run_cli("view", str(out / "config.json"))
    assert code == 2 and "not a Rerun recording" in output
    code, output = run_cli("view", str(out))
    assert code == 2 and str(out / "train.rrd") in output and "no display" in output


def test_load_agents_returns_a_runs_agents_ready_to_act_and_evaluate(tmp_path: Path) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--no-record")
    agents = pursuit_bench.load_agents(out)
    assert list(agents) == ["predator_0", "prey_0"]
    env = pursuit_bench.parallel_env("1p-low")
    obs, _ = env.reset(seed=0)
    actions = {name: agents[name].act(obs[name]) for name in env.agents}
    env.step(actions)
    result = evaluate_agents("1p-low", agents, episodes=4, seed=0, num_envs=4)  # type: ignore[arg-type]
    assert result["predator_kind"] == "hierarchical" and len(result["panels"]) == 1
    assert pursuit_bench.VectorPursuitEnv(2, "1p-low").num_envs == 2


def test_trails_go_out_in_small_chunks(tmp_path: Path) -> None:
    """One chunk of thousands of trail rows made `rerun rrd verify` take minutes."""
    path = tmp_path / "x.rrd"
    rng = np.random.default_rng(0)
    with Recorder(path, ["predator_0", "prey_0"], {"condition": "1p-low"}) as recorder:
        for episode in range(1, 41):
            steps = int(rng.integers(20, 60))
            trace = EpisodeTrace(
                positions=rng.uniform(-0.9, 0.9, (steps + 1, 2, 2)),
                modes=np.zeros((steps, 1), dtype=np.int64),
                rewards=np.zeros((steps, 2)),
                wall=np.zeros((steps, 2), dtype=bool),
                captured=np.zeros((steps, 1), dtype=bool),
                truncated=True,
            )
            recorder.log_episode(episode, trace)
    sizes = [c.num_rows for c in rc.RrdReader(path).store().stream() if "trails/" in str(c.entity_path)]
    assert sum(sizes) > 1000 and max(sizes) <= TRAIL_ROWS_PER_CHUNK


@pytest.mark.parametrize("command", [["--help"], ["conditions"], ["train", "--condition", "9p"]])
def test_the_cli_starts_without_torch_or_rerun(command: list[str]) -> None:
    code = "import sys; from pursuit_bench.cli.main import main\n"
    code += f"try:\n    main({command!r})\nexcept SystemExit:\n    pass\n"
    code += "print(sorted({'torch', 'rerun'} & set(sys.modules)))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.stdout.strip().splitlines()[-1] == "[]", result.stdout + result.stderr


@pytest.mark.slow
def test_sigterm_at_any_moment_of_eval_leaves_old_files_or_complete_new_ones(tmp_path: Path, processes) -> None:
    """SIGTERM sent at many moments of an evaluation, whatever call it lands in (Rerun's
    included): either exit 143 with the previous files untouched, or exit 0 with a complete new
    set; never anything between, never a process left running."""
    out = tmp_path / "run"
    train_tiny(out)
    code, output = run_cli("eval", str(out), "--episodes", "6", "--num-envs", "3")
    assert code == 0, output
    before = {name: (out / name).read_bytes() for name in ("eval.json", "eval.png", "eval.rrd")}
    outcomes = set()
    for delay in (0.0, 0.05, 0.1, 0.2, 0.4, 0.8, 1.6, 3.2):  # moments to land on; the assertions hold for any
        process = processes(cli_command("eval", str(out), "--episodes", "40", "--num-envs", "4", "--seed", "3"))
        under_way = functools.partial(lambda p: p.poll() is not None or (out / ".eval.rrd.tmp").exists(), process)
        wait_until(under_way, "the evaluation under way")
        time.sleep(delay)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=120)
        outcomes.add(process.returncode)
        assert process.returncode in (0, 143), stderr
        assert not list(out.glob(".*.tmp")), stderr
        now = {name: (out / name).read_bytes() for name in before}
        if process.returncode == 143:
            assert now == before and "keeps its previous results" in stderr
        else:
            result = json.loads(now["eval.json"])
            assert result["seed"] == 3 and result["episodes"] == 40
            before = now
    assert 143 in outcomes


def checkpoint_agents(folder: Path) -> dict:
    return torch.load(folder / "checkpoint.pt", weights_only=True)["agents"]


def assert_same(a: object, b: object, where: str = "agents") -> None:
    if isinstance(a, torch.Tensor):
        assert isinstance(b, torch.Tensor) and torch.equal(a, b), where
    elif isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for key in a:
            assert_same(a[key], b[key], f"{where}/{key}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_same(x, y, f"{where}[{k}]")
    else:
        assert a == b, where


@pytest.mark.parametrize(("condition", "physics"), [("1p-low", "pymunk"), ("3p-low-individual", "numpy")])
def test_a_resumed_run_equals_one_trained_in_one_go(tmp_path: Path, condition: str, physics: str) -> None:
    """N episodes, then a resume to 2N, equal 2N in one go: every metrics row (ε and β
    included) and every weight, optimiser moment and replay entry, bit for bit."""
    options = ["--condition", condition, "--physics", physics, "--preset", "quick", "--no-record", "--seed", "3"]
    code, output = run_cli("train", "--out", str(tmp_path / "a"), *options, "--episodes", "30")
    assert code == 0, output
    code, output = run_cli("train", "--out", str(tmp_path / "a"), "--resume", "--episodes", "60")
    assert code == 0, output
    code, output = run_cli("train", "--out", str(tmp_path / "b"), *options, "--episodes", "60")
    assert code == 0, output
    resumed = (tmp_path / "a" / "metrics.jsonl").read_text().splitlines()
    in_one_go = (tmp_path / "b" / "metrics.jsonl").read_text().splitlines()
    assert len(resumed) == 60 and resumed == in_one_go
    assert_same(checkpoint_agents(tmp_path / "a"), checkpoint_agents(tmp_path / "b"))


def test_a_checkpoint_without_the_arenas_still_resumes(tmp_path: Path) -> None:
    """Checkpoints written before the arenas were saved restart them, as they used to."""
    out = tmp_path / "run"
    train_tiny(out, "--no-record", episodes=6)
    state = torch.load(out / "checkpoint.pt", weights_only=True)
    del state["arenas"], state["pending"], state["last_losses"]
    torch.save(state, out / "checkpoint.pt")
    code, output = run_cli("train", "--out", str(out), "--resume", "--episodes", "10", "--no-record")
    assert code == 0, output
    assert [json.loads(row)["episode"] for row in (out / "metrics.jsonl").read_text().splitlines()] == list(
        range(1, 11)
    )


def test_a_folder_is_prepared_for_a_new_resumed_or_replaced_run_and_refuses_what_it_holds(tmp_path: Path) -> None:
    """runs.prepare, the logic behind ``train --out/--resume/--force``, without the command line."""
    from pursuit_bench.training.train_config import TrainConfig

    config = TrainConfig(condition="1p-high", episodes=5)
    out = tmp_path / "run"
    out.mkdir()
    assert runs.prepare(out, config, {}, resume=False, force=False) == (None, None)
    assert runs.read_config(out)[0] == config
    state, note = runs.prepare(out, config, {}, resume=True, force=False)
    assert state is None and note == f"{out}: no checkpoint yet; starting the run from its beginning"
    other = TrainConfig(condition="2p-low-shared", episodes=5)
    assert runs.prepare(out, other, {}, resume=False, force=False) == (None, None)  # never checkpointed: free
    (out / runs.CHECKPOINT).write_bytes(b"")  # a run that has trained (its checkpoint unread here)
    with pytest.raises(runs.FolderRefused, match="already holds this run: pass --resume"):
        runs.prepare(out, other, {}, resume=False, force=False)
    with pytest.raises(runs.FolderRefused, match="already holds a different run"):
        runs.prepare(out, config, {}, resume=False, force=False)
    assert runs.prepare(out, config, {}, resume=False, force=True) == (None, None)
    assert runs.read_config(out)[0] == config and not (out / runs.CHECKPOINT).exists()
    stranger = tmp_path / "stranger"
    stranger.mkdir()
    (stranger / "notes.txt").write_text("mine\n")
    with pytest.raises(runs.FolderRefused, match="holds no pursuit-bench run"):
        runs.prepare(stranger, config, {}, resume=False, force=True)
    assert (stranger / "notes.txt").read_text() == "mine\n"
