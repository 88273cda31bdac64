"""``pursuit-bench view`` and ``pursuit-bench conditions``: recordings in the Rerun viewer, and
the paper's ten conditions.
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
from pathlib import Path

import click

from pursuit_bench.cli.options import BadInput
from pursuit_bench.env.conditions import CONDITIONS


@click.command()
def conditions() -> None:
    """The paper's ten conditions and their options."""
    click.echo(f"{'condition':22s} {'predators':>9s} {'chase cost':>10s}  reward sharing")
    for name, c in CONDITIONS.items():
        click.echo(f"{name:22s} {c.n_predators:>9d} {c.chase_cost:>10g}  {c.reward_sharing}")


#: The first bytes of every Rerun recording.
RRD_MAGIC = b"RRF2"


@click.command(short_help="Open a recording, or every recording of a run, in the Rerun viewer.")
@click.argument("path", type=click.Path(path_type=Path))
def view(path: Path) -> None:
    """Open a recording (.rrd), or every recording of a run folder, in the Rerun viewer."""
    if path.is_dir():
        from pursuit_bench.training import runs

        files = runs.recordings(path)
        if not files:
            raise BadInput(f"{path}: the folder holds no recording (.rrd)")
    elif not path.is_file():
        raise BadInput(f"{path}: no such recording")
    else:
        with path.open("rb") as f:
            head = f.read(len(RRD_MAGIC))
        if head != RRD_MAGIC:
            raise BadInput(f"{path}: not a Rerun recording (.rrd)")
        files = [path]
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        shown = " ".join(str(f) for f in files)
        raise BadInput(  # a refusal like the others: exit 2
            f"no display here to open the viewer on. Copy {shown} to a machine with one and run "
            f"`rerun {shown}`, or serve the web viewer from here to this machine only: "
            f"`rerun --web-viewer --bind 127.0.0.1 {shown}` and open the address it prints in a browser "
            "(from another machine, through `ssh -L 9090:127.0.0.1:9090 HOST`)"
        )
    rerun = shutil.which("rerun")
    if rerun is None and importlib.util.find_spec("rerun") is None:
        raise ModuleNotFoundError("Rerun is not installed", name="rerun")  # cli/entry.py names its extra
    args = [rerun] if rerun else [sys.executable, "-m", "rerun"]
    raise SystemExit(subprocess.call([*args, *map(str, files)]))
