"""Check that the figures the README quotes for the main job are what the main job gives.

    bash scripts/demo.sh && .venv/bin/python scripts/check_readme.py

The shipped agents' figures (``runs/demo-pretrained/eval.json``) must be in the README exactly:
evaluating shipped weights repeats on any machine. The short training run's figures
(``runs/demo/eval.json``) repeat bit for bit on one machine but not across machines, so the
README gives them as the spread over seeds 0–4 measured here (``results/readme/main-job.json``,
written by ``--record-seeds``), and this script checks that the README quotes that spread and
that the main job's seed-0 figures lie inside it. The README's answer (the block between its
``answer:begin`` and ``answer:end`` markers: the sentences that quote the counts, and the table)
is recomputed from the committed results (``results/rule-study/``, ``results/reproduction/``), as are
REPRODUCTION.md's rule-study block and docs/residual.md's residual-study block
(``results/residual-study/``). Exits 1 naming any sentence the README lacks or block that differs.

    python scripts/check_readme.py --record-seeds MAINJOB/seed*   # run folders of seeds 0-4
    python scripts/check_readme.py --write-answer                 # rewrite the answer block
"""

from __future__ import annotations

import argparse
import functools
import json
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SEEDS = ROOT / "results" / "readme" / "main-job.json"
VARIANTS = ("trained", "always_chase", "always_stalk")


def signed(value: float) -> str:
    """``+0.27`` / ``−0.25`` (a typographic minus, as the README writes it)."""
    return f"{value:+.2f}".replace("-", "−")


def shipped_sentence(result: dict[str, Any]) -> str:
    """What the README says of the shipped agents' evaluation (``eval --pretrained``)."""
    panels = result["panels"]

    def joined(key: str) -> str:
        return " / ".join(signed(p[key]) for p in panels)

    return (
        f"{joined('trained')} against always-chase's {joined('always_chase')} and "
        f"always-stalk's {joined('always_stalk')}"
    )


def spread_sentence(seeds: dict[str, Any]) -> str:
    """What the README says of the short training run over seeds 0–4."""

    def span(key: str) -> str:
        values = [s[key] for s in seeds["seeds"]]
        return f"{signed(min(values))} to {signed(max(values))}"

    return (
        f"the hierarchical predator scores {span('trained')}, always-chase {span('always_chase')} and "
        f"always-stalk {span('always_stalk')}"
    )


def outside(trained: dict[str, Any], seeds: dict[str, Any]) -> list[str]:
    """The main job's figures that lie outside the recorded spread over seeds (empty if none)."""
    out = []
    for key in VARIANTS:
        values = [s[key] for s in seeds["seeds"]]
        if not min(values) <= trained[key] <= max(values):
            out.append(f"{key} {trained[key]:+.3f} outside [{min(values):+.3f}, {max(values):+.3f}]")
    return out


#: The answer's table: its rows' labels, and what each row counts (the rule study's summary at
#: the last budget, or the reproduction's verdicts against the fixed modes).
ANSWER_ROWS = (
    ("hierarchical − flat: return against the population at {last:,} episodes (**primary**)", "primary"),
    ("hierarchical − flat: margin over the fixed modes at {last:,} episodes (secondary)", "margin"),
    ("hierarchical − flat: return averaged over {first}–{last:,} episodes (head start, secondary)", "head_start"),
    (
        "learned stalk/chase switch − better fixed mode, own prey, {last:,} episodes (the paper's comparison: "
        "both steer by the rule; earlier evaluation)",
        "fixed_modes",
    ),
)
RULE_STUDY = ROOT / "results" / "rule-study"
BUDGET_STUDY = ROOT / "results" / "budget-study"
REPRODUCTION = ROOT / "results" / "reproduction"
BEGIN = "<!-- answer:begin: scripts/check_readme.py --write-answer writes this block -->"
END = "<!-- answer:end -->"
STUDY_BEGIN = "<!-- rule-study:begin: scripts/check_readme.py --write-answer writes this block -->"
STUDY_END = "<!-- rule-study:end -->"
RESIDUAL_STUDY = ROOT / "results" / "residual-study"
RESIDUAL_BEGIN = "<!-- residual-study:begin: scripts/check_readme.py --write-answer writes this block -->"
RESIDUAL_END = "<!-- residual-study:end -->"
RESIDUAL_DOC = ROOT / "docs" / "residual.md"


