"""``pursuit-bench law``: which pursuit law the predators follow (:mod:`pursuit_bench.laws.pursuit_laws`),
for a run, the shipped agents or every run of a sweep.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import click

from pursuit_bench.cli.options import (
    BadInput,
    obstacles_option,
    pretrained_options,
    run_or_pretrained,
    threads_option,
    trained_agents,
)


@click.command(short_help="Fit pursuit laws to the predators' attacks and choose one by BIC.")
@click.argument("folder", metavar="[RUN|SWEEP]", type=click.Path(path_type=Path), required=False)
@pretrained_options
@click.option("--episodes", type=click.IntRange(min=1), default=20, show_default=True, help="Episodes to play per run.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Seeds the episodes.")
@obstacles_option
@click.option(
    "--tracks",
    type=click.Path(path_type=Path, dir_okay=False),
    default=None,
    help="Fit the laws to tracked animals instead: a movement poses dataset (netCDF), or with "
    "--source-software any file movement's loaders read; with --pursuer and --target. Writes law-tracks.json "
    "beside it, or into --out. Needs the animals extra.",
)
@click.option("--pursuer", default=None, help="With --tracks: the individual that pursues.")
@click.option("--target", default=None, help="With --tracks: the individual pursued.")
@click.option(
    "--source-software",
    default=None,
    help="With --tracks: the tracker that wrote the file (DeepLabCut, SLEAP, LightningPose, …: movement's "
    "load_dataset names), for files that are not movement's netCDF.",
)
@click.option("--fps", type=click.FloatRange(min=0, min_open=True), default=None, help="With --tracks: its frame rate.")
@threads_option
def law(
    folder: Path | None,
    pretrained: str | None,
    out: Path | None,
    episodes: int,
    seed: int,
    obstacles: int | None,
    tracks: Path | None,
    pursuer: str | None,
    target: str | None,
    source_software: str | None,
    fps: float | None,
    threads: int,
) -> None:
    """Fit five laws (none, proportional pursuit, proportional navigation, mixed, parallel
    navigation) to every predator's attacks (chase phases) and stalking phases, each simulated
    from its initial conditions, and choose one per segment by BIC (docs/pursuit-law.md),
    beside the scripted predators in their places: law.json and law.png. On a SWEEP: every
    evaluated run (without the scripted references), summarised per condition and kind over
    seeds."""
    if tracks is not None:
        if folder is not None or pretrained is not None:
            raise BadInput("--tracks fits a tracked dataset: give it without a RUN or --pretrained")
        _law_tracks(tracks, pursuer, target, source_software, fps, out, seed)
        return
    where = run_or_pretrained(folder, pretrained, out)
    if pretrained is None and (where / "sweep.json").is_file():
        _law_sweep(where, episodes, seed, threads)
        return
    try:
        with trained_agents(where, pretrained, threads, obstacles) as (config, agents, _):
            from pursuit_bench.laws import pursuit_laws

            name = where.name if pretrained is None else f"shipped agents of {pretrained}"
            result = pursuit_laws.analyse(
                config.condition,
                agents,
                config.predator,
                episodes,
                seed,
                task_options=config.task_options,
                avoidance=config.avoids,
            )
            _write(where, result, f"{name}: {config.condition}, pursuit laws fitted to {episodes} episodes")
    except ValueError as error:
        raise BadInput(str(error)) from None
    for kind, predators in result["kinds"].items():
        for predator, fits in predators.items():
            click.echo(f"{kind} {predator}: {_line(fits)}")
    click.echo(f"written: law.json, law.png in {where}")


def _law_tracks(
    path: Path,
    pursuer: str | None,
    target: str | None,
    source_software: str | None,
    fps: float | None,
    out: Path | None,
    seed: int,
) -> None:
    """law --tracks: the laws fitted to a tracked pursuer and target (laws/tracked_laws.py)."""
    if pursuer is None or target is None:
        raise BadInput("--tracks needs --pursuer NAME and --target NAME (individuals of the dataset)")
    if not path.is_file():
        raise BadInput(f"--tracks {path}: no such file")
    import movement  # noqa: F401  # a missing extra is said in one line (cli/entry.py)

    from pursuit_bench.io import tracks as tracks_io
    from pursuit_bench.io.files import atomic_write_text
    from pursuit_bench.laws import tracked_laws

    try:
        if source_software is None:
            dataset = tracks_io.read(path)
        else:
            from movement.io import load_dataset

            try:
                dataset = load_dataset(path, source_software=source_software, fps=fps)
            except Exception as error:  # the loader's own refusal, in one line
                raise ValueError(f"{path}: movement's {source_software} loader refuses it ({error})") from None
        result = tracked_laws.fit_tracks(dataset, pursuer, target, seed)
    except ValueError as error:
        raise BadInput(f"--tracks {path}: {error}") from None
    where = out or path.parent
    where.mkdir(parents=True, exist_ok=True)
    result["tracks"] = str(path)
    atomic_write_text(where / "law-tracks.json", json.dumps(result) + "\n")
    if result["resampled_to_s"] is not None:
        click.echo(f"resampled from one sample every {result['sampled_every_s']:g} s to the env's 0.1 s (linear)")
    gaps = len(result["stretches"]) - 1
    click.echo(
        f"{pursuer} → {target}: {len(result['stretches'])} stretch{'es' if gaps else ''} without a gap "
        f"({gaps} gap{'s' if gaps != 1 else ''} split the track), {result['pieces']} pieces of at most "
        f"{result['piece_samples']} samples fitted"
    )
    attacks = result["attacks"]
    shares = ", ".join(f"{name} {share:.0%}" for name, share in attacks["share"].items() if share)
    click.echo(f"chosen by BIC: {shares}; written: {where / 'law-tracks.json'}")


def _line(fits: dict[str, Any]) -> str:
    parts = []
    for phase in ("chase", "stalk"):
        entry = fits[phase]
        if not entry["attacks"]:
            parts.append(f"{phase}: no segment long enough to fit")
            continue
        shares = ", ".join(f"{law} {share:.0%}" for law, share in entry["share"].items() if share)
        n_gain = entry["laws"]["pn"]["summary"]["N"]
        median = "none interior" if n_gain["median"] is None else f"median {n_gain['median']:.1f}"
        parts.append(
            f"{phase}: {entry['attacks']} segments, chosen {shares}; pn's N {median}, "
            f"{n_gain['upper']:.0%} at the bound"
        )
    return "; ".join(parts)


def _write(folder: Path, result: dict[str, Any], title: str) -> None:
    from pursuit_bench.figures.plots import law_png
    from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text

    atomic_write_bytes(folder / "law.png", law_png(result, title))
    atomic_write_text(folder / "law.json", json.dumps(result) + "\n")


def _law_sweep(sweep: Path, episodes: int, seed: int, threads: int) -> None:
    import torch

    from pursuit_bench.io.files import atomic_write_text
    from pursuit_bench.laws import pursuit_laws
    from pursuit_bench.training import runs

    torch.set_num_threads(threads)
    per_run = []
    for folder in sorted((sweep / "runs").glob("*/eval.json")):
        run = folder.parent
        config = runs.read_config(run)[0]
        agents = runs.load_agents(run)
        result = pursuit_laws.analyse(
            config.condition,
            agents,  # type: ignore[arg-type]
            config.predator,
            episodes,
            seed,
            references=False,
            task_options=config.task_options,
        )
        per_run.append({**result, "run": run.name})
        winners = ", ".join(
            f"{p} {fits['chase']['winner'] or '-'}/{fits['stalk']['winner'] or '-'}"
            for p, fits in result["kinds"][config.predator].items()
        )
        click.echo(f"{run.name}: {winners}")
    if not per_run:
        raise BadInput(f"{sweep}: no evaluated run (runs/*/eval.json) to fit")
    summary = pursuit_laws.over_seeds(per_run)
    atomic_write_text(sweep / "law.json", json.dumps({"summary": summary, "runs": per_run}) + "\n")
    for condition, kinds in summary.items():
        for kind, entry in kinds.items():
            chosen = ", ".join(f"{phase} {entry[phase]['winner'] or '-'}" for phase in ("chase", "stalk"))
            click.echo(f"{condition} {kind}: law chosen most: {chosen} ({entry['runs']} runs)")
    click.echo(f"written: law.json in {sweep}")
