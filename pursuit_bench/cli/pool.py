"""``pursuit-bench pool``: the learned predator kinds of a sweep (hierarchical, flat, residual: any
two or more) judged against one pool of opponents at every kept budget, pairwise
(:mod:`pursuit_bench.reports.pool`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from pursuit_bench.cli.options import BadInput, OutFolder, check_out_folder


@click.command(short_help="Predator kinds compared pairwise, each judged against one pool of opponents.")
@click.argument("sweeps", metavar="SWEEP...", type=click.Path(path_type=Path), nargs=-1, required=True)
@click.option("--out", type=OutFolder(), required=True, help="Folder for pool.json and its report.")
@click.option(
    "--pool-seeds",
    default=None,
    help="Seeds whose runs supply the pool's prey and are not judged (comma-separated) [the sweep's last two].",
)
@click.option(
    "--episodes", type=click.IntRange(min=1), default=60, show_default=True, help="Episodes per variant per opponent."
)
@click.option(
    "--cross-episodes",
    type=click.IntRange(min=1),
    default=300,
    show_default=True,
    help="Episodes per variant of cross-kind play (own prey, the other kind's).",
)
@click.option("--seed", type=click.IntRange(min=0), default=12345, show_default=True, help="Seeds the evaluations.")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Processes evaluating at once [the cores].")
def pool(
    sweeps: tuple[Path, ...],
    out: Path,
    pool_seeds: str | None,
    episodes: int,
    cross_episodes: int,
    seed: int,
    workers: int | None,
) -> None:
    """Judge the learned kinds' runs of SWEEP (hierarchical, flat, residual: one sweep of every kind,
    or one a kind) against a common pool: FleeingPrey and the prey of the pool seeds' runs of every
    kind, at every budget the sweep kept a checkpoint for, by the paper's protocol, each kind against
    every other (Holm over a budget's panels and comparisons); and each run in cross-kind play (its
    predators against each other kind's prey of the same seed). Writes pool.json (every
    evaluation), pool-report.json, pool.md and pool.png into --out; each evaluation is kept as it
    finishes (pool-parts/): rerunning the command goes on where it stopped. `pursuit-bench report
    OUT` rewrites the report from pool.json."""
    import os

    check_out_folder(out)
    for where in sweeps:  # before anything heavy is imported (training.sweep brings torch): a refusal comes at once
        if not where.is_dir():
            raise BadInput(f"{where}: no such sweep folder")
        if not (where / "sweep.json").is_file():
            raise BadInput(f"{where}: not a sweep folder (no sweep.json)")
    from pursuit_bench.io.files import atomic_write_text
    from pursuit_bench.reports import pool as pools

    sources, budgets, seeds = _sources(sweeps)
    try:
        chosen = tuple(seeds[-2:]) if pool_seeds is None else tuple(int(s) for s in pool_seeds.split(","))
    except ValueError:
        raise BadInput(f"--pool-seeds {pool_seeds}: expected comma-separated seeds, e.g. 8,9") from None
    if unknown := [s for s in chosen if s not in seeds]:
        raise BadInput(f"--pool-seeds: {unknown} not among the sweep's seeds {seeds}")
    out.mkdir(parents=True, exist_ok=True)

    def progress(done: int, total: int) -> None:
        click.echo(f"pool: {done} of {total} evaluations", err=True)

    try:
        result = pools.run(
            sources,
            budgets,
            out,
            pool_seeds=chosen,
            episodes=episodes,
            cross_episodes=cross_episodes,
            seed=seed,
            workers=workers or os.cpu_count() or 1,
            progress=progress,
        )
    except ValueError as error:
        raise BadInput(str(error)) from None
    atomic_write_text(out / "pool.json", json.dumps(result) + "\n")
    try:
        summary = pools.write_report(result, out)
    except ValueError as error:
        raise BadInput(str(error)) from None
    click.echo(pools.counts_markdown(summary))
    click.echo(f"written: pool.json, pool-report.json, pool.md, pool.png in {out}")


def _sources(sweeps: tuple[Path, ...]) -> tuple[list[dict[str, Any]], list[int], list[int]]:
    """The learned kinds' runs of the sweeps (each finished, with every kept checkpoint),
    their common budgets (two or more: learning against budget needs them) and seeds."""
    from pursuit_bench.reports.pool import ORDER
    from pursuit_bench.training import runs
    from pursuit_bench.training.sweep import PLAN, SweepPlan, run_status

    sources: list[dict[str, Any]] = []
    budgets: list[int] | None = None
    seeds: set[int] = set()
    for where in sweeps:
        try:
            plan = SweepPlan.from_dict(json.loads((where / PLAN).read_text())["plan"])
        except (ValueError, KeyError, TypeError) as error:
            raise BadInput(f"{where / PLAN}: not a pursuit-bench sweep plan ({error})") from None
        mine = sorted({*plan.keep_checkpoints, plan.episodes})
        if len(mine) < 2:
            raise BadInput(f"{where}: no kept checkpoints; train the sweep with --keep-checkpoints (e.g. 1500,5000)")
        if budgets is not None and mine != budgets:
            raise BadInput(f"{where}: its budgets {mine} differ from the other sweep's {budgets}")
        budgets = mine
        seeds |= set(range(plan.seeds))
        for name, config in sorted(plan.runs().items()):
            if config.predator not in ORDER:
                continue
            folder = where / "runs" / name
            try:
                done, evaluated = run_status(folder, config, plan.keep_checkpoints)
            except ValueError as error:
                raise BadInput(str(error)) from None
            missing = [n for n in plan.keep_checkpoints if not (folder / runs.milestone_checkpoint(n)).is_file()]
            if not evaluated or done < config.episodes or missing:
                raise BadInput(f"{folder}: not finished (trained {done} of {config.episodes}); finish the sweep first")
            sources.append(
                {
                    "name": name,
                    "condition": config.condition,
                    "kind": config.predator,
                    "seed": config.seed,
                    "folder": str(folder),
                }
            )
    assert budgets is not None
    return sources, budgets, sorted(seeds)
