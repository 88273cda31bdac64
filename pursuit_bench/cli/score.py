"""``pursuit-bench score``: an agent against a shipped population of held-out opponents, with
normalized scores per condition and their aggregate (:mod:`pursuit_bench.benchmark.score`,
docs/leaderboard.md)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from pursuit_bench.cli.options import BadInput, OutFolder, names, threads_option
from pursuit_bench.cli.wording import counted
from pursuit_bench.env.conditions import CONDITIONS


@click.command(name="score", short_help="Score an agent against the shipped populations (the leaderboard's number).")
@click.argument("agent")
@click.option("--role", type=click.Choice(["predator", "prey"]), required=True, help="The role the agent plays.")
@click.option(
    "--conditions",
    default="all",
    show_default=True,
    help="Comma-separated conditions, or 'all' (those the agent can play: a team plays where its size fits).",
)
@click.option("--episodes", type=click.IntRange(min=2), default=100, show_default=True, help="Episodes per member.")
@click.option("--seed", type=click.IntRange(min=0), default=12345, show_default=True, help="Fixes the episodes.")
@click.option(
    "--population", default=None, help="The opponents' population [rule-study once shipped, else provisional]."
)
@click.option("--out", type=OutFolder(), required=True, help="Folder for score.json and score.md.")
@threads_option
def score(
    agent: str,
    role: str,
    conditions: str,
    episodes: int,
    seed: int,
    population: str | None,
    out: Path,
    threads: int,
) -> None:
    """Score AGENT (MODULE:FACTORY, a Stable-Baselines3 MODEL.zip, a run folder, pretrained[:CONDITION],
    or a reference: random, always-chase, always-stalk, pure-pursuit, FleeingPrey) in --role against
    every member of each condition's population of the other role, on the same episodes, beside the
    reference agents.
    The agent fills every slot of its role. Writes score.json and score.md into --out, both
    complete or neither."""
    chosen = names(conditions, list(CONDITIONS), "conditions")
    import torch

    from pursuit_bench.benchmark import populations
    from pursuit_bench.benchmark import score as scoring
    from pursuit_bench.cli.progress import Progress
    from pursuit_bench.io.files import atomic_write_text

    torch.set_num_threads(threads)
    try:
        contestant = scoring.resolve(agent, role)
        playable = [c for c in chosen if contestant.can_play(c)]
        if not playable or (conditions != "all" and len(playable) < len(chosen)):
            raise BadInput(scoring.cannot_play(contestant, chosen))
        name = population or populations.default(role)
        pops = {c: populations.load(name, c) for c in playable}
        for condition in playable:
            scoring.check_plays(contestant, condition)
            scoring.check_members(pops[condition])
    except ValueError as error:
        raise BadInput(str(error)) from None
    skipped = [c for c in chosen if c not in playable]
    provisional = any(p.provisional for p in pops.values())
    click.echo(
        f"scoring {contestant.description} as {role}, filling "
        f"{'every predator slot' if role == 'predator' else 'the prey'}"
        f"{' (a team of copies where there are several)' if role == 'predator' and contestant.copies else ''}, "
        f"against population {name}{' (PROVISIONAL)' if provisional else ''}"
        + (f"; skipped (team size): {', '.join(skipped)}" if skipped else ""),
        err=True,
    )
    n_refs = len(set(scoring.REFERENCE_ROWS[role]) | {contestant.label})  # the agent, if a reference, plays once
    total = sum(len(p.members) for p in pops.values()) * episodes * n_refs
    done = [0]
    progress = Progress(
        f"score {agent}", total, 0, lambda: counted(len(pops), "condition"), every_episodes=max(total // 20, 1)
    )

    def on_episodes(n: int) -> None:
        done[0] = min(done[0] + n, total)
        progress.update(done[0])

    try:
        result = scoring.score(
            contestant, playable, episodes=episodes, seed=seed, population=name, on_episodes=on_episodes
        )
    except ValueError as error:
        raise BadInput(str(error)) from None
    except KeyboardInterrupt:
        click.echo(f"\ninterrupted: nothing written to {out}", err=True)
        sys.exit(130)
    finally:
        progress.close()
    texts = {"score.md": scoring.markdown(result), "score.json": scoring.dumps(result)}
    for file, text in texts.items():  # complete under temporary names, then renamed: score.json last
        atomic_write_text(out / f".{file}.tmp", text)
    for file in texts:
        os.replace(out / f".{file}.tmp", out / file)
    for condition, c in result["conditions"].items():
        excluded = (
            f"; excluded from the population (the scored run's own): {', '.join(c['excluded'])}"
            if c["excluded"]
            else ""
        )
        why = scoring.undefined_why(result, condition)
        normalized = f"– ({why})" if why else f"{c['normalized']:.2f}"
        click.echo(f"{condition}: return {c['mean_return']:+.3f}, normalized {normalized}{excluded}")
    agg = result["aggregate"]
    click.echo(f"aggregate (IQM of normalized scores): {scoring.aggregate_text(agg)}")
    for line in scoring.standing(result):
        click.echo(line)
    warning = "PROVISIONAL population; " if result["provisional"] else ""
    click.echo(f"{warning}results in {out / 'score.json'} and {out / 'score.md'}")