@functools.cache
def rule_study_summary() -> dict[str, Any]:
    """The rule study's report (``rule_report.summarise``) of the committed results, its seed rule
    applied: a condition whose runs the rule still asks for is left out."""
    from pursuit_bench.reports import rule_report, rule_study

    runs = rule_study.read_runs(RULE_STUDY / "runs")
    return rule_report.summarise(runs, seed_rule=rule_report.study_of(RULE_STUDY).seed_rule)


def answer() -> dict[str, Any]:
    """The counts the README's answer quotes, from the committed results: per row of its table
    (panels, rule ahead, equivalent, not resolved, rule behind), the panels judged and the
    conditions still running (the rule study's seed rule applied), per kind the panels where
    its runs fail significantly more often (reliability, Holm), and per budget before the last
    the primary measure's "rule helps" and "flat better" counts (each budget its own Holm family)."""
    from pursuit_bench import stats
    from pursuit_bench.env.conditions import CONDITIONS
    from pursuit_bench.reports import reproduction as report

    summary = rule_study_summary()
    rows: dict[str, tuple[int, ...]] = {}
    for key in ("primary", "margin", "head_start"):
        counts = (summary if key == "primary" else summary["secondary"])[key]["counts"]
        order = ("rule helps", "equivalent", "not resolved", "flat better")
        rows[key] = (sum(counts.values()), *(counts[v] for v in order))
    table = report.panel_table(report.collect(REPRODUCTION))
    report.judge(table)
    verdicts = [t["verdict"] for t in table if "verdict" in t]
    order = ("better", "equivalent", "not resolved", "worse")
    rows["fixed_modes"] = (len(verdicts), *(verdicts.count(v) for v in order))
    judged = {r["condition"] for r in summary["primary"]["panels"]}
    fail_more: dict[str, dict[str, list[tuple[str, str]]]] = {}
    for line, key in (("failure", "reliability"), ("zero", "reliability_below_zero")):
        more: dict[str, list[tuple[str, str]]] = {"flat": [], "hierarchical": []}
        for r in summary["secondary"][key]:
            # two-sided at 2 ALPHA, as the verdicts; the difference is hierarchical's share − flat's
            if r["difference"]["p_holm"] <= 2 * stats.ALPHA:
                more["hierarchical" if r["difference"]["difference"] > 0 else "flat"].append(
                    (r["condition"], r["predator"])
                )
        fail_more[line] = more
    return {
        "rows": rows,
        "budgets": {"first": summary["budgets"][0], "last": summary["budgets"][-1]},
        "all_panels": sum(c.n_predators for c in CONDITIONS.values()),
        "running": [c for c in CONDITIONS if c in summary.get("in_progress", {})],
        "not_started": [c for c in CONDITIONS if c not in judged and c not in summary.get("in_progress", {})],
        "running_panels": sum(CONDITIONS[c].n_predators for c in CONDITIONS if c not in judged),
        "fail_more": fail_more,
        "failure_margin": summary["failure_margin"],
        "by_budget": [
            (b["episodes"], b["counts"]["rule helps"], b["counts"]["flat better"])
            for b in summary["secondary"]["budgets"]
        ],
        "head_start_weights": _trapezoid_weights(summary["budgets"]),
        "budget": budget_answer(),
    }


def budget_answer() -> dict[str, Any]:
    """The budget study's state (``results/budget-study``): its judged runs in and planned, and
    once all are in (the whole family: ``budget_report.summarise``) the primary verdicts' counts
    in the table's order (panels, rule helps, equivalent, not resolved, flat better)."""
    from pursuit_bench.reports import budget_report

    runs = budget_report.read_runs(BUDGET_STUDY)
    planned = len(budget_report.CONDITIONS) * len(budget_report.KINDS) * len(budget_report.SEEDS)
    done, _ = budget_report.complete(runs)
    out: dict[str, Any] = {"runs": len(runs), "planned": planned, "panels": budget_report.PANELS, "row": None}
    if len(done) == len(budget_report.CONDITIONS):
        counts = budget_report.summarise(runs)["primary"]["counts"]
        out["row"] = (
            budget_report.PANELS,
            *(counts[v] for v in ("rule helps", "equivalent", "not resolved", "flat better")),
        )
    return out


