"""Running the command line in tests: in-process through click's runner, or as a real process; and
the checkout's scripts loaded by path."""

import importlib.util
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from click.testing import CliRunner

from pursuit_bench.cli.main import main


def run_cli(*args: str) -> tuple[int, str]:
    """Exit code and output (stdout and stderr) of ``pursuit-bench ARGS``, in this process."""
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.output


def cli_command(*args: str) -> list[str]:
    """The command line of ``pursuit-bench ARGS`` as a process of its own."""
    return [sys.executable, "-m", "pursuit_bench.cli.main", *args]


def wait_until(condition: Callable[[], bool], what: str, timeout: float = 120.0) -> None:
    """Poll ``condition`` until it holds (a failure after ``timeout`` seconds): tests wait for
    what they need to see, never for a fixed time."""
    start = time.monotonic()
    while not condition():
        assert time.monotonic() - start < timeout, f"{what}: not seen within {timeout:.0f} s"
        time.sleep(0.05)


def wait_for(path: Path, timeout: float = 120.0) -> None:
    wait_until(path.exists, f"{path}", timeout)


def lines(path: Path) -> int:
    """Complete lines in a file (0 if it is not there yet)."""
    try:
        return path.read_text().count("\n")
    except FileNotFoundError:
        return 0


ROOT = Path(__file__).resolve().parents[1]


def load_script(relative: str) -> ModuleType:
    """A script of the checkout (``docs/gen/law_tables.py``, ``studies/coverage/interval_coverage.py``)
    loaded as a module by its path, once: scripts are not a package, and no test edits ``sys.path``."""
    name = "script_" + relative.removesuffix(".py").replace("/", "_").replace("-", "_")
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / relative)
    assert spec is not None and spec.loader is not None, relative
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # before running it: dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module
