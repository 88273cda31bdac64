"""Running the command line in tests: in-process through click's runner, or as a real process."""

import subprocess
import sys
import time
from pathlib import Path

from click.testing import CliRunner

from pursuit_bench.cli.main import main


def run_cli(*args: str) -> tuple[int, str]:
    """Exit code and output (stdout and stderr) of ``pursuit-bench ARGS``, in this process."""
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.output


def cli_process(*args: str) -> subprocess.Popen:
    """``pursuit-bench ARGS`` as a process of its own (for signals and kills)."""
    command = [sys.executable, "-m", "pursuit_bench.cli.main", *args]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for(path: Path, timeout: float = 120.0) -> None:
    start = time.monotonic()
    while not path.exists():
        assert time.monotonic() - start < timeout, f"{path} never appeared"
        time.sleep(0.05)
