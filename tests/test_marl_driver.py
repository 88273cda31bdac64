"""The MARL study's driver (studies/marl/run.py): ``--only`` refuses a run it does not plan in
one line, and does only the runs named (a named run already scored is done: nothing trained)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

DRIVER = Path(__file__).resolve().parents[1] / "studies" / "marl" / "run.py"


def drive(tmp_path: Path, *options: str) -> tuple[int, str]:
    """The driver's exit code and stderr; it and whatever it started are ended whatever happens
    (a driver that ignored ``--only`` would start training)."""
    command = [sys.executable, str(DRIVER), "--work", str(tmp_path / "work"), "--results", str(tmp_path / "results")]
    process = subprocess.Popen([*command, *options], stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        _, stderr = process.communicate(timeout=120)
        return process.returncode, stderr
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()


def test_only_refuses_a_run_not_planned_in_one_line(tmp_path: Path) -> None:
    code, stderr = drive(tmp_path, "--only", "3p-high-individual-iql-seed2,1p-high-qmix-seed0")
    assert code == 2 and stderr.strip().count("\n") == 0 and "unknown run 1p-high-qmix-seed0" in stderr, stderr
    assert not (tmp_path / "work").exists()  # refused before anything was made


def test_only_does_the_runs_named_and_no_other(tmp_path: Path) -> None:
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "3p-high-individual-iql-seed2.score.json").write_text("{}\n")
    code, stderr = drive(tmp_path, "--only", "3p-high-individual-iql-seed2")
    assert code == 0, stderr
    assert not (tmp_path / "work" / "runs").exists()  # the one named is scored, the others not named: none trained
    assert (tmp_path / "work" / "progress.log").read_text().rstrip().endswith("every run named by --only scored")
