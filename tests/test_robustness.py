"""The robustness study's tests and tables (pursuit_bench/analysis/robustness.py, docs/robustness.md):
each family corrected by Holm, verdicts that follow the corrected tests, and a doc whose tables
and quoted intervals are what the committed result gives."""

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from cli_helpers import load_script
from scipy import stats as scipy_stats

from pursuit_bench import stats
from pursuit_bench.analysis import robustness
from pursuit_bench.reports import pool

ROOT = Path(__file__).parents[1]
robustness_study = load_script("studies/robustness/robustness_study.py")

#: An interval as the tables print it (``-0.498 [-0.721, -0.275]``) or the text quotes it
#: (``−0.498 [−0.721, −0.275]``, or a loss unsigned: ``0.137 [0.017, 0.258]``).
INTERVAL = re.compile(r"([+−-]?\d+\.\d+) \[([+−-]?\d+\.\d+), ([+−-]?\d+\.\d+)\]")


@pytest.fixture(scope="module")
def committed() -> dict[str, Any]:
    return robustness_study.load()  # summaries and tests recomputed from the committed evaluations


def _intervals(text: str) -> set[tuple[float, ...]]:
    return {tuple(round(float(x.replace("−", "-")), 3) for x in match.groups()) for match in INTERVAL.finditer(text)}


def test_every_table_in_the_doc_is_what_the_script_gives(committed: dict[str, Any]) -> None:
    found = robustness_study.blocks((ROOT / "docs" / "robustness.md").read_text())
    fresh = robustness.sections(committed)
    assert sorted(found) == sorted(fresh)
    for name, table in fresh.items():
        assert found[name] == table, f"docs/robustness.md's {name!r} table differs: {robustness_study.COMMAND}"
    kinds = {(s["condition"], s["kind"]) for s in committed["sources"]}
    assert len(kinds) == 8 and all(len(committed["crossplay"][c][k]["seeds"]) == 5 for c, k in kinds)


def test_every_interval_and_family_the_text_quotes_is_the_tables(committed: dict[str, Any]) -> None:
    text = (ROOT / "docs" / "robustness.md").read_text()
    prose = " ".join(robustness_study.BLOCK.sub("", text).split())  # an interval may break across lines
    tables = "\n".join(robustness.sections(committed).values())
    # the other kind's prey: REPRODUCTION.md's cross-kind table, from the committed pool result
    tables += pool.cross_markdown(pool.cross_kind(json.loads((ROOT / "results" / "pool" / "pool.json").read_text())))
    known = _intervals(tables)
    known |= {(-m, -high, -low) for m, low, high in known}  # a loss quoted unsigned
    quoted = _intervals(prose)
    assert len(quoted) > 40
    assert sorted(quoted - known) == []
    holm = set(re.findall(r"Holm p (\d\.\d{3})", prose))
    assert holm and holm <= set(re.findall(r"\b(\d\.\d{3})\b", tables))
    for name, size in re.findall(r"`([a-z ]+)` \((\d+)\)", prose):
        assert committed["families"][name]["counts"]["comparisons"] == int(size), name


#: An interval the text quotes and the Holm p it gives for it, in one clause (no other interval
#: between them).
QUOTED_P = re.compile(INTERVAL.pattern + r"[^\[\]]{0,90}?Holm p (\d\.\d{3})")


def test_each_quoted_holm_p_is_the_one_of_its_own_row(committed: dict[str, Any]) -> None:
    """A Holm p quoted beside an interval sits in the same table row as that interval (signed
    as quoted or, for a loss quoted unsigned, negated): a p from another row fails."""
    text = (ROOT / "docs" / "robustness.md").read_text()
    prose = " ".join(robustness_study.BLOCK.sub("", text).split())
    rows = "\n".join(robustness.sections(committed).values()).splitlines()
    pairs = QUOTED_P.findall(prose)
    assert len(pairs) > 20
    for *numbers, p in pairs:
        m, low, high = (float(x.replace("−", "-")) for x in numbers)
        shown = {f"{m:+.3f} [{low:+.3f}, {high:+.3f}]", f"{-m:+.3f} [{-high:+.3f}, {-low:+.3f}]"}
        assert any(any(i in row for i in shown) and p in row for row in rows), (numbers, p)


def test_the_families_hold_the_counts_and_intervals_issue_37_found(committed: dict[str, Any]) -> None:
    families = committed["families"]
    assert {k: families["ladder"]["counts"][k] for k in ("comparisons", "uncorrected", "falls", "rises")} == {
        "comparisons": 168, "uncorrected": 64, "falls": 2, "rises": 0,
    }  # fmt: skip
    assert {k: families["changes"]["counts"][k] for k in ("comparisons", "uncorrected", "falls", "rises")} == {
        "comparisons": 56, "uncorrected": 24, "falls": 5, "rises": 0,
    }  # fmt: skip

    def row(family: str, condition: str, perturbation: str, value: float, kind: str) -> dict[str, Any]:
        (found,) = [
            r
            for r in families[family]["rows"]
            if (r["condition"], r["perturbation"], r["value"], r["kind"]) == (condition, perturbation, value, kind)
        ]
        return found

    both = "hierarchical − flat"
    for (condition, perturbation, value), expected in {
        ("1p-high", "obs-noise", 0.1): (-0.498, -0.721, -0.275),
        ("2p-high-individual", "obs-noise", 0.1): (-0.308, -0.423, -0.194),
        ("2p-high-individual", "delay", 1): (-0.110, -0.252, 0.032),
        ("1p-high", "damping", 3.0): (-0.153, -0.440, 0.134),
    }.items():
        r = row("ladder kinds", condition, perturbation, value, both)
        assert (r["mean"], *r["ci"]) == pytest.approx(expected, abs=5e-4)
    assert row("kinds", "1p-high", "obs-noise", 0.1, both)["verdict"] == "hierarchical lower"
    assert row("kinds", "1p-high", "damping", 3.0, both)["verdict"] == "not resolved"
    obstacles = row("changes", "1p-high", "obstacles", 6, "hierarchical")
    assert (obstacles["mean"], *obstacles["ci"]) == pytest.approx((-0.137, -0.258, -0.017), abs=5e-4)
    assert obstacles["p"] < 0.05 < obstacles["p_holm"] and obstacles["verdict"] == "not resolved"
    gap = next(r for r in families["gaps"]["rows"] if (r["condition"], r["kind"]) == ("1p-high", "hierarchical"))
    assert gap["ci"][1] == pytest.approx(0.104, abs=5e-4) and gap["verdict"] == "not resolved"


