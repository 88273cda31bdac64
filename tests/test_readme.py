"""scripts/check_readme.py on a fast path: the shipped agents' figures evaluated afresh (seconds)
and the training run's spread over seeds from its committed source file."""

import gzip
import json
import math
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import load_script, run_cli
from scipy import stats

check_readme = load_script("scripts/check_readme.py")


def test_the_readme_quotes_the_shipped_agents_as_the_main_job_evaluates_them(tmp_path: Path) -> None:
    out = tmp_path / "demo-pretrained"
    code, output = run_cli(
        "eval", "--pretrained", "2p-high-individual", "--episodes", "300", "--out", str(out), "--no-record"
    )
    assert code == 0, output
    sentence = check_readme.shipped_sentence(json.loads((out / "eval.json").read_text()))
    assert sentence in check_readme.readme()


def test_the_readme_quotes_the_training_runs_spread_over_seeds() -> None:
    seeds = json.loads(check_readme.SEEDS.read_text())
    assert [s["seed"] for s in seeds["seeds"]] == [0, 1, 2, 3, 4]
    assert check_readme.spread_sentence(seeds) in check_readme.readme()
    seed0 = seeds["seeds"][0]
    assert check_readme.outside(seed0, seeds) == []
    moved = {**seed0, "always_chase": max(s["always_chase"] for s in seeds["seeds"]) + 0.01}
    assert check_readme.outside(moved, seeds) and "always_chase" in check_readme.outside(moved, seeds)[0]


def test_the_readme_s_answer_is_what_the_committed_results_give() -> None:
    """The answer's sentences and table, recomputed from results/rule-study/ (its seed rule
    applied) and results/reproduction/; the README gives it before the env's use, in at most 150
    lines. The counts are checked against the study's per-panel verdicts counted here."""
    counts = check_readme.answer()
    text = check_readme.ROOT.joinpath("README.md").read_text()
    assert check_readme.answer_block(counts) in text
    assert check_readme.study_block(counts) in (check_readme.ROOT / "REPRODUCTION.md").read_text()
    assert text.index("## What the project found") < text.index("## Use the env") and len(text.splitlines()) <= 150
    assert "[REPRODUCTION.md](REPRODUCTION.md)" in text
    by_hand = _rule_study_by_hand(counts["running"] + counts["not_started"])
    assert list(counts["rows"]["primary"]) == by_hand
    assert by_hand[0] == counts["all_panels"] - counts["running_panels"]


def test_the_readme_s_budget_study_line_and_row_follow_its_committed_runs() -> None:
    """The budget study's line and row: while its runs come in, the count of committed judged
    runs (counted here from the files) and no verdict; once all are in, the verdicts' counts."""
    counts = check_readme.answer()
    runs = sorted((check_readme.BUDGET_STUDY / "runs").glob("*-seed*.json.gz"))
    assert counts["budget"]["runs"] == len(runs) and counts["budget"]["planned"] == 60
    text = " ".join(check_readme.ROOT.joinpath("README.md").read_text().split())
    if len(runs) < 60:
        assert counts["budget"]["row"] is None
        assert f"is running, {len(runs)} of its 60 judged runs in" in text
        assert f"running: {len(runs)} of 60 runs in, no verdict yet) | 6 | – | – | – | – |" in text
    done = {**counts, "budget": {**counts["budget"], "runs": 60, "row": (6, 1, 2, 3, 0)}}
    sentence = check_readme.budget_sentence(done)
    assert "the rule helps in 1 of the 6 panels, the flat learner is better in 0, 2 are equivalent" in sentence
    assert "and 3 are not resolved" in sentence and "running" not in check_readme.budget_row(done)
    assert check_readme.budget_row(done).endswith("| 6 | 1 | 2 | 3 | 0 |")


def test_the_residual_study_s_24_primary_verdicts_recomputed_by_hand() -> None:
    """Every verdict of the residual study's primary table (docs/figures/residual-study/, what its
    block prints) is what a formula written here gives from results/residual-study/runs/: residual
    − hierarchical and residual − flat in each of the 12 panels, one family of 24."""
    report = json.loads((check_readme.ROOT / "docs/figures/residual-study/residual-study-report.json").read_text())
    rows = report["primary"]["panels"]
    returns = _pool_returns(check_readme.ROOT / "results" / "residual-study", [])
    pairs = [tuple(r["pair"]) for r in rows]
    by_hand = _verdicts_by_hand(
        [
            (returns[(r["condition"], r["predator"])][a], returns[(r["condition"], r["predator"])][b])
            for r, (a, b) in zip(rows, pairs, strict=True)
        ]
    )
    said = {"better": "ahead", "worse": "behind", "equivalent": "equivalent", "not resolved": "not resolved"}
    assert len(rows) == 24
    for row, (first, second), verdict in zip(rows, pairs, by_hand, strict=True):
        words = row["verdict"].removeprefix(f"{first} ").removesuffix(f" than {second}").split(": ")[-1]
        assert said[words] == verdict, (row["condition"], row["predator"], row["pair"], row["verdict"])