def _trapezoid_weights(budgets: list[int]) -> list[float]:
    """Each budget's share of the head start's average (trapezoids on a log-episode axis over the
    span, as ``rule_report.head_start``): the weights sum to 1."""
    gaps = np.diff(np.log(budgets)) / (np.log(budgets[-1]) - np.log(budgets[0]))
    return [float(w) for w in (np.concatenate([gaps, [0.0]]) + np.concatenate([[0.0], gaps])) / 2]


def answer_table(counts: dict[str, Any]) -> str:
    """The README's table of the answer, from ``answer()``."""
    header = ("panels", "first ahead", "equivalent (±0.05)", "not resolved", "first behind")
    lines = [
        "| comparison, per panel | " + " | ".join(header) + " |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {label.format(**counts['budgets'])} | " + " | ".join(map(str, counts["rows"][key])) + " |"
        for label, key in ANSWER_ROWS
    ]
    lines.insert(3, budget_row(counts))  # beside the primary row at 15,000 episodes
    return "\n".join(lines)


def budget_row(counts: dict[str, Any]) -> str:
    """The table's row of the budget study's primary verdicts (dashes while it runs)."""
    budget = counts["budget"]
    cells = budget["row"] or (budget["panels"], *["–"] * 4)
    running = "" if budget["row"] else f"; running: {budget['runs']} of {budget['planned']} runs in, no verdict yet"
    return (
        "| hierarchical − flat: return against a population trained as long, at 10⁶ episodes (the budget study, "
        f"**primary**; 3 conditions{running}) | " + " | ".join(map(str, cells)) + " |"
    )


def _panels(panels: list[tuple[str, str]]) -> str:
    """``4 panels (3p-low-shared, 3p-high-individual's predator_1)``: a condition named alone where
    all its panels are listed; ``none`` for none."""
    from pursuit_bench.env.conditions import CONDITIONS

    if not panels:
        return "none"
    by: dict[str, list[str]] = {}
    for condition, predator in panels:
        by.setdefault(condition, []).append(predator)
    names = [c if len(p) == CONDITIONS[c].n_predators else f"{c}'s {' and '.join(p)}" for c, p in by.items()]
    return f"{len(panels)} panel{'s' if len(panels) > 1 else ''} ({', '.join(names)})"


def answer_sentences(counts: dict[str, Any]) -> list[str]:
    """The README's sentences that quote the answer's counts (the bold one first)."""
    primary, head = counts["rows"]["primary"], counts["rows"]["head_start"]
    judged = primary[0]
    waiting = counts["running"] + counts["not_started"]
    so_far = "" if not waiting else " so far"
    behind = "none" if head[4] == 0 else str(head[4])
    fail = counts["fail_more"]
    budgets = counts["by_budget"]
    at = _listed([f"{helps} at {_episodes(e)}" for e, helps, _ in budgets])
    flat_at = _listed([str(flat) for _, _, flat in budgets])
    early = budgets[:2]
    weight = sum(counts["head_start_weights"][: len(early)])
    sentences = [
        f"**On the primary measure, fixed before the runs, the rule helps in {primary[1]} of the {judged} "
        f"panels judged{so_far}, the flat learner is better in {primary[4]}, {primary[2]} are equivalent "
        f"within ±0.05 and {primary[3]} are not resolved.**",
        f"The rule gives a head start (secondary) that shrinks with training: by the primary test repeated at "
        f"the earlier budgets (secondary; each budget its own Holm family; no test of the trend) the rule is "
        f"ahead in {at} episodes, and the flat learner in {flat_at}; averaged over "
        f"{counts['budgets']['first']}–{counts['budgets']['last']:,} episodes on a log-episode axis, which puts "
        f"{weight * 100:.0f} % of its weight on "
        f"{_listed([_episodes(e) for e, _, _ in early])} episodes, the return is "
        f"significantly higher with the rule in {head[1]} of the {judged} panels and lower in {behind}.",
        f"Reliability (secondary), a result of its own, depends on where failure is drawn: at "
        f"{abs(counts['failure_margin']):.2f} below the better fixed mode put in a run's place (the line "
        f"fixed before the runs) the flat learner's runs fail significantly more often in "
        f"{_panels(fail['failure']['flat'])} and the hierarchical predator's in "
        f"{_panels(fail['failure']['hierarchical'])}; at 0 (the sensitivity check) the flat learner's in "
        f"{_panels(fail['zero']['flat'])} and the hierarchical predator's in "
        f"{_panels(fail['zero']['hierarchical'])} (Holm).",
    ]
    if waiting:
        parts = [f"{', '.join(counts[key])} ({words})" for key, words in (("running", "runs in training"),
                 ("not_started", "not started")) if counts[key]]  # fmt: skip
        sentences.insert(
            1,
            f"Not judged yet: {'; '.join(parts)}, {counts['running_panels']} of the {counts['all_panels']} panels; "
            f"until they are in, Holm runs over the {judged} panels judged, so every count here is interim (one "
            f"can fall as the family grows to {counts['all_panels']}).",
        )
    return sentences


