"""``pursuit-bench analyze``: Fig. 3 of a run (or of the shipped agents) and the chase modes of a
sweep (:mod:`pursuit_bench.analysis.fig3`).
"""

from __future__ import annotations

from pathlib import Path

import click

from pursuit_bench.cli.options import (
    BadInput,
    obstacles_option,
    pretrained_options,
    run_or_pretrained,
    threads_option,
    trained_agents,
)


@click.command(short_help="Fig. 3: value streams and chase modes of a run or a sweep.")
@click.argument("folder", metavar="[RUN]", type=click.Path(path_type=Path), required=False)
@pretrained_options
@click.option("--episodes", type=click.IntRange(min=1), default=200, show_default=True, help="Episodes to play.")
@click.option(
    "--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seeds the episodes and the t-SNE."
)
@obstacles_option
@threads_option
def analyze(
    folder: Path | None,
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    obstacles: int | None,
    threads: int,
) -> None:
    """What the trained predators' value streams represent and when they chase (Fig. 3).

    On a RUN folder (or a shipped agent, --pretrained): fig3.png, modes.png, analysis.json and
    analysis.rrd. On a sweep folder: P(chase | distance) and the chase-onset distance for low
    against high chase cost, per number of predators, over seeds: modes.png and analysis.json
    in the sweep folder."""
    where = run_or_pretrained(folder, pretrained, out)
    if pretrained is None and (where / "sweep.json").is_file():
        _analyze_sweep(where, episodes, seed, threads)
        return
    try:
        with trained_agents(where, pretrained, threads, obstacles) as (config, agents, _):
            from pursuit_bench.analysis import fig3

            result = fig3.analyze_run(where, config, agents, episodes, seed)
    except ValueError as error:  # RunBusy, not a run folder, not trained, not hierarchical
        raise BadInput(str(error)) from None
    for name, r in result.items():
        onset = r["chase_onset_distance"]
        median = f"{onset['median']:.2f}" if onset["median"] is not None else "–"
        click.echo(
            f"{name}: organisation by distance R² {r['organisation']['distance']:.2f}, by V(s) "
            f"{r['organisation']['value']:.2f}; P(chase) {r['p_chase']:.2f}; chase bouts start at {median} (median)"
        )
    click.echo(f"written: fig3.png, modes.png, analysis.json, analysis.rrd in {where}")


def _analyze_sweep(sweep_folder: Path, episodes: int, seed: int, threads: int) -> None:
    import torch

    from pursuit_bench.analysis import fig3

    torch.set_num_threads(threads)
    try:
        result = fig3.analyze_sweep(sweep_folder, episodes, seed)
    except ValueError as error:
        raise BadInput(str(error)) from None
    for label, r in result.items():
        median = f"{r['chase_onset_median']:.2f}" if r["chase_onset_median"] is not None else "–"
        click.echo(f"{label}: {r['runs']} runs, chase bouts start at {median} (median)")
    click.echo(f"written: modes.png, analysis.json in {sweep_folder}")
