"""The command line, run for real on tiny budgets."""

import json
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import cli_command, lines, run_cli, wait_for, wait_until

TINY = [
    "--episodes",
    "12",
    "--num-envs",
    "4",
    "--learning-starts",
    "32",
    "--batch-size",
    "16",
    "--checkpoint-every",
    "5",
]


def train_tiny(out: Path, *extra: str) -> None:
    code, output = run_cli("train", "--condition", "2p-high-shared", "--out", str(out), *TINY, *extra)
    assert code == 0, output


def test_conditions_lists_all_ten() -> None:
    code, output = run_cli("conditions")
    assert code == 0 and len(output.strip().splitlines()) == 11 and "3p-high-individual" in output


def test_train_then_eval_writes_the_run_folder(tmp_path: Path) -> None:
    out = tmp_path / "run"
    train_tiny(out, "--record-every", "3")
    for name in ("config.json", "metrics.jsonl", "checkpoint.pt", "train.rrd"):
        assert (out / name).is_file(), name
    config = json.loads((out / "config.json").read_text())
    assert config["train"]["condition"] == "2p-high-shared" and config["train"]["agent"]["learning_starts"] == 32
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert [r["episode"] for r in rows] == list(range(1, 13))
    assert {"return/predator_0", "return/prey_0", "captured", "length", "epsilon"} <= set(rows[0])

    code, output = run_cli("eval", str(out), "--episodes", "10", "--num-envs", "5")
    assert code == 0, output
    result = json.loads((out / "eval.json").read_text())
    assert (result["condition"], result["episodes"], result["seed"]) == ("2p-high-shared", 10, 12345)
    assert [p["predator"] for p in result["panels"]] == ["predator_0", "predator_1"]
    for panel in result["panels"]:
        assert all(isinstance(panel[k], float) for k in ("trained", "always_chase", "always_stalk"))
    assert 0.0 <= result["capture_rate"] <= 1.0 and set(result["chase_fraction"]) == {"predator_0", "predator_1"}
    assert (out / "eval.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and (out / "eval.png").stat().st_size > 5000
    assert (out / "eval.rrd").stat().st_size > 0
    # the prey's outcomes name all four ways an episode ends and add up; the capture rate says its protocol
    prey_line = next(line for line in output.splitlines() if line.startswith("prey_0"))
    for side in prey_line.split("; "):
        shares = [float(share) for share in re.findall(r"(?:caught|wall|limit) ([\d.]+)%", side)]
        assert len(shares) == 4 and abs(sum(shares) - 100) < 0.25, side
    assert "capture rate" in output and "the paper's protocol: the prey ε-greedy with ε = 0.1" in output
    assert result["protocol"]["prey_epsilon"] == 0.1  # a learning prey of ours: the ε it played with


def test_same_seed_same_eval(tmp_path: Path) -> None:
    results = []
    for name in ("a", "b"):
        train_tiny(tmp_path / name, "--no-record", "--seed", "3")
        code, output = run_cli("eval", str(tmp_path / name), "--episodes", "8", "--no-record")
        assert code == 0, output
        results.append((tmp_path / name / "eval.json").read_text())
    assert results[0] == results[1]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["train", "--condition", "4p-low"], "'4p-low' is not one of"),
        (["train", "--episodes", "0"], "0 is not in the range 1<=x<=100000000"),
        (["train", "--episodes", "10000000000000"], "is not in the range 1<=x<=100000000"),
        (["train", "--no-record", "--record-every", "5"], "--record-every goes with recording"),
        (["train", "--gamma", "1.5"], "--gamma 1.5"),
        (["eval", "nowhere"], "nowhere: no such run folder"),
        (["view", "missing.rrd"], "missing.rrd: no such recording"),
        (["eval", "--pretrained", "1p-high", "--out", "a-file"], "--out a-file: exists and is not a folder"),
        (["analyze", "--pretrained", "1p-high", "--out", "a-file"], "--out a-file: exists and is not a folder"),
        (["train", "--out", "a-file/sub"], "--out a-file/sub: a-file is a file"),
        (["eval", "--pretrained", "1p-high", "--out", "a-file/sub"], "--out a-file/sub: a-file is a file"),
        (["sweep", "--out", "a-file/sub/deeper"], "--out a-file/sub/deeper: a-file is a file"),
        (["score", "random", "--role", "predator", "--out", "a-file/sub"], "--out a-file/sub: a-file is a file"),
        (["report", ".", "--out", "a-file/sub"], "--out a-file/sub: a-file is a file"),
        (["pool", ".", "--out", "a-file/sub"], "--out a-file/sub: a-file is a file"),
        (["report", "."], "report also reads a run folder (config.json), a pool study (pool.json), the rule"),
    ],
)
def test_bad_input_is_one_line_and_status_2(tmp_path: Path, monkeypatch, args: list[str], message: str) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a-file").write_text("not a folder")
    code, output = run_cli(*args)
    assert code == 2 and message in output and len(output.strip().splitlines()) == 1, output