def budget_sentence(counts: dict[str, Any]) -> str:
    """The README's sentence on the budget study (its line in the answer): where it stands, or
    once all its runs are in, its primary verdicts."""
    budget = counts["budget"]
    if budget["row"] is None:
        return (
            f"At the paper's budget, 10⁶ episodes, the budget study (fixed before its runs: 3 conditions, "
            f"{budget['panels']} panels, 10 runs a kind) is running, {budget['runs']} of its {budget['planned']} "
            'judged runs in; nothing of it is judged until all are (REPRODUCTION.md, "The paper\'s budget").'
        )
    _, helps, equivalent, unresolved, flat = budget["row"]
    return (
        f"**At the paper's budget, 10⁶ episodes** (the budget study, fixed before its runs: 3 conditions, "
        f"{budget['panels']} panels, 10 runs a kind, against a population trained as long), the rule helps in "
        f"{helps} of the {budget['panels']} panels, the flat learner is better in {flat}, {equivalent} are "
        f"equivalent within ±0.05 and {unresolved} are not resolved."
    )


def _episodes(episodes: int) -> str:
    """``1500``, ``5000``, ``10,500``: a budget as the prose writes it (a comma from five digits)."""
    return f"{episodes:,}" if episodes >= 10_000 else str(episodes)


def _listed(items: list[str]) -> str:
    """``a, b, c and d``; ``a``; ``none`` for none."""
    if not items:
        return "none"
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def _wrapped(text: str) -> str:
    """``text`` as one paragraph wrapped at 100 characters, never inside a word or a name."""
    return textwrap.fill(text, 100, break_long_words=False, break_on_hyphens=False)


def _paragraph(counts: dict[str, Any]) -> str:
    """The answer's sentences as one paragraph, wrapped at 100 characters."""
    return _wrapped(" ".join(answer_sentences(counts)))


def answer_block(counts: dict[str, Any]) -> str:
    """The README's generated block: the sentences, the budget study's, then the table, between
    the markers."""
    paragraph = _wrapped(" ".join([*answer_sentences(counts), budget_sentence(counts)]))
    return "\n".join([BEGIN, paragraph, "", answer_table(counts), END])


def study_block(counts: dict[str, Any]) -> str:
    """REPRODUCTION.md's generated block of the rule study: the README's sentences, then the
    study's report (``pursuit-bench report results/rule-study``'s rule-study.md), its headings one
    level down."""
    from pursuit_bench.reports import rule_report

    tables = ("\n" + rule_report.markdown(rule_study_summary())).replace("\n## ", "\n### ").strip()
    return "\n".join([STUDY_BEGIN, _paragraph(counts), "", tables, STUDY_END])


def _panels_named(rows: list[dict[str, Any]], every: dict[str, int]) -> str:
    """The panels of ``rows`` by setting: ``1p-high``; ``every predator of 3p-low-individual``;
    ``2p-high-individual predator_0``. ``every``: each setting's number of panels."""
    by_setting: dict[str, list[str]] = {}
    for row in rows:
        by_setting.setdefault(row["condition"], []).append(row["predator"])
    named = []
    for setting, predators in by_setting.items():
        if every[setting] == 1:
            named.append(setting)
        elif len(predators) == every[setting]:
            named.append(f"every predator of {setting}")
        else:
            named.append(f"{setting} {' and '.join(predators)}")
    return "; ".join(named)


