"""docs/pursuit-law.md's tables, from the files in results/pursuit-law/:

- ``validation.json`` and ``confusion.json`` (``python studies/pursuit-law/law_validation.py``): attacks
  with a known answer;
- ``shipped-1p-low.json``: the shipped 1p-low agents and the scripted predators in their
  places, 20 episodes (``--shipped`` plays and fits them, about 30 s);
- ``sweep-summary.json``: the summaries ``pursuit-bench law SWEEP --episodes 5`` wrote for the
  reproduction sweep's hierarchical and flat runs (``--collect`` merges them).

    python docs/gen/law_tables.py --shipped                                            # writes the file
    python docs/gen/law_tables.py --collect sweeps/repro1000 sweeps/repro1000-flat     # writes the file
    python docs/gen/law_tables.py                                                      # prints the tables

``tables()`` gives them by name; tests/test_pursuit_law_docs.py checks that the doc holds each.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

RESULTS = Path(__file__).resolve().parents[2] / "results" / "pursuit-law"
SUMMARY = RESULTS / "sweep-summary.json"
SHIPPED = RESULTS / "shipped-1p-low.json"
#: The shipped agents fitted for the doc: condition, episodes, seed.
SHIPPED_RUN = ("1p-low", 20, 0)
#: The order laws are shown in.
SHOWN = ("parallel", "pn", "mixed", "pp", "none")
#: How a ``mixed`` verdict is read (the validation: docs/pursuit-law.md).
MIXED_READ = "pn or mixed, not separable at 10 Hz"
SHARE_HEADER = f"share chosen: parallel / pn / {MIXED_READ} / pp / none"
LAWS = ("none", "pp", "pn", "mixed", "parallel")
GAINS = {"none": (), "pp": ("K",), "pn": ("N",), "mixed": ("N", "K"), "parallel": ()}
N_BOUND = 15.0


def _load(name: str) -> Any:
    return json.loads((RESULTS / name).read_text())


def made_with(true: dict[str, Any]) -> str:
    """A synthetic pursuer's law as the tables name it."""
    gains = [f"{g} {true['n_gain' if g == 'N' else 'k_gain']:g}" for g in GAINS[true["law"]]]
    delay = [f"τ {true['delay']:g} s"] if true["law"] != "none" else []
    flown = (
        [f"{true['directions']} directions, held {true['hold']:g} s, velocity lag {true['velocity_lag']:.2f} s"]
        if true.get("directions")
        else []
    )
    return ", ".join(gains + delay + flown) or "-"


def _counts(chosen: list[str], order: tuple[str, ...] = SHOWN) -> str:
    counted = Counter(chosen)
    return ", ".join(f"{law} {counted[law]}" for law in order if counted[law])


def validation_table() -> str:
    """Each law's attacks (whole attacks, five per case): how often chosen, its own fit."""
    lines = [
        "| law | made with | chosen as itself | its fitted gains (5 attacks) | delays (s) | error relative to none |",
        "|---|---|---:|---|---|---:|",
    ]
    for case in _load("validation.json")["cases"]:
        true = case["true"]
        if true.get("directions"):
            continue
        law, attacks = true["law"], case["attacks"]
        own = [a["fits"][law] for a in attacks]
        chosen = [a["chosen"] for a in attacks]
        others = sorted({c for c in chosen if c != law})
        hits = f"{sum(c == law for c in chosen)} of {len(attacks)}" + (f" (else {', '.join(others)})" if others else "")
        gains = "; ".join(", ".join(f"{k} {v:.2f}" for k, v in f["gains"].items()) for f in own if f["gains"])
        delays = ", ".join(f"{f['delay']:g}" for f in own)
        relative = np.median([a["relative_errors"][law] for a in attacks])
        lines.append(f"| {law} | {made_with(true)} | {hits} | {gains or '-'} | {delays} | {relative:.3f} |")
    return "\n".join(lines)


def _gain_text(fit: dict[str, Any], gain: str) -> str:
    side = fit["censored"].get(gain)
    bound = {"N": (0, 15), "K": (0, 30)}[gain]
    return f">{bound[1]}" if side == "upper" else f"<{bound[0]}" if side == "lower" else f"{fit['gains'][gain]:.2f}"


