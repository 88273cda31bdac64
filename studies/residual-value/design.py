"""The residual study's fixed design (docs/residual.md, "Protocol of the residual study"): its
settings, kinds, seeds, population, comparisons, ladders and seed rule. Pure data and small
functions (no torch): ``run.py`` drives the study by it, ``tests/test_residual_study.py`` checks it.

Nothing here is in the package: it reads the package's constants where the rule study fixed them,
and adds only what the residual study adds. Run as a script, it prints the fingerprint of the
training code in ``git ls-tree -r REV -- pursuit_bench``'s listing on its input (:data:`TRAINING_CODE`).
"""

from __future__ import annotations

import hashlib
import sys
from typing import Any

try:  # this checkout's module paths; below, the pinned build's (before 0.2's redesign)
    from pursuit_bench.reports import rule_study
except ImportError:
    from pursuit_bench.study import rule_study

from pursuit_bench.env.conditions import CONDITIONS

#: The rule study's build (``studies/rule-value/build.json``), which trained the hierarchical and
#: flat runs reused here: its commit and ``studies/rule-value/run.py``'s fingerprint of the
#: package's tracked .py files. This study runs on a later build (PLAN.md, "The build"), pinned in
#: ``build.json`` beside this file, whose training code must be this build's (:data:`TRAINING_CODE`).
RULE_STUDY_CODE = "cc950401500232df"
RULE_STUDY_COMMIT = "ec5779b6759f318367ef65b14b1a83533ccce805"

#: The training code: the package's files a run's training reads. A sweep's worker
#: (``training/sweep.py``'s ``run_stack``, which the driver's sweeps and the rule study's ran)
#: imports, at the top of a module or inside a function, only modules of these layers and the
#: package's ``__init__`` (which sets MKL's and OpenBLAS's kernels, and so training's bits), so the
#: set is all of them: every .py file of the package's ``__init__``, ``io``, ``env``, ``rules``,
#: ``agents`` and ``training`` (recording, rendering and the Gymnasium/PettingZoo views included,
#: though training may not call them: too many files rather than too few). ``pretrained``,
#: ``study`` and ``cli`` are not imported by training (the layers' rule, ``tests/test_layers.py``;
#: the driver calls the sweep directly, not ``pursuit-bench sweep``).
TRAINING_CODE_PATHS = (
    "pursuit_bench/__init__.py",
    "pursuit_bench/io/",
    "pursuit_bench/env/",
    "pursuit_bench/rules/",
    "pursuit_bench/agents/",
    "pursuit_bench/training/",
)
#: Left out: evaluation only. Of training, only a sweep's worker imports ``training/evaluate.py``
#: (``run_stack``), and calls it only once every run of its stack is trained and checkpointed
#: (``train_stack`` returns, then ``evaluate_folder``: the run's own evaluation, which this study
#: does not read); ``train.py``, ``stack.py``, ``runs.py`` and the layers below do not import it.
#: It is the one file of these layers changed since the rule study's build (commit 1ac828e: the
#: evaluations with perturbed senses play the first episodes to start, each to its end).
NOT_TRAINING = ("pursuit_bench/training/evaluate.py",)
#: The fingerprint of the training code at the rule study's build (42 files), which the driver
#: requires of the package it runs on. Recompute it from git (either line; the same number):
#:   git ls-tree -r ec5779b -- pursuit_bench | PYTHONPATH=. python studies/residual-value/design.py
#:   git ls-tree -r ec5779b -- pursuit_bench | awk '{print $3, $4}' \
#:     | grep -E ' pursuit_bench/(__init__\.py|(io|env|rules|agents|training)/.*\.py)$' \
#:     | grep -v ' pursuit_bench/training/evaluate\.py$' | sha256sum | cut -c1-16
TRAINING_CODE = "4ebfb2467b9caa00"

KINDS = ("hierarchical", "residual", "flat")
#: The comparisons, first − second; one Holm family per budget over every (panel, comparison).
COMPARISONS = (("residual", "hierarchical"), ("residual", "flat"))
OBSTACLES = 4
#: Every setting: its condition and obstacles per arena. The plain ones are the rule study's.
SETTINGS: dict[str, tuple[str, int]] = {
    "3p-low-individual": ("3p-low-individual", 0),
    "3p-high-shared": ("3p-high-shared", 0),
    "2p-high-individual": ("2p-high-individual", 0),
    "1p-high": ("1p-high", 0),
    f"2p-high-individual-obstacles{OBSTACLES}": ("2p-high-individual", OBSTACLES),
    f"1p-high-obstacles{OBSTACLES}": ("1p-high", OBSTACLES),
}
POPULATION = "residual-study"
FLEEING = rule_study.FLEEING
BUDGETS = rule_study.BUDGETS
EPISODES, EVAL_SEED = rule_study.EPISODES, rule_study.EVAL_SEED
POPULATION_RUNS = rule_study.POPULATION_RUNS
#: Seeds of the judged runs (the rule study's range) and the seed rule's counts (the rule study's).
JUDGED_SEEDS_END = rule_study.JUDGED_SEEDS_END
FIRST_RUNS, STEP_RUNS, MOST_RUNS = rule_study.FIRST_RUNS, rule_study.STEP_RUNS, rule_study.MOST_RUNS
FAILURE_MARGIN = rule_study.FAILURE_MARGIN
#: The robustness ladders run (``pursuit_bench.study.robustness.LADDERS``' rungs), on the kinds
#: compared there; the obstacles ladder only where the runs trained without obstacles.
LADDERS: dict[str, tuple[float, ...]] = {"obs-noise": (0.02, 0.05, 0.1), "delay": (1, 3, 6), "obstacles": (2, 4, 6)}
LADDER_KINDS = ("residual", "hierarchical")
LADDER_EPISODES = 300
#: ``analyze``'s correction by distance and mode: episodes and seed (the CLI's defaults).
ANALYSIS_EPISODES, ANALYSIS_SEED = 200, 0
#: A residual run's margin "differs" from the hierarchical one when its pool margin at the last
#: budget (mean over its predators) is further than this from the hierarchical run of its seed's.
DIFFERS = 0.05


