"""``pursuit-bench report``: the claim judged panel by panel over a sweep's seeds (verdicts, paired
differences, per-seed counts, power, convergence: :func:`pursuit_bench.reports.reproduction.write`), or the
learning curves and a summary of one run.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import click

from pursuit_bench.cli.options import BadInput, OutFolder, check_out_folder
from pursuit_bench.cli.wording import counted


@click.command(short_help="A sweep's panels judged over seeds (better / not resolved / worse); a run's curves.")
@click.argument("where", metavar="SWEEP|RESULTS|RUN", type=click.Path(path_type=Path))
@click.option("--out", type=OutFolder(), default=None, help="Where to write [the folder given].")
def report(where: Path, out: Path | None) -> None:
    """Fig. 2 over seeds from a sweep's run folders, or from its compact results (what
    `scripts/export_results.py` writes): report.md and report.json (the
    panels' verdicts, paired differences, per-seed counts, power), fig2.png, forest.png,
    counts.png, curves.png and budget.png. On a RUN folder: its learning curves (curves.png) and a summary.
    On a pool study's folder (pool.json, from `pursuit-bench pool`): pool-report.json, pool.md, pool.png.
    On the rule study's folder (rule-study.json, runs/): rule-study-report.json, rule-study.md, rule-study.png.
    On the residual study's (residual-study.json, runs/): residual-study-report.json, .md and .png, its kinds
    compared pairwise as residual-study.json names them. On the budget study's (budget-study.json, runs/):
    budget-study-report.json, budget-study.md, budget-study.png and budget-fig2.png (interim, without
    verdicts, until all 6 panels are in)."""
    if not where.is_dir():  # before the statistics and the figures are imported: a refusal comes at once
        raise BadInput(f"{where}: no such folder" if not where.exists() else f"{where}: a file, not a folder")
    from pursuit_bench.reports import reproduction as reports

    if out is not None:
        check_out_folder(out)
    for marker, _, handler in FOLDERS:
        if (where / marker).is_file():
            handler(where, out or where)
            return
    try:
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
        totals = reports.write(where, out)
    except reports.NoRuns as error:  # none of the folders report reads: say which it does
        kinds = ", ".join(f"{what} ({marker})" for marker, what, _ in FOLDERS)
        raise BadInput(f"{error} (report also reads {kinds})") from None
    except ValueError as error:
        raise BadInput(str(error)) from None
    click.echo(
        f"{counted(totals['panels'], 'panel')}: {totals['better']} better, {totals['equivalent']} equivalent, "
        f"{totals['not resolved']} not resolved, {totals['worse']} worse (paired by seed, Holm-corrected); "
        f"highest mean in {totals['hierarchical_best']}"
    )
    for row in totals["budgets"]:
        click.echo(
            f"  at {row['episodes']} episodes: {row['better']} better, {row['equivalent']} equivalent, "
            f"{row['not resolved']} not resolved, {row['worse']} worse"
        )
    click.echo(f"written in {out or where}: {', '.join(totals['written'])}")


def _report_residual_study(where: Path, out: Path) -> None:
    _report_rule_study(where, out, "residual-study")


def _report_budget_study(where: Path, out: Path) -> None:
    from pursuit_bench.reports import budget_report

    try:
        summary = budget_report.write_report(where, out)
    except ValueError as error:
        raise BadInput(str(error)) from None
    state = "whole: verdicts written" if summary["whole_family"] else "interim: no verdicts until all 6 panels are in"
    click.echo(f"budget study, conditions in: {', '.join(summary['complete'])} ({state})")
    click.echo(f"written in {out}: budget-study-report.json, budget-study.md, budget-study.png, budget-fig2.png")


def _report_pool(where: Path, out: Path) -> None:
    """A pool study (``pursuit-bench pool``): its report rewritten from pool.json."""
    from pursuit_bench.reports import pool

    try:
        summary = pool.write_report(pool.load(where / "pool.json"), out)
    except ValueError as error:
        raise BadInput(str(error)) from None
    click.echo(pool.counts_markdown(summary))
    click.echo(f"written in {out}: pool-report.json, pool.md, pool.png")


def _report_rule_study(where: Path, out: Path, stem: str = "rule-study") -> None:
    """The rule study (issue 47), or a study of more kinds in its format (``stem``.json names the
    kinds, the comparisons and how far a run's margin must be from its twin's to differ): its report
    from the judged runs' compact results (runs/)."""
    from pursuit_bench.reports import rule_report

    try:
        study = rule_report.study_of(where, stem)
        summary = rule_report.write_report(where, out, stem, study.kinds, study.pairs, study.differs, study.seed_rule)
    except ValueError as error:
        raise BadInput(str(error)) from None
    click.echo(f"primary, {summary['primary']['measure']}: {rule_report.counts_line(summary['primary']['counts'])}")
    corrections = f", {stem}-corrections.png" if summary["secondary"].get("corrections") else ""
    click.echo(f"written in {out}: {stem}-report.json, {stem}.md, {stem}.png{corrections}")


def _report_run(folder: Path, out: Path) -> None:
    """One run: what was trained, how far, its last episodes and its evaluation, and curves.png."""
    from pursuit_bench.figures.plots import curves_png
    from pursuit_bench.io.files import atomic_write_bytes
    from pursuit_bench.reports import reproduction as reports

    config = json.loads((folder / "config.json").read_text())["train"]
    metrics = folder / "metrics.jsonl"
    rows = [json.loads(line) for line in metrics.read_text().splitlines()] if metrics.exists() else []
    click.echo(
        f"{folder}: {config['condition']}, {config['predator']} predators, {config['prey']} prey, "
        f"seed {config['seed']}: {len(rows)} of {config['episodes']} episodes trained"
    )
    if rows:
        last = rows[-min(100, len(rows)) :]
        means = {
            k.removeprefix("return/"): sum(r[k] for r in last) / len(last) for k in last[0] if k.startswith("return/")
        }
        capture = sum(r["captured"] for r in last) / len(last)
        click.echo(
            f"  last {len(last)} episodes: return "
            + " ".join(f"{k} {v:+.2f}" for k, v in means.items())
            + f" | capture {capture:.0%}"
        )
        result = reports.RunResult(
            folder.name,
            config["condition"],
            config["predator"],
            int(config["seed"]),
            {},
            {},
            reports.block_curve(rows),
            config,
        )
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(out / "curves.png", curves_png(reports.curves([result])))
        click.echo(f"  learning curves: {out / 'curves.png'}")
    for path in sorted(folder.glob("eval*.json")):
        result_json = json.loads(path.read_text())
        evaluated = result_json.get("trained_episodes")
        if evaluated is not None and evaluated < len(rows) and not path.stem.startswith("eval-ep"):
            click.echo(f"  {path.name}: stale, evaluated after {evaluated} episodes; the run has trained {len(rows)}")
        for panel in result_json["panels"]:
            click.echo(
                f"  {path.name}: {panel['predator']} {result_json['predator_kind']} {panel['trained']:+.3f}, "
                f"always-chase {panel['always_chase']:+.3f}, always-stalk {panel['always_stalk']:+.3f}"
            )


#: The folders ``report`` reads besides a sweep and its compact results, each told by the file
#: it holds (looked for in this order): the file, what the folder is, what writes its report.
FOLDERS: tuple[tuple[str, str, Callable[[Path, Path], None]], ...] = (
    ("config.json", "a run folder", _report_run),
    ("pool.json", "a pool study", _report_pool),
    ("rule-study.json", "the rule study's results", _report_rule_study),
    ("residual-study.json", "the residual study's results", _report_residual_study),
    ("budget-study.json", "the budget study's results", _report_budget_study),
)