def _study(seeds: int = 4) -> tuple[list[dict[str, Any]], dict[str, dict[str, Any]]]:
    """One condition, both kinds: the hierarchical margin falls by 0.3 under obs-noise, rises by
    0.3 under act-noise, scatters widely under delay, falls by 0.3 elsewhere; the flat one moves
    by at most 0.002 everywhere; cross-play margins equal self-play ones up to 0.001."""
    rng = np.random.default_rng(7)
    sources = [
        {"name": f"{kind}-{s}", "condition": "1p-high", "kind": kind, "seed": s} for kind in ("hierarchical", "flat")
        for s in range(seeds)
    ]  # fmt: skip
    done: dict[str, dict[str, Any]] = {}
    for source in sources:
        plain = 0.3 + 0.02 * rng.standard_normal()
        done[f"{source['name']}|none"] = {"margin": plain, "always_chase": 0.0}
        for name, levels in robustness.LADDERS.items():
            for value in levels:
                if source["kind"] == "flat":
                    shift = 0.002 * rng.uniform(-1, 1)
                elif name == "delay":
                    shift = rng.uniform(-1, 1)
                else:
                    shift = (0.3 if name == "act-noise" else -0.3) + 0.01 * rng.standard_normal()
                done[f"{source['name']}|{name}={value:g}"] = {"margin": plain + shift, "always_chase": 0.0}
        for other in sources:
            if other is not source and other["kind"] == source["kind"]:
                done[f"{source['name']}|vs|{other['name']}"] = {"margin": plain + 0.001 * rng.uniform(-1, 1)}
    return sources, done


def test_the_verdicts_follow_the_corrected_tests_in_each_family() -> None:
    sources, done = _study()
    families = robustness.summarise(sources, done, 10, 0)["families"]
    sizes = {name: f["counts"]["comparisons"] for name, f in families.items()}
    assert sizes == {
        "margins": 16, "changes": 14, "kinds": 7, "ladder": 42, "ladder kinds": 21, "gaps": 2, "gap kinds": 1,
    }  # fmt: skip
    changes = {(r["kind"], r["perturbation"]): r for r in families["changes"]["rows"]}
    for name in robustness.LADDERS:
        expected = {"obs-noise": "falls", "act-noise": "rises", "delay": "not resolved"}.get(name, "falls")
        assert changes["hierarchical", name]["verdict"] == expected, name
        assert changes["flat", name]["verdict"] == "equivalent", name
    kinds = {r["perturbation"]: r["verdict"] for r in families["kinds"]["rows"]}
    assert kinds["obs-noise"] == "hierarchical lower" and kinds["act-noise"] == "hierarchical higher"
    assert [r["verdict"] for r in families["gaps"]["rows"]] == ["equivalent", "equivalent"]
    for name, family in families.items():  # each family corrected alone, by Holm
        rows = family["rows"]
        assert [r["p_holm"] for r in rows] == pytest.approx(stats.holm([r["p"] for r in rows]).tolist())
        if name != "margins":
            adjusted = stats.holm([r["equivalence"]["p"] for r in rows])
            assert [r["equivalence"]["p_holm"] for r in rows] == pytest.approx(adjusted.tolist())
    delay = changes["hierarchical", "delay"]
    runs = [s["name"] for s in sources if s["kind"] == "hierarchical"]
    values = [done[f"{n}|delay=6"]["margin"] - done[f"{n}|none"]["margin"] for n in runs]
    assert delay["p"] == pytest.approx(scipy_stats.ttest_1samp(values, 0.0).pvalue)
    ladder = {(r["kind"], r["perturbation"], r["value"]): r for r in families["ladder"]["rows"]}
    for r in families["changes"]["rows"]:  # the strongest rung again, in the larger family
        assert ladder[r["kind"], r["perturbation"], r["value"]]["p_holm"] >= r["p_holm"]
    assert json.loads(json.dumps(families)) == families  # full precision, plain JSON


def test_a_study_of_one_run_has_empty_families_and_prints() -> None:
    sources, done = _study()
    one = [sources[0]]
    result = robustness.summarise(one, {k: v for k, v in done.items() if k.startswith(f"{one[0]['name']}|")}, 10, 0)
    assert all(f["rows"] == [] and f["counts"]["comparisons"] == 0 for f in result["families"].values())
    text = robustness.markdown(result)
    assert "| 1p-high | hierarchical | 1 | +0." in text and "none here" in text


def test_the_doc_writer_replaces_each_block_and_refuses_a_missing_one(committed: dict[str, Any]) -> None:
    text = (ROOT / "docs" / "robustness.md").read_text()
    planted = text.replace("| 1p-high | obs-noise=0.1 | -0.859 |", "| 1p-high | obs-noise=0.1 | -0.858 |", 1)
    assert planted != text and robustness_study.written(planted, committed) == text
    with pytest.raises(ValueError, match="generated blocks"):
        robustness_study.written(robustness_study.BLOCK.sub("", text, count=1), committed)
