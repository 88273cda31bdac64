"""``pursuit-bench``: train, evaluate and look at agents from the command line.

One module per command (``cli/train.py``, ``cli/evaluate.py``, …) parses options into
configurations and calls the library; ``cli/options.py`` holds what they share. Bad input is a
one-line error and exit status 2; SIGINT and SIGTERM stop a command cleanly with status 130 and
143. torch and Rerun are imported inside the commands that use them, so that ``--help`` and
errors come at once.
"""

from __future__ import annotations

import sys
from typing import Any

import click

from pursuit_bench.cli.analyze import analyze
from pursuit_bench.cli.evaluate import evaluate
from pursuit_bench.cli.law import law
from pursuit_bench.cli.marl import marl
from pursuit_bench.cli.pool import pool
from pursuit_bench.cli.report import report
from pursuit_bench.cli.robust import robust
from pursuit_bench.cli.score import score
from pursuit_bench.cli.sweep import sweep
from pursuit_bench.cli.train import train
from pursuit_bench.cli.view import conditions, view


class OneLineErrors(click.Group):
    """click's group, with every refusal on one line: ``Error: … (see 'pursuit-bench CMD --help')``
    where click prints its usage, a hint and the error on four (its convention)."""

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        run: Any = super().main  # click types main() by standalone_mode: one call here serves both
        if not standalone_mode:
            return run(*args, standalone_mode=False, **kwargs)
        try:
            code = run(*args, standalone_mode=False, **kwargs)
        except click.ClickException as error:
            context = getattr(error, "ctx", None)
            hint = f" (see '{context.command_path} --help')" if isinstance(error, click.UsageError) and context else ""
            click.echo(f"Error: {error.format_message()}{hint}", err=True)
            sys.exit(error.exit_code)
        except click.Abort:
            click.echo("Aborted!", err=True)
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)


@click.group(cls=OneLineErrors, context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(package_name="pursuit-bench")
def main() -> None:
    """pursuit-bench: predators hunt a prey; deep RL picks how hard, parallel navigation where."""


for command in (conditions, train, evaluate, sweep, report, pool, analyze, law, robust, score, marl, view):
    main.add_command(command)


if __name__ == "__main__":
    main()
