"""``pursuit-bench robust``: the predators' margin over the baselines under a ladder of
perturbations, and cross-play over a sweep's seeds (:mod:`pursuit_bench.analysis.robustness`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from pursuit_bench.cli.options import BadInput, pretrained_options, run_or_pretrained


@click.command(short_help="Margins under perturbed worlds and senses; cross-play over a sweep's seeds.")
@click.argument("folders", metavar="[RUN|SWEEP]...", type=click.Path(path_type=Path), nargs=-1)
@pretrained_options
@click.option("--episodes", type=click.IntRange(min=1), default=300, show_default=True, help="Episodes per variant.")
@click.option("--seed", type=click.IntRange(min=0), default=12345, show_default=True, help="Seeds the evaluations.")
@click.option("--workers", type=click.IntRange(min=1), default=None, help="Processes evaluating at once [the cores].")
@click.option(
    "--conditions", default=None, help="On a SWEEP: only these conditions (comma-separated) [every one it has]."
)
@click.option("--seeds", type=click.IntRange(min=1), default=None, help="On a SWEEP: only seeds 0 … N-1 [all].")
def robust(
    folders: tuple[Path, ...],
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    workers: int | None,
    conditions: str | None,
    seeds: int | None,
) -> None:
    """Evaluate every run of a SWEEP (or one RUN, or the shipped agents) by the paper's protocol
    under each perturbation's ladder of strengths (docs/robustness.md), and, over a sweep's
    seeds, each seed's predators against every seed's prey of the same condition and kind:
    robust.json, robust.md and robust.png. Several folders (a sweep of each predator kind, say)
    are studied as one, into --out. Each evaluation is kept as it finishes (robust-parts/):
    rerunning the command goes on where it stopped."""
    import os

    if pretrained is not None:
        if folders:
            raise click.UsageError("give RUN or SWEEP folders or --pretrained CONDITION, not both")
        where = run_or_pretrained(None, pretrained, out)
        sources = _sources(where, pretrained, conditions, seeds)
    else:
        if not folders:
            raise click.UsageError("give a RUN or SWEEP folder (or several, with --out) or --pretrained CONDITION")
        if len(folders) > 1 and out is None:
            raise click.UsageError("several folders go with --out")
        where = out or folders[0]
        sources = [s for folder in folders for s in _sources(folder, None, conditions, seeds)]
    from pursuit_bench.training import runs

    for source in sources:  # a checkpoint that cannot be read stops the study before any worker starts
        if isinstance(source["source"], Path):
            try:
                runs.load_checkpoint(source["source"])
            except ValueError as error:
                raise BadInput(str(error)) from None
    where.mkdir(parents=True, exist_ok=True)
    from pursuit_bench.analysis import robustness
    from pursuit_bench.figures.plots import robust_png
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    def progress(done: int, total: int) -> None:
        click.echo(f"robust: {done} of {total} evaluations", err=True)

    try:
        result = robustness.run(
            sources, where, episodes=episodes, seed=seed, workers=workers or os.cpu_count() or 1, progress=progress
        )
    except ValueError as error:
        raise BadInput(str(error)) from None
    atomic_write_text(where / "robust.json", json.dumps(result, indent=2) + "\n")
    atomic_write_text(where / "robust.md", robustness.markdown(result))
    atomic_write_bytes(where / "robust.png", robust_png(result))
    click.echo(robustness.families_markdown(result))
    click.echo(f"written: robust.json, robust.md, robust.png in {where}")


def _sources(where: Path, pretrained: str | None, conditions: str | None, seeds: int | None) -> list[dict[str, Any]]:
    """What to evaluate: the shipped agents, one run, or every evaluated run of a sweep."""
    from pursuit_bench.training import runs

    if pretrained is not None:
        from pursuit_bench import pretrained as shipped

        config, _, about = shipped.described(pretrained)
        seed = about["pretrained"].get("seed", 0)
        return [
            {
                "name": f"pretrained-{pretrained}",
                "condition": pretrained,
                "kind": config.predator,
                "seed": seed,
                "config": config,
                "source": pretrained,
            }
        ]
    if (where / "sweep.json").is_file():
        folders = sorted(p.parent for p in (where / "runs").glob("*/eval.json"))
    elif (where / "config.json").is_file():
        folders = [where]
    else:
        raise BadInput(f"{where}: neither a run folder (config.json) nor a sweep folder (sweep.json)")
    wanted = None if conditions is None else {c.strip() for c in conditions.split(",") if c.strip()}
    sources = []
    for run in folders:
        config, _ = runs.read_config(run)
        if (wanted is not None and config.condition not in wanted) or (seeds is not None and config.seed >= seeds):
            continue
        sources.append(
            {
                "name": run.name,
                "condition": config.condition,
                "kind": config.predator,
                "seed": config.seed,
                "config": config,
                "source": run,
            }
        )
    if not sources:
        raise BadInput(f"{where}: no evaluated run" + (f" of {conditions}" if conditions else ""))
    return sources