def residual_headline(summary: dict[str, Any]) -> str:
    """What the study's report says, in sentences: each comparison's primary verdicts with the
    panels named, then each robustness ladder's cells where the residual predator's margin changes
    significantly more or less favourably than the hierarchical one's (Holm per ladder), settings named."""
    from pursuit_bench import stats

    panels = summary["primary"]["panels"]
    first_pair = list(summary["comparisons"][0])
    every: dict[str, int] = {}
    for row in panels:
        if row["pair"] == first_pair:
            every[row["condition"]] = every.get(row["condition"], 0) + 1
    parts = []
    for first, second in summary["comparisons"]:
        rows = [r for r in panels if r["pair"] == [first, second]]
        verdicts = [
            ("better in", f"{first} better than {second}"),
            ("worse in", f"{first} worse than {second}"),
            (f"equivalent within ±{summary['equivalence_margin']:g} in", "equivalent"),
            ("not resolved in", "not resolved"),
        ]
        said = []
        for words, verdict in verdicts:
            chosen = [r for r in rows if r["verdict"] == verdict]
            said.append(f"{words} {len(chosen)}" + (f" ({_panels_named(chosen, every)})" if chosen else ""))
        parts.append(f"{first} against {second}: " + ", ".join(said))
    text = (
        f"**On the primary measure** ({summary['primary']['measure']}, fixed before the runs; Holm over "
        f"{len(panels)} tests, {sum(every.values())} panels): " + "; ".join(parts) + "."
    )
    ladders = summary["secondary"].get("ladders", {})
    said = []
    for name, ladder in ladders.items():
        sides = [
            stats.difference_verdict(c["difference"]["mean"], c["difference"]["p_holm"], None, ("below", "above"))
            for c in ladder["cells"]
        ]
        found = []
        for side in ("above", "below"):
            hit = [c for c, s in zip(ladder["cells"], sides, strict=True) if s == side]
            at: dict[str, list[str]] = {}
            for cell in hit:
                at.setdefault(cell["setting"], []).append(f"{cell['rung']:g}")
            where = "; ".join(f"{s} at {', '.join(r)}" for s, r in at.items())
            found.append(f"{side} 0 in {len(hit)}" + (f" ({where})" if hit else ""))
        said.append(f"{found[0]} of the {name} ladder's {len(ladder['cells'])} cells and {found[1]}")
    if said:
        first, second = next(iter(ladders.values()))["pair"]
        text += (
            f" **On the robustness ladders** (secondary; the change of a run's margin from the unperturbed "
            f"level, {first} − {second} paired by seed, Holm per ladder; above 0: the {first} predator "
            f"the more robust), the difference is significantly " + "; ".join(said) + "."
        )
    return _wrapped(text)


def residual_block() -> str:
    """docs/residual.md's generated block: the residual study's report
    (``pursuit-bench report results/residual-study``'s residual-study.md, its headings one level
    down) over the settings whose runs are all in, led by what is not judged yet; before any
    setting is complete, only that."""
    from pursuit_bench.reports import rule_report, rule_study

    study = rule_report.study_of(RESIDUAL_STUDY, "residual-study")
    runs = rule_study.read_runs(RESIDUAL_STUDY / "runs")
    done, waiting = rule_report.complete_settings(runs, study.kinds, study.seed_rule)
    held = {rule_report.setting_of(r) for r in runs}
    not_begun = [s for s in study.settings if s not in held]
    if not done:
        text = (
            f"**Nothing judged yet**: no setting holds every run its seed rule asks for, of all "
            f"{len(study.kinds)} kinds. Committed so far: {len(runs)} judged run{'' if len(runs) == 1 else 's'}"
            f"{'; under way: ' + rule_report.in_progress_text(waiting) if waiting else ''}"
            f"{'; none yet of ' + ', '.join(not_begun) if not_begun else ''}. This page makes no claim about "
            "how the residual predator compares until one does."
        )
        return "\n".join([RESIDUAL_BEGIN, _wrapped(text), RESIDUAL_END])
    summary = rule_report.summarise(
        runs, kinds=study.kinds, pairs=study.pairs, differs=study.differs, seed_rule=study.seed_rule
    )
    tables = ("\n" + rule_report.markdown(summary, study.differs)).replace("\n## ", "\n### ").strip()
    tables = residual_headline(summary) + "\n\n" + tables
    judged = list(dict.fromkeys(rule_report.setting_of(r) for r in done))
    if len(judged) < len(study.settings):
        panels = len(summary["primary"]["panels"])
        lead = (
            f"**Interim: {len(judged)} of the {len(study.settings)} settings judged** ({', '.join(judged)}). Holm runs "
            f"over their {panels} tests, not over the protocol's family of every setting (each ladder's family "
            "likewise over these settings' cells: final once every setting it runs in is judged, as the obstacles "
            "ladder's is once the four plain settings are, the only ones it runs in); adding tests can only raise "
            "an adjusted p, so the final verdicts can be "
            "weaker than these, never stronger (better or worse can fall to equivalent or not resolved, "
            "equivalent to not resolved)"
            f"{'; no run committed yet of ' + ', '.join(not_begun) if not_begun else ''}."
        )
        tables = _wrapped(lead) + "\n\n" + tables
    return "\n".join([RESIDUAL_BEGIN, tables, RESIDUAL_END])