def test_docs_residual_md_s_study_block_is_what_the_committed_results_give() -> None:
    assert check_readme.residual_block() in check_readme.RESIDUAL_DOC.read_text()


def test_the_residual_study_s_headline_counts_what_its_tables_show() -> None:
    """The sentences above docs/residual.md's tables against the tables as rendered: each
    comparison's verdicts counted from the primary table's rows, each ladder's significant cells
    from its table's p (Holm) and sign."""
    block = check_readme.residual_block()
    if "### Primary" not in block:
        pytest.skip("no setting of the residual study judged yet")
    headline = " ".join(block.split("**On the primary measure**", 1)[1].split("###", 1)[0].split())
    primary = block.split("### Primary", 1)[1].split("\n### ", 1)[0]
    rows = [[c.strip(" *") for c in line.split("|")[1:-1]] for line in primary.splitlines() if line.startswith("| ")]
    verdicts: dict[str, list[str]] = {}
    for row in rows[1:]:
        verdicts.setdefault(row[2], []).append(row[-1])
    for comparison, found in verdicts.items():
        first, second = comparison.split(" − ")
        named = r"(\d+)(?: \([^)]*\))?"
        said = re.search(
            rf"{first} against {second}: better in {named}, worse in {named}, "
            rf"equivalent within ±[\d.]+ in {named}, not resolved in {named}",
            headline,
        )
        assert said is not None, comparison
        expected = [f"{first} better than {second}", f"{first} worse than {second}", "equivalent", "not resolved"]
        assert [int(n) for n in said.groups()] == [found.count(v) for v in expected]
    ladders = block.split("### Secondary: the robustness ladders", 1)[1].split("\n### ", 1)[0]
    tables = re.findall(r"\n(\S+) \(one Holm family of \d+\):\n\n((?:\|.*\n?)+)", ladders)
    assert len(tables) == 3
    for name, table in tables:
        cells = [[c.strip() for c in line.split("|")[1:-1]] for line in table.splitlines() if line.startswith("| ")]
        above = sum(float(c[-1]) <= 0.05 and float(c[-2].split()[0]) > 0 for c in cells[1:])
        below = sum(float(c[-1]) <= 0.05 and float(c[-2].split()[0]) < 0 for c in cells[1:])
        about = re.search(
            rf"above 0 in (\d+)(?: \([^)]*\))? of the {re.escape(name)} ladder's (\d+) cells and below 0 in (\d+)",
            headline,
        )
        assert about is not None, name
        assert (int(about[1]), int(about[2]), int(about[3])) == (above, len(cells) - 1, below)