def misspecification_table() -> str:
    """The laws flown as our predators fly: what the fitter calls them."""
    lines = [
        "| flown as our predators fly | chosen (5 attacks) | the chosen law's gains, delay | pn's N | "
        "best law's error relative to none: median (range) | attacks with 2+ laws under the floor |",
        "|---|---|---|---|---|---:|",
    ]
    for case in _load("validation.json")["cases"]:
        true = case["true"]
        if not true.get("directions"):
            continue
        attacks = case["attacks"]
        chosen = [a["chosen"] for a in attacks]
        fitted = []
        for a in attacks:
            fit = a["fits"][a["chosen"]]
            gains = ", ".join(f"{g} {_gain_text(fit, g)}" for g in fit["gains"])
            fitted.append(f"{a['chosen']}: " + ", ".join(([gains] if gains else []) + [f"τ {fit['delay']:g}"]))
        n_gains = ", ".join(_gain_text(a["fits"]["pn"], "N") for a in attacks)
        best = [a["relative_errors"][a["chosen"]] for a in attacks]
        ties = sum(len(a["under_floor"]) >= 2 for a in attacks)
        lines.append(
            f"| {true['law']}, {made_with(true)} | {_counts(chosen)} | {'; '.join(fitted)} | {n_gains} | "
            f"{np.median(best):.3f} ({min(best):.3f}–{max(best):.3f}) | {ties} |"
        )
    return "\n".join(lines)


#: Laws each law holds (a gain at 0): a choice between a law and one it holds, both under the
#: floor, is parsimony; between two laws neither holds, the data do not make it.
HOLDS = {"none": (), "pp": ("none",), "pn": ("none",), "mixed": ("none", "pp", "pn"), "parallel": ()}
#: The confusion matrix's lengths the trained predators' chases have (7–19 samples after the
#: onset for the shipped 1p-low agents): the reading of their shares pools these.
SHORT = 20
#: Verdicts read through the confusion matrix, and the synthetic laws of their kind.
READ = {"parallel": ("parallel",), "pn": ("pn",), "pp": ("pp",)}


def _untied(attack: dict[str, Any]) -> bool:
    """Whether two laws neither of which holds the other are both under the floor."""
    under = attack["under_floor"]
    return any(b not in HOLDS[a] and a not in HOLDS[b] for a in under for b in under if a < b)


def _row_name(true: dict[str, Any]) -> str:
    return f"{true['law']}, {made_with(true)}" if true["law"] != "none" else "none"


def confusion_table() -> str:
    """True law × chosen law by the samples after the onset."""
    data = _load("confusion.json")
    per_cell = data["per_cell"]
    lines = [
        f"| made with | n | {' | '.join(SHOWN)} | laws neither holding the other tied under the floor "
        "| chosen law's error relative to none: median |",
        "|---|---:|" + "---:|" * (len(SHOWN) + 2),
    ]
    for row in data["rows"]:
        true = row["true"]
        for n in data["lengths"]:
            attacks = row["cells"][str(n)]["attacks"]
            if len(attacks) != per_cell:
                raise ValueError(f"{_row_name(true)}, n {n}: {len(attacks)} attacks, expected {per_cell}")
            counted = Counter(a["chosen"] for a in attacks)
            ties = sum(_untied(a) for a in attacks)
            best = np.median([a["relative_errors"][a["chosen"]] for a in attacks])
            cells = " | ".join(f"**{counted[law]}**" if law == true["law"] else str(counted[law]) for law in SHOWN)
            lines.append(f"| {_row_name(true)} | {n} | {cells} | {ties} | {best:.3f} |")
    return "\n".join(lines)


def rates() -> dict[str, dict[str, Any]]:
    """Per verdict of :data:`READ`, pooled over the confusion matrix's lengths up to :data:`SHORT`:
    how often the synthetic laws of its kind are given it (``own``: each such row's rate) and
    every other row (``others``: each row's rate, by name)."""
    data = _load("confusion.json")
    lengths = [n for n in data["lengths"] if n <= SHORT]
    found: dict[str, dict[str, Any]] = {}
    for verdict, kinds in READ.items():
        own: dict[str, tuple[int, int]] = {}
        others: dict[str, tuple[int, int]] = {}
        for row in data["rows"]:
            attacks = [a for n in lengths for a in row["cells"][str(n)]["attacks"]]
            rate = (sum(a["chosen"] == verdict for a in attacks), len(attacks))
            is_own = row["true"]["law"] in kinds and not row["true"].get("directions")
            (own if is_own else others)[_row_name(row["true"])] = rate
        found[verdict] = {"own": own, "others": others, "lengths": lengths}
    return found


def _fraction(rate: tuple[int, int]) -> float:
    return rate[0] / rate[1]