@pytest.mark.parametrize(
    "command",
    [
        ["train"],
        ["eval", "--pretrained", "1p-high"],
        ["analyze", "--pretrained", "1p-high"],
        ["law", "--pretrained", "1p-high"],
        ["robust", "--pretrained", "1p-high"],
        ["robust", "."],
        ["sweep"],
        ["pool", "."],
        ["report", "."],
        ["score", "random", "--role", "predator", "--conditions", "1p-low", "--episodes", "2"],
    ],
)
@pytest.mark.parametrize(
    ("out", "message"),
    [("", "--out '': an empty path"), ("/proc/x", "--out /proc/x: cannot write there"), ("/proc/x/y", "cannot write")],
)
def test_an_out_folder_that_cannot_be_written_is_refused_before_any_work(
    tmp_path: Path, monkeypatch, command: list[str], out: str, message: str
) -> None:
    """Every command's --out is checked as the command line is read: an impossible or empty path
    is one line and status 2, before anything is played or trained, and nothing is left behind."""
    if out.startswith("/proc") and not Path("/proc").is_dir():
        pytest.skip("needs Linux's /proc (a folder nothing can be made in)")
    monkeypatch.chdir(tmp_path)
    code, output = run_cli(*command, "--out", out)
    assert code == 2 and message in output and len(output.strip().splitlines()) == 1, output
    assert list(tmp_path.iterdir()) == []


def test_view_without_a_display_says_what_to_do(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    recording = tmp_path / "x.rrd"
    recording.write_bytes(b"RRF2")
    code, output = run_cli("view", str(recording))
    assert code == 2 and "no display" in output and "Traceback" not in output  # a refusal like every other
    assert "rerun --web-viewer --bind 127.0.0.1 " in output


def test_bad_run_folders(tmp_path: Path) -> None:
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    code, output = run_cli("eval", str(foreign))
    assert code == 2 and "not a pursuit-bench run folder" in output
    code, output = run_cli("train", "--out", str(foreign), *TINY)
    assert code == 2 and "holds no pursuit-bench run" in output and (foreign / "notes.txt").exists()

    out = tmp_path / "run"
    train_tiny(out, "--no-record")
    code, output = run_cli("train", "--condition", "1p-low", "--out", str(out), *TINY)
    assert code == 2 and "already holds a different run" in output
    code, output = run_cli("train", "--condition", "2p-high-shared", "--out", str(out), *TINY)
    assert code == 2 and "already holds this run" in output
    code, output = run_cli("train", "--condition", "1p-low", "--out", str(out), "--resume", *TINY)
    assert code == 2 and "--condition 1p-low disagrees with the run's 2p-high-shared" in output

    checkpoint = out / "checkpoint.pt"
    good = checkpoint.read_bytes()
    checkpoint.write_bytes(good[: len(good) // 2])  # truncated
    code, output = run_cli("eval", str(out))
    assert code == 2 and "checkpoint.pt: not a readable pursuit-bench checkpoint (truncated or corrupted)" in output
    assert len(output.strip().splitlines()[-1]) < 200  # the file's name and a few words, not torch's advice
    checkpoint.write_bytes(b"garbage" * 100)  # corrupted
    code, output = run_cli("eval", str(out))
    assert code == 2 and "not a readable" in output and len(output.strip().splitlines()) == 1

    code, output = run_cli("train", "--condition", "1p-low", "--out", str(out), "--force", *TINY, "--no-record")
    assert code == 0, output
    assert json.loads((out / "config.json").read_text())["train"]["condition"] == "1p-low"


@pytest.mark.slow
@pytest.mark.long
def test_killed_training_resumes_to_the_same_episode_count(tmp_path: Path, processes) -> None:
    out = tmp_path / "run"
    args = ["train", "--condition", "1p-low", "--out", str(out), "--episodes", "400", "--num-envs", "4"]
    args += ["--learning-starts", "32", "--batch-size", "16", "--checkpoint-every", "20"]
    process = processes(cli_command(*args))
    wait_for(out / "checkpoint.pt")
    process.send_signal(signal.SIGKILL)
    process.wait()
    resumed = subprocess.run(
        [sys.executable, "-m", "pursuit_bench.cli.main", *args, "--resume"], capture_output=True, text=True
    )
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming" in resumed.stderr
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    assert [r["episode"] for r in rows] == list(range(1, 401))
    assert (out / "train.resume1.rrd").exists()


@pytest.mark.slow
def test_ctrl_c_stops_cleanly_with_a_checkpoint_and_a_valid_recording(tmp_path: Path, processes) -> None:
    out = tmp_path / "run"
    process = processes(
        cli_command("train", "--condition", "1p-low", "--out", str(out), "--episodes", "100000", "--record-every", "1")
    )
    wait_until(lambda: lines(out / "metrics.jsonl") >= 20, "20 episodes trained")
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "SIGINT: stopped at episode" in stderr and "Traceback" not in stderr
    state_rows = (out / "metrics.jsonl").read_text().splitlines()
    assert len(state_rows) > 0
    verify = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(out / "train.rrd")], capture_output=True, text=True
    )
    assert verify.returncode == 0, verify.stdout + verify.stderr
    code, output = run_cli("eval", str(out), "--episodes", "4", "--no-record")
    assert code == 0, output  # the checkpoint written on Ctrl-C loads


@pytest.mark.slow
@pytest.mark.long
def test_a_training_log_line_has_an_eta(tmp_path: Path) -> None:
    command = cli_command("train", "--condition", "1p-low", "--out", str(tmp_path / "r"), *TINY, "--no-record")
    done = subprocess.run([*command, "--log-every", "4"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "episodes/s | ETA " in done.stderr, done.stderr