def _with_block(path: Path, begin: str, end: str, block: str) -> str:
    """``path``'s text with what lies between its ``begin`` and ``end`` markers (both included)
    replaced by ``block``; ValueError naming the file where a marker is missing or out of order."""
    text = path.read_text()
    start, stop = text.find(begin), text.find(end)
    if start < 0 or stop < start:
        raise ValueError(f"{path.name}: expected the markers {begin!r} and then {end!r}")
    return text[:start] + block + text[stop + len(end) :]


def write_answer() -> None:
    """Rewrite the README's answer block, REPRODUCTION.md's rule-study block and docs/residual.md's
    residual-study block from the results: every file checked before any is written, each written
    whole or not at all."""
    from pursuit_bench.io.files import atomic_write_text

    counts = answer()
    texts = {
        ROOT / "README.md": _with_block(ROOT / "README.md", BEGIN, END, answer_block(counts)),
        ROOT / "REPRODUCTION.md": _with_block(ROOT / "REPRODUCTION.md", STUDY_BEGIN, STUDY_END, study_block(counts)),
        RESIDUAL_DOC: _with_block(RESIDUAL_DOC, RESIDUAL_BEGIN, RESIDUAL_END, residual_block()),
    }
    for path, text in texts.items():
        atomic_write_text(path, text)


def readme() -> str:
    return " ".join((ROOT / "README.md").read_text().split())  # line breaks as spaces


def record_seeds(folders: list[Path]) -> None:
    """Write results/readme/main-job.json from the runs of the main job's training on several seeds."""
    rows = []
    for folder in folders:
        config = json.loads((folder / "config.json").read_text())["train"]
        panel = json.loads((folder / "eval.json").read_text())["panels"][0]
        rows.append({"seed": config["seed"], **{key: panel[key] for key in VARIANTS}})
    payload = {
        "command": "scripts/demo.sh's training and evaluation, --seed S",
        "seeds": sorted(rows, key=lambda r: r["seed"]),
    }
    SEEDS.parent.mkdir(parents=True, exist_ok=True)
    SEEDS.write_text(json.dumps(payload, indent=2) + "\n")
    print(f"{SEEDS}: {len(rows)} seeds")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record-seeds", type=Path, nargs="+", default=None, help="Run folders of seeds 0–4.")
    parser.add_argument(
        "--write-answer",
        action="store_true",
        help="Rewrite the README's answer, REPRODUCTION.md's rule-study block and docs/residual.md's study block.",
    )
    args = parser.parse_args()
    if args.write_answer:
        try:
            write_answer()
        except ValueError as error:
            print(f"check_readme: {error}", file=sys.stderr)
            return 2
        return 0
    if args.record_seeds:
        record_seeds(args.record_seeds)
        return 0
    seeds = json.loads(SEEDS.read_text())
    shipped = json.loads((ROOT / "runs/demo-pretrained/eval.json").read_text())
    trained = json.loads((ROOT / "runs/demo/eval.json").read_text())["panels"][0]
    text = readme()
    counts = answer()
    quoted = (shipped_sentence(shipped), spread_sentence(seeds))
    problems = [f"README.md lacks: {s!r}" for s in quoted if s not in text]
    if answer_block(counts) not in (ROOT / "README.md").read_text():
        problems.append(f"README.md's answer is not what the results give (--write-answer):\n{answer_block(counts)}")
    if study_block(counts) not in (ROOT / "REPRODUCTION.md").read_text():
        problems.append("REPRODUCTION.md's rule-study block is not what the results give (--write-answer)")
    if residual_block() not in RESIDUAL_DOC.read_text():
        problems.append("docs/residual.md's residual-study block is not what the results give (--write-answer)")
    problems += [f"runs/demo/eval.json: {line}" for line in outside(trained, seeds)]
    for problem in problems:
        print(problem, file=sys.stderr)
    if not problems:
        print("README.md quotes the shipped agents' figures exactly and the training run inside its spread over seeds")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