def implied(share: float, verdict: dict[str, Any]) -> tuple[float, float]:
    """The share of chases of the verdict's kind that an observed ``share`` of that verdict
    implies, if every chase was made by one of the confusion matrix's synthetic pursuers:
    ``share = p a + (1 − p) b`` with a an own row's rate and b another row's, so p lies between
    ``(share − b_max) / (a_max − b_max)`` and ``(share − b_min) / (a_min − b_min)``, clipped to
    [0, 1]."""
    a = [_fraction(r) for r in verdict["own"].values()]
    b = [_fraction(r) for r in verdict["others"].values()]
    low_a, high_a, low_b, high_b = min(a), max(a), min(b), max(b)
    lower = (share - high_b) / (high_a - high_b) if high_a > high_b else 0.0
    upper = (share - low_b) / (low_a - low_b) if low_a > low_b else 1.0
    return float(np.clip(lower, 0, 1)), float(np.clip(upper, 0, 1))


def rates_table() -> str:
    """The rates the trained predators' shares are read through."""
    lines = [
        "| verdict | given to its own kind's synthetic attacks | given to the others' at most | at least |",
        "|---|---|---|---|",
    ]
    for verdict, found in rates().items():
        own = "; ".join(f"{name}: {k} of {n}" for name, (k, n) in found["own"].items())
        most = max(found["others"].items(), key=lambda item: _fraction(item[1]))
        least = min(found["others"].items(), key=lambda item: _fraction(item[1]))
        lines.append(
            f"| {verdict} | {own} | {most[1][0]} of {most[1][1]} ({most[0]}) "
            f"| {least[1][0]} of {least[1][1]} ({least[0]}) |"
        )
    return "\n".join(lines)


def reading_table() -> str:
    """The trained and scripted predators' chase shares read through the confusion matrix: the
    shipped 1p-low agents and the sweep's chase rows with at least 20 segments."""
    found = rates()
    lines = [
        "| predators | segments | "
        + " | ".join(f"{v}: share chosen; chases of its kind implied" for v in READ)
        + f" | {MIXED_READ}: share chosen |",
        "|---|---:|" + "---|" * (len(READ) + 1),
    ]
    rows: list[tuple[str, int, dict[str, float]]] = []
    names = {"always_chase": "always-chase", "pure_pursuit": "pure pursuit"}
    for kind, predators in json.loads(SHIPPED.read_text())["kinds"].items():
        for chase in (fits["chase"] for fits in predators.values()):
            if chase["attacks"]:
                rows.append((f"shipped 1p-low, {names.get(kind, kind)}", chase["attacks"], chase["share"]))
    for condition, kinds in sorted(json.loads(SUMMARY.read_text()).items()):
        for kind in ("hierarchical", "flat"):
            entry = kinds.get(kind, {}).get("chase")
            if entry and entry["attacks"] >= 20:
                shares = {law: entry["share"][law]["mean"] for law in SHOWN}
                rows.append((f"{condition}, {kind} (sweep, mean over runs)", entry["attacks"], shares))
    for name, segments, share in rows:
        cells = []
        for verdict in READ:
            low, high = implied(share[verdict], found[verdict])
            cells.append(f"{share[verdict]:.0%}; {low:.0%}–{high:.0%}")
        lines.append(f"| {name} | {segments} | {' | '.join(cells)} | {share['mixed']:.0%} |")
    return "\n".join(lines)


def _shares(share: dict[str, float]) -> str:
    return " / ".join(f"{share[law]:.0%}" for law in SHOWN)


def _censored_text(summary: dict[str, Any] | None) -> str:
    """The share of fits at the upper bound and the median that counts them."""
    if summary is None:
        return "not recorded"
    if not summary["fits"]:
        return "-"
    side = summary["side"]
    median = f">{N_BOUND:g}" if side == "upper" else "<0" if side == "lower" else f"{summary['median']:.1f}"
    return f"{summary['upper']:.0%}; {median}"


