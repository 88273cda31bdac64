"""docs/pursuit-law.md against its sources: every table in it is what docs/gen/law_tables.py prints
from results/pursuit-law/, and those files are what the code gives (a few selections redone)."""

import json
import re
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from cli_helpers import load_script

from pursuit_bench.laws import guidance
from pursuit_bench.laws.synthetic_attacks import TrueLaw, attack

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "pursuit-law.md"
RESULTS = ROOT / "results" / "pursuit-law"


SCRIPTS = {"law_tables": "docs/gen/law_tables.py", "law_validation": "studies/pursuit-law/law_validation.py"}


def _script(name: str) -> ModuleType:
    return load_script(SCRIPTS[name])


@pytest.fixture(scope="module")
def tables() -> dict[str, str]:
    return _script("law_tables").tables()


def _doc_tables(text: str) -> list[str]:
    """Every markdown table of the doc, as its lines joined."""
    found, current = [], []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            current.append(line)
        elif current:
            found.append("\n".join(current))
            current = []
    return found


def test_the_doc_holds_every_table_as_its_script_prints_it(tables: dict[str, str]) -> None:
    text = DOC.read_text()
    in_doc = {table.splitlines()[0]: table for table in _doc_tables(text)}
    for name, table in tables.items():
        header = table.splitlines()[0]
        if header not in in_doc:
            pytest.fail(f"docs/pursuit-law.md has no {name} table (header {header!r})")
        lines, printed = in_doc[header].splitlines(), table.splitlines()
        for k, (there, here) in enumerate(zip(lines, printed, strict=False)):
            if there != here:
                pytest.fail(f"{name} table, line {k + 1}: the doc has\n{there}\nthe script prints\n{here}")
        assert len(lines) == len(printed), f"{name} table: {len(lines)} lines in the doc, {len(printed)} printed"
    assert text.index(tables["misspecification"]) < text.index(tables["shipped"]) < text.index(tables["sweep"])


def test_every_table_of_the_doc_is_generated_but_the_laws(tables: dict[str, str]) -> None:
    """No hand-typed table: each one is a generated table (docs/gen/law_tables.py's, or the tracked
    laws' confusion matrix from studies/tracked-laws/validation.json), or the method's list of laws."""
    validate = load_script("studies/tracked-laws/validate.py")
    tracked = json.loads((ROOT / "studies" / "tracked-laws" / "validation.json").read_text())["confusion"]
    generated = [*tables.values(), validate.confusion_table(tracked)]
    for table in _doc_tables(DOC.read_text()):
        if table not in generated and not table.startswith("| law | heading |"):
            pytest.fail(f"a table docs/gen/law_tables.py does not print: {table.splitlines()[0]}")


def test_the_doc_says_how_to_regenerate_and_reads_mixed_as_not_separable(tables: dict[str, str]) -> None:
    text = DOC.read_text()
    for command in ("python studies/pursuit-law/law_validation.py", "python docs/gen/law_tables.py --shipped"):
        assert command in text
    assert "pn or mixed, not separable at 10 Hz" in tables["sweep"].splitlines()[0]
    assert "is a real one" not in text
    # the mixed law's K: no value, no interval, in any table
    assert not any(re.search(r"mixed's .*K", t.splitlines()[0]) for t in tables.values())


def test_the_shipped_table_counts_fits_at_the_bound() -> None:
    """Its pn column gives the share at the bound and the median that counts it, from the fits."""
    module = _script("law_tables")
    data = json.loads((RESULTS / "shipped-1p-low.json").read_text())
    pn = data["kinds"]["hierarchical"]["predator_0"]["chase"]["laws"]["pn"]
    sides = [c.get("N") for c in pn["censored"]]
    share = sides.count("upper") / len(sides)
    expected = f"{share:.0%}; " + (">15" if share >= 0.5 else f"{np.median(pn['gains']['N']):.1f}")
    row = next(line for line in module.shipped_table().splitlines() if line.startswith("| hierarchical |"))
    assert f"| {expected} |" in row


def test_the_reading_bounds_follow_the_rates() -> None:
    """share = p a + (1 − p) b: with a of 0.9 and b of 0.1 to 0.3, a share of 0.5 means p of 1/3 to
    1/2; ranges are clipped to [0, 1]."""
    implied = _script("law_tables").implied
    verdict = {"own": {"x": (9, 10)}, "others": {"y": (1, 10), "z": (3, 10)}}
    low, high = implied(0.5, verdict)
    assert low == pytest.approx((0.5 - 0.3) / (0.9 - 0.3)) and high == pytest.approx((0.5 - 0.1) / (0.9 - 0.1))
    assert implied(0.05, verdict)[0] == 0.0 and implied(1.0, verdict)[1] == 1.0


def _true(entry: dict) -> TrueLaw:
    return TrueLaw(**entry)


@pytest.mark.parametrize(("row", "length", "index"), [(2, "12", 0), (6, "16", 3), (7, "8", 1)])
def test_the_confusion_matrix_is_what_the_code_gives(row: int, length: str, index: int) -> None:
    data = json.loads((RESULTS / "confusion.json").read_text())
    entry = data["rows"][row]
    stored = entry["cells"][length]["attacks"][index]
    history, n = data["history"], int(length)
    pursuer, target = attack(_true(entry["true"]), stored["seed"], data["dt"], duration=(history + n) * data["dt"])
    selection = guidance.select(pursuer, target, data["dt"], history, history)
    assert selection.chosen.law == stored["chosen"] and selection.chosen.samples == n
    assert selection.under_floor == stored["under_floor"]
    for law, fit in selection.fits.items():
        assert fit.error == pytest.approx(stored["fits"][law]["error"], rel=1e-9, abs=1e-12)


def test_the_validation_file_is_what_the_code_gives() -> None:
    """One attack of the misspecification control, redone."""
    data = json.loads((RESULTS / "validation.json").read_text())
    case = next(c for c in data["cases"] if c["true"]["directions"] and c["true"]["law"] == "parallel")
    stored = case["attacks"][1]
    selection = guidance.select(*attack(_true(case["true"]), stored["seed"]), data["dt"])
    assert selection.chosen.law == stored["chosen"]
    assert selection.relative_errors == pytest.approx(stored["relative_errors"], rel=1e-9)