def training_files(listing: str) -> dict[str, str]:
    """The training code's files in ``git ls-tree -r REV -- pursuit_bench``'s output: each path
    (:data:`TRAINING_CODE_PATHS`, less :data:`NOT_TRAINING`) with its blob's hash."""
    files = {}
    for line in listing.splitlines():
        about, path = line.split("\t", 1)
        if path.endswith(".py") and path not in NOT_TRAINING and path.startswith(TRAINING_CODE_PATHS):
            files[path] = about.split()[2]
    return files


def training_code(files: dict[str, str]) -> str:
    """The fingerprint of :func:`training_files`: the first 16 hex digits of the SHA-256 of their
    lines ``<blob> <path>``, by path."""
    lines = "".join(f"{blob} {path}\n" for path, blob in sorted(files.items()))
    return hashlib.sha256(lines.encode()).hexdigest()[:16]


def condition_of(setting: str) -> str:
    return SETTINGS[setting][0]


def obstacles_of(setting: str) -> int:
    return SETTINGS[setting][1]


def plain(setting: str) -> bool:
    """Whether the rule study has the setting (its hierarchical and flat runs are reused)."""
    return obstacles_of(setting) == 0


def population_name(setting: str) -> str:
    """The population's name (the package's folder ``populations/<name>/<condition>/``): the plain
    settings' is ``residual-study``, the obstacle ones' ``residual-study-obstacles4`` (a population
    folder is named by a condition; the obstacles go into the population's name)."""
    return POPULATION if plain(setting) else f"{POPULATION}-obstacles{obstacles_of(setting)}"


def population_seeds(kind: str) -> range:
    """The seeds of a kind's population runs: hierarchical 1000–1003 and flat 1004–1007 (the rule
    study's), residual 1008–1011."""
    start = rule_study.POPULATION_FIRST_SEED + KINDS_BY_SEED.index(kind) * POPULATION_RUNS
    return range(start, start + POPULATION_RUNS)


#: The kinds in the order of their population seeds (the rule study's two first).
KINDS_BY_SEED = ("hierarchical", "flat", "residual")


def members(setting: str) -> list[dict[str, Any]]:
    """A setting's population: the rule study's members of its condition (FleeingPrey, 4
    hierarchical, 4 flat), then the residual kind's 4; the same names and seeds in the obstacle
    settings, whose members are trained here with the obstacles."""
    rule = rule_study.members(condition_of(setting))
    added = [
        {"name": f"residual-seed{seed}", "kind": "residual", "policy": None, "seed": seed}
        for seed in population_seeds("residual")
    ]
    return [*rule, *added]


def trained_here(setting: str, stage: str) -> tuple[str, ...]:
    """The kinds this study trains in a setting (``stage``: population or judged): the residual
    kind alone where the rule study has the setting, all three elsewhere."""
    if stage not in ("population", "judged"):
        raise ValueError(f"stage={stage!r}: expected population or judged")
    return ("residual",) if plain(setting) else KINDS_BY_SEED


def check_design(judged: dict[str, list[int]], population: list[dict[str, Any]]) -> None:
    """ValueError unless the population's seeds are distinct, at least 1000 and disjoint from
    every judged seed (0–999) (``rule_study.check_design``, which reads any kinds)."""
    rule_study.check_design(judged, population)


def seeds_wanted(
    runs: list[dict[str, Any]], first: int = FIRST_RUNS, step: int = STEP_RUNS, most: int = MOST_RUNS
) -> int:
    """The rule study's seed rule over the three kinds of one setting (``runs``: its compact
    results against its population): ``first``; once seeds 0 … n-1 of every kind are in (n <
    ``most``), n + ``step`` where some panel has a failed run of any kind among them, else n."""
    return rule_study.seeds_wanted(runs, first, step, most, KINDS)


def plan() -> list[dict[str, Any]]:
    """What the study runs, setting by setting, in order: the population's members (which are
    trained here, which come from the rule study), the judged runs (trained here or reused from the
    rule study), the comparisons, the ladders and the analysis. PLAN.md and the tests read it."""
    rows = []
    for setting in SETTINGS:
        rows.append(
            {
                "setting": setting,
                "condition": condition_of(setting),
                "obstacles": obstacles_of(setting),
                "population": population_name(setting),
                "members": [m["name"] for m in members(setting)],
                "population_trained_here": list(trained_here(setting, "population")),
                "judged_trained_here": list(trained_here(setting, "judged")),
                "judged_reused": [] if not plain(setting) else ["hierarchical", "flat"],
                "judged_seeds": f"0–{FIRST_RUNS - 1}, by the seed rule up to 0–{MOST_RUNS - 1}",
                "budgets": list(BUDGETS),
                "comparisons": [list(c) for c in COMPARISONS],
                "ladders": {k: list(v) for k, v in LADDERS.items() if k != "obstacles" or plain(setting)},
                "ladder_kinds": list(LADDER_KINDS),
                "analysis": "residual runs",
            }
        )
    return rows


assert all(c in CONDITIONS for c, _ in SETTINGS.values())

if __name__ == "__main__":
    print(training_code(training_files(sys.stdin.read())))