def shipped_table() -> str:
    """The shipped 1p-low agents' chases and the scripted predators' in their places."""
    data = json.loads(SHIPPED.read_text())
    lines = [
        f"| predator | segments (chase) | samples after the onset: median (range) | {SHARE_HEADER} "
        "| pn's N: at the bound 15; median counting it | pn's N: interior median (drops the bound) "
        "| best law's error relative to none: median |",
        "|---|---:|---|---|---|---|---:|",
    ]
    names = {"always_chase": "always-chase (its lower layer alone)", "pure_pursuit": "pure pursuit"}
    for kind, predators in data["kinds"].items():
        for fits in predators.values():
            chase = fits["chase"]
            if not chase["attacks"]:
                continue
            pn = chase["laws"]["pn"]
            censored = _censored_text(_censored(pn["gains"]["N"], [c.get("N") for c in pn["censored"]]))
            interior = pn["summary"]["N"]["median"]
            best = [chase["laws"][law]["relative_error"][k] for k, law in enumerate(chase["chosen"])]
            samples = chase["samples"]
            lines.append(
                f"| {names.get(kind, kind)} | {chase['attacks']} "
                f"| {np.median(samples):g} ({min(samples)}–{max(samples)}) "
                f"| {_shares(chase['share'])} | {censored} | {'-' if interior is None else f'{interior:.1f}'} "
                f"| {np.median(best):.2f} |"
            )
    return "\n".join(lines)


def _censored(values: list[float], sides: list[str | None]) -> dict[str, Any]:
    from pursuit_bench.laws.pursuit_laws import censored_median

    return censored_median(values, sides)


def _interval(entry: dict[str, Any]) -> str:
    if entry["mean"] is None:
        return "-"
    ci = entry["ci"]
    return f"{entry['mean']:.2f}" + (f" [{ci[0]:.2f}, {ci[1]:.2f}]" if ci else "")


def sweep_table() -> str:
    """Per condition, kind and phase over the sweep's runs: the shares chosen and the gains."""
    summary = json.loads(SUMMARY.read_text())
    lines = [
        f"| condition | predators | phase | segments | {SHARE_HEADER} | pn's N: runs' interior medians, "
        "mean [95 % t] | runs with an interior pn fit | pn's N: at the bound; median counting it | mixed's N |",
        "|---|---|---|---:|---|---|---:|---|---|",
    ]
    for condition, kinds in sorted(summary.items()):
        for kind in ("hierarchical", "flat"):
            if kind not in kinds:
                continue
            for phase in ("chase", "stalk"):
                entry = kinds[kind][phase]
                if not entry["attacks"]:
                    continue
                shares = {law: entry["share"][law]["mean"] for law in SHOWN}
                gains = entry["gains"]
                lines.append(
                    f"| {condition} | {kind} | {phase} | {entry['attacks']} | {_shares(shares)} | "
                    f"{_interval(gains['pn.N'])} | {gains['pn.N']['runs']} of {kinds[kind]['runs']} | "
                    f"{_censored_text(gains['pn.N'].get('censored'))} | {_interval(gains['mixed.N'])} |"
                )
    return "\n".join(lines)


def tables() -> dict[str, str]:
    """Every table of docs/pursuit-law.md by name, in the doc's order."""
    return {
        "validation": validation_table(),
        "misspecification": misspecification_table(),
        "confusion": confusion_table(),
        "shipped": shipped_table(),
        "sweep": sweep_table(),
        "rates": rates_table(),
        "reading": reading_table(),
    }


def shipped() -> None:
    """Play and fit the shipped agents (:data:`SHIPPED_RUN`) as ``pursuit-bench law --pretrained``
    does, and write what the tables need (the example trajectories left out)."""
    import torch

    from pursuit_bench import pretrained
    from pursuit_bench.io.files import atomic_write_text
    from pursuit_bench.laws import pursuit_laws

    torch.set_num_threads(1)
    condition, episodes, seed = SHIPPED_RUN
    config, agents, _ = pretrained.described(condition)
    result = pursuit_laws.analyse(
        condition,
        agents,  # type: ignore[arg-type]
        config.predator,
        episodes,
        seed,
        task_options=config.task_options,
        avoidance=config.avoids,
    )
    result.pop("examples")
    atomic_write_text(SHIPPED, json.dumps(result) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--collect", nargs="*", type=Path, help="sweep folders whose law.json to collect")
    parser.add_argument("--shipped", action="store_true", help="play and fit the shipped 1p-low agents")
    args = parser.parse_args()
    if args.collect:
        from pursuit_bench.io.files import atomic_write_text

        merged: dict[str, Any] = {}
        for sweep in args.collect:
            for condition, kinds in json.loads((sweep / "law.json").read_text())["summary"].items():
                merged.setdefault(condition, {}).update(kinds)
        atomic_write_text(SUMMARY, json.dumps(merged, indent=1) + "\n")
    if args.shipped:
        shipped()
    for name, table in tables().items():
        print(f"<!-- {name} -->\n{table}\n")


if __name__ == "__main__":
    main()