def test_the_residual_study_s_block_judges_only_the_settings_whose_runs_are_all_in(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from test_rule_report import KINDS3, PAIRS3, three_kind_runs

    from pursuit_bench.reports import rule_study

    where = tmp_path / "residual-study"
    (where / "runs").mkdir(parents=True)
    about = {"kinds": list(KINDS3), "comparisons": [list(p) for p in PAIRS3], "differs": 0.05}
    about["settings"] = {s: {} for s in ("1p-high", "1p-high-obstacles4", "2p-high-individual", "3p-high-shared")}
    (where / "residual-study.json").write_text(json.dumps(about) + "\n")
    monkeypatch.setattr(check_readme, "RESIDUAL_STUDY", where)
    runs = [r for r in three_kind_runs(n=4) if r["name"] != "1p-high-obstacles4-flat-seed3"]
    for run in runs:
        extra = {k: run[k] for k in ("protocol", "episodes", "pool", "setting", "obstacles")}
        rule_study.write_run(where / "runs", run["name"], run["condition"], run["kind"], run["seed"], "abc", extra)
    block = check_readme.residual_block()
    assert block.startswith(check_readme.RESIDUAL_BEGIN) and block.endswith(check_readme.RESIDUAL_END)
    assert "1p-high-obstacles4 (4 hierarchical, 4 residual, 3 flat)" in block  # under way, named, not judged
    lead = " ".join(block.split("### Primary", 1)[0].split())
    assert "**Interim: 2 of the 4 settings judged** (1p-high, 2p-high-individual)" in lead
    assert "no run committed yet of 3p-high-shared." in lead
    assert "### Primary: the pool return at 15000 episodes" in block
    primary = block.split("### Primary", 1)[1].split("###", 1)[0]
    assert "| 1p-high | predator_0 |" in primary and "1p-high-obstacles4 |" not in primary
    for path in (where / "runs").glob("1p-high-*"):  # only the incomplete setting's runs
        if "obstacles4" in path.name:
            continue
        path.unlink()
    for path in (where / "runs").glob("2p-high-individual-*"):
        path.unlink()
    block = " ".join(check_readme.residual_block().split())  # a paragraph wrapped at 100 characters
    assert "**Nothing judged yet**" in block and "1p-high-obstacles4 (4 hierarchical, 4 residual, 3 flat)" in block
    assert "### Primary" not in block


def test_the_answer_blocks_are_written_only_between_their_markers(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text(f"before\n{check_readme.BEGIN}\nold\n{check_readme.END}\nafter\n")
    assert check_readme._with_block(page, check_readme.BEGIN, check_readme.END, "NEW") == "before\nNEW\nafter\n"
    for text in (f"{check_readme.BEGIN} no end", f"{check_readme.END} then {check_readme.BEGIN}", "none"):
        page.write_text(text)
        with pytest.raises(ValueError, match=r"page\.md: expected the markers"):
            check_readme._with_block(page, check_readme.BEGIN, check_readme.END, "NEW")


def _pool_returns(folder: Path, leave_out: list[str]) -> dict[tuple[str, str], dict[str, list[float]]]:
    """Per panel (setting, predator) and kind, each run's pool return at 15,000 episodes: its
    trained return averaged over the population's members, read from the committed run files;
    the runs of the conditions in ``leave_out`` left out."""
    returns: dict[tuple[str, str], dict[str, list[float]]] = {}
    for path in sorted((folder / "runs").glob("*.json.gz")):
        run = json.loads(gzip.decompress(path.read_bytes()))
        if run["condition"] in leave_out:
            continue
        members = run["pool"]["15000"]
        for predator in members["FleeingPrey"]["panels"]:
            value = float(np.mean([m["panels"][predator][0] for m in members.values()]))
            panel = (run.get("setting", run["condition"]), predator)
            returns.setdefault(panel, {}).setdefault(run["kind"], []).append(value)
    return returns


def _holm_by_hand(p: list[float]) -> list[float]:
    """Holm's step-down adjusted p-values, written out: the k-th smallest times (m − k), each at
    least the one before it, at most 1."""
    adjusted, running_max = [0.0] * len(p), 0.0
    for rank, i in enumerate(sorted(range(len(p)), key=lambda j: p[j])):
        running_max = max(running_max, min(1.0, (len(p) - rank) * p[i]))
        adjusted[i] = running_max
    return adjusted


def _verdicts_by_hand(comparisons: list[tuple[list[float], list[float]]], margin: float = 0.05) -> list[str]:
    """Each comparison's verdict in one family, by formulas written here (scipy's Welch t-test,
    not the study's code): "ahead" or "behind" when Welch's two-sided p, Holm-adjusted over the
    family, is at most 0.05; else "equivalent" when the two one-sided Welch tests against
    ±``margin`` (TOST: the first kind shifted by the margin, which leaves the variances as they
    are) give a larger p that is, Holm-adjusted over the family, at most 0.025; else "not resolved"."""
    welch = [stats.ttest_ind(a, b, equal_var=False) for a, b in comparisons]
    tost = [
        max(
            stats.ttest_ind(np.add(a, margin), b, equal_var=False, alternative="greater").pvalue,
            stats.ttest_ind(np.subtract(a, margin), b, equal_var=False, alternative="less").pvalue,
        )
        for a, b in comparisons
    ]
    verdicts = []
    for test, differs, same in zip(welch, _holm_by_hand([t.pvalue for t in welch]), _holm_by_hand(tost), strict=True):
        if differs <= 0.05:
            verdicts.append("ahead" if test.statistic > 0 else "behind")
        else:
            verdicts.append("equivalent" if same <= 0.025 else "not resolved")
    return verdicts


def _rule_study_by_hand(running: list[str]) -> list[int]:
    """The primary row of the README's table recomputed from results/rule-study/runs/: panels
    judged, rule helps, equivalent, not resolved, flat better (hierarchical − flat, one family)."""
    returns = _pool_returns(check_readme.RULE_STUDY, running)
    verdicts = _verdicts_by_hand([(k["hierarchical"], k["flat"]) for k in returns.values()])
    return [len(verdicts), *(verdicts.count(v) for v in ("ahead", "equivalent", "not resolved", "behind"))]


def test_the_readme_keeps_none_of_the_sentences_an_audit_found_wrong() -> None:
    words = check_readme.readme().lower()
    for wrong in ("without qualification", "gains nothing detectable", "spread widely", "on the same episodes"):
        assert wrong not in words, wrong


def python_blocks(path: Path) -> list[str]:
    """Every ```python block of a Markdown file, dedented (some sit in a list item)."""
    blocks = re.findall(r"^( *)```python\n(.*?)^\1```", path.read_text(), flags=re.S | re.M)
    return [textwrap.dedent("\n".join(line[len(indent) :] for line in body.splitlines())) for indent, body in blocks]


def test_the_package_description_has_no_relative_link_or_image() -> None:
    """The wheel's long description (DESCRIPTION.md) is shown on a package index's page, where a
    link or an image relative to the repository is broken: every target must be absolute."""
    description = _relative_targets((check_readme.ROOT / "DESCRIPTION.md").read_text())
    assert description == [], description
    # the same reading finds the README's own relative links and images (the README is shown
    # on GitHub, where they work): a reading that found nothing would pass above whatever it read
    readme = _relative_targets(check_readme.readme())
    assert "docs/figures/episode.png" in readme and any(t.endswith(".md") for t in readme), readme


def _relative_targets(text: str) -> list[str]:
    """The targets of a Markdown text's links and images (``[a](t)``, ``<img src="t">``) that are not
    absolute ``http(s)://`` addresses."""
    targets = re.findall(r"\]\(([^)\s]+)", text) + re.findall(r"<img[^>]*src=[\"']([^\"']+)", text)
    return [t for t in targets if not re.match(r"https?://", t)]


@pytest.mark.slow
def test_every_python_block_of_the_readme_and_of_use_md_runs_as_written(tmp_path: Path) -> None:
    """One interpreter per file, its blocks run one after another (as a reader would paste them);
    docs/use.md loads the main job's run folder, trained here for 2 episodes."""
    code, output = run_cli(
        "train", "--condition", "1p-high", "--episodes", "2", "--no-record", "--out", str(tmp_path / "runs" / "demo")
    )
    assert code == 0, output
    readme, use = python_blocks(check_readme.ROOT / "README.md"), python_blocks(check_readme.ROOT / "docs" / "use.md")
    package = python_blocks(check_readme.ROOT / "DESCRIPTION.md")
    assert len(readme) == 1 and "pursuit_v0" in readme[0] and len(use) >= 2 and "load_agents" in use[0]
    assert package == readme  # the package index's page shows the README's example
    for blocks in (readme, use):
        script = "\n\n".join(blocks)
        done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True)
        assert done.returncode == 0, f"{script}\n{done.stderr}"


def _close(a: object, b: object) -> bool:
    """Two JSON values alike, floats to 1e-12 relative: dicts with the same keys, lists of the
    same length, everything else equal."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12)
    return type(a) is type(b) and a == b


@pytest.mark.long
@pytest.mark.parametrize("stem", ["rule-study", "residual-study"])
def test_a_study_s_committed_report_regenerates(tmp_path: Path, stem: str) -> None:
    """docs/figures/<stem>/ (REPRODUCTION.md's or docs/residual.md's figures, and the report its
    block quotes) is what `pursuit-bench report results/<stem>` writes from the committed results:
    the tables and figures byte for byte; the JSON's numbers to 1e-12 relative, since SciPy's
    Boschloo p-values (a numerical maximisation) differ in their last bits from one CPU to another
    (seen: 0.3662940152851117 on one machine, 0.36629401528511163 on the next)."""
    code, output = run_cli("report", str(check_readme.ROOT / "results" / stem), "--out", str(tmp_path))
    assert code == 0, output
    committed = check_readme.ROOT / "docs" / "figures" / stem
    names = [f"{stem}-report.json", f"{stem}.md", f"{stem}.png"]
    if (tmp_path / f"{stem}-corrections.png").exists() or (committed / f"{stem}-corrections.png").exists():
        names.append(f"{stem}-corrections.png")  # a study with a residual kind's corrections
    for name in names:
        if name.endswith(".json"):
            assert _close(json.loads((tmp_path / name).read_text()), json.loads((committed / name).read_text())), name
        else:
            assert (tmp_path / name).read_bytes() == (committed / name).read_bytes(), name
