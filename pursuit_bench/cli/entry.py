"""The ``pursuit-bench`` script's entry point: the command line with, when a module of an extra is
missing, one line that names the extra to install instead of a traceback.

``pip install pursuit-bench`` installs the environment alone (numpy, pymunk, Gymnasium,
PettingZoo, numba) and click: ``--help`` and ``conditions`` work with it; the other commands
need the ``train`` extra (torch, Rerun, …) and ``sweep --backend ray`` the ``ray`` extra
(pyproject.toml). This module imports nothing but the standard library before it has caught
what is missing.
"""

from __future__ import annotations

import sys

#: Each module the commands import that the environment's install lacks: (the distribution
#: that holds it, the extra that installs it). tests/test_install.py checks it against pyproject.toml.
EXTRA_OF: dict[str, tuple[str, str]] = {
    "torch": ("torch", "train"),
    "rerun": ("rerun-sdk", "train"),
    "matplotlib": ("matplotlib", "train"),
    "scipy": ("scipy", "train"),
    "sklearn": ("scikit-learn", "train"),
    "safetensors": ("safetensors", "train"),
    "threadpoolctl": ("threadpoolctl", "train"),
    "ray": ("ray", "ray"),
    "tensorboard": ("tensorboard", "tensorboard"),
    "movement": ("movement", "animals"),
}


def missing_extra(error: ModuleNotFoundError) -> str | None:
    """The one-line message for a module an extra installs, or None for any other module."""
    module = (error.name or "").partition(".")[0]
    if module not in EXTRA_OF:
        return None
    distribution, extra = EXTRA_OF[module]
    # pursuit-bench is on no index: the extra is installed from the clone or from the wheel's path
    wheel = f"pip install 'path/to/pursuit_bench-{_version()}-py3-none-any.whl[{extra}]'"
    if extra == "train":  # torch comes with it: its CPU build first, or pip takes the CUDA one (GBs)
        wheel = f"pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu, then {wheel}"
    script = "scripts/install.sh" + ("" if extra == "train" else f" {extra}")
    install = f"in a clone, run {script} (it installs torch's CPU build, then -e '.[{extra}]'); from a wheel, {wheel}"
    command = " ".join(["pursuit-bench", *(a for a in sys.argv[1:2] if not a.startswith("-"))])
    return f"Error: {command} needs {distribution}, which pursuit-bench's '{extra}' extra installs: {install}"


def _version() -> str:
    """The installed pursuit-bench's version (its wheel's name holds it)."""
    from importlib import metadata

    try:
        return metadata.version("pursuit-bench")
    except metadata.PackageNotFoundError:
        return "VERSION"


def main() -> None:
    """Run the command line; a missing extra's module ends it with one line and status 1."""
    try:
        from pursuit_bench.cli.main import main as command_line

        command_line()
    except ModuleNotFoundError as error:
        message = missing_extra(error)
        if message is None:
            raise
        print(message, file=sys.stderr)
        sys.exit(1)
