"""The budget study's fixed design (PROTOCOL.md beside this file): its conditions, kinds, seeds,
budgets, population and build. Pure data and small functions: ``run.py`` drives the study by it,
``measure.py`` measures its rates, ``tests/test_budget_study.py`` checks it against the protocol.

Nothing here is in the package. The runs are the rule study's runs trained on: the first
:data:`RULE_EPISODES` episodes by the rule study's own plan (:func:`sweep_plan`), then on from that
checkpoint to :data:`EPISODES` (:func:`continuation_plan`). Run as a script, it prints the
fingerprints of the package in ``git ls-files -s -- pursuit_bench``'s (or ``git ls-tree -r REV --
pursuit_bench``'s) listing on its input.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path
from typing import Any

#: The study's conditions, cheapest first (the order the driver trains them in): one of each of
#: the rule study's verdicts (rule helps, flat better, not resolved).
CONDITIONS = ("3p-low-shared", "2p-high-shared", "1p-high")
#: The panels: every predator of every condition (1 + 2 + 3 = 6).
PANELS = (
    ("3p-low-shared", "predator_0"),
    ("3p-low-shared", "predator_1"),
    ("3p-low-shared", "predator_2"),
    ("2p-high-shared", "predator_0"),
    ("2p-high-shared", "predator_1"),
    ("1p-high", "predator_0"),
)
KINDS = ("hierarchical", "flat")
PRESET = "reproduction"
#: The rule study's training length: every run's first part, by the rule study's plan.
RULE_EPISODES = 15_000
#: The rule study's kept checkpoints of a judged run (its first part keeps them too: the same plan).
RULE_KEEP = (1500, 5000, 10_500, 12_750)
#: The study's budgets: every run is kept and evaluated at each; the last is the run's end.
BUDGETS = (15_000, 50_000, 150_000, 500_000, 1_000_000)
EPISODES = BUDGETS[-1]
NUM_ENVS = 32
CHECKPOINT_EVERY = 1000
#: Judged seeds of each kind (the rule study's seeds 0–9), fixed: none is added.
JUDGED_SEEDS = tuple(range(10))
#: The population: FleeingPrey and the prey of 4 hierarchical (1000–1003) and 4 flat (1004–1007)
#: runs, the rule study's members, trained on to every budget.
POPULATION_RUNS = 4
POPULATION_FIRST_SEED = 1000
FLEEING = "FleeingPrey"
#: The rule study's committed population (15,000 episodes), which each member's first part must equal.
RULE_POPULATION = "rule-study"
#: Evaluation (the rule study's CRN protocol): episodes per variant per member, the seed.
EVAL_EPISODES, EVAL_SEED, DRAWS = 60, 12345, "crn-1"
#: The statistics (PROTOCOL.md): Welch, Holm over the panels, TOST within this bound.
EQUIVALENCE = 0.05
ALPHA = 0.05
FAILURE_MARGIN = -0.05
#: The core-hours the protocol's seed cut starts from (PROTOCOL.md, "Seeds").
CUT_ABOVE_CORE_HOURS = 80.0
#: The fewest judged seeds a kind the cut may leave in a condition.
MIN_CUT_SEEDS = 6

#: The build that trains every run (PROTOCOL.md, "Build"): ``build.json`` beside this file.
BUILD_COMMIT = "d9886b9a83fedb2d3bddf7f56205833f96e20624"


def population_seeds(kind: str) -> range:
    """The seeds of a kind's population runs: hierarchical 1000–1003, flat 1004–1007."""
    if kind not in KINDS:
        raise ValueError(f"kind={kind!r}: expected one of {', '.join(KINDS)}")
    start = POPULATION_FIRST_SEED + KINDS.index(kind) * POPULATION_RUNS
    return range(start, start + POPULATION_RUNS)


def members(condition: str) -> list[dict[str, Any]]:
    """A condition's population: FleeingPrey, then each learned member (the rule study's names)."""
    if condition not in CONDITIONS:
        raise ValueError(f"condition={condition!r}: expected one of {', '.join(CONDITIONS)}")
    learned = [
        {"name": f"{kind}-seed{seed}", "kind": kind, "policy": None, "seed": seed}
        for kind in KINDS
        for seed in population_seeds(kind)
    ]
    return [{"name": FLEEING, "kind": "scripted", "policy": FLEEING, "seed": None}, *learned]


def run_name(condition: str, kind: str, seed: int) -> str:
    """A run's folder name, the sweep's: ``<condition>-<kind>-seed<S>``."""
    return f"{condition}-{kind}-seed{seed}"


def sweep_plan(
    kind: str,
    conditions: list[str],
    first: int,
    seeds: int,
    episodes: int,
    keep: tuple[int, ...],
    *,
    preset: str = PRESET,
    num_envs: int = NUM_ENVS,
    checkpoint_every: int = CHECKPOINT_EVERY,
) -> Any:
    """A sweep's plan as the rule study's driver makes it (``studies/rule-value/run.py``'s
    ``plan_for``): ``kind`` one of :data:`KINDS` or ``both``. ``preset``, ``num_envs`` and
    ``checkpoint_every`` are for trying the driver only."""
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training.sweep import SweepPlan

    if kind not in (*KINDS, "both"):
        raise ValueError(f"kind={kind!r}: expected one of {', '.join(KINDS)} or both")
    return SweepPlan(
        conditions=tuple(conditions),
        seeds=seeds,
        first_seed=first,
        predators=(kind,) if kind != "both" else KINDS,
        agent=PRESETS[preset].replace(episodes=episodes),
        episodes=episodes,
        eval_episodes=1,  # the sweep's own evaluation (each run against its own prey) is not read
        num_envs=num_envs,
        checkpoint_every=checkpoint_every,
        preset=preset,
        keep_checkpoints=keep,
    )


def stage_seeds(stage: str, kind: str) -> range:
    """The seeds a stage trains: a kind's population seeds, or the judged seeds (both kinds)."""
    if stage == "population":
        return population_seeds(kind)
    if stage == "judged":
        return range(JUDGED_SEEDS[0], JUDGED_SEEDS[-1] + 1)
    raise ValueError(f"stage={stage!r}: expected population or judged")


def first_part(
    stage: str,
    condition: str,
    kind: str,
    budgets: tuple[int, ...] = BUDGETS,
    rule_keep: tuple[int, ...] = RULE_KEEP,
    **trial: Any,
) -> Any:
    """The rule study's plan of a run's first ``budgets[0]`` (15,000) episodes: the
    population's (a kind's seeds, no kept checkpoints) or the judged runs' (both kinds, seeds
    0–9, :data:`RULE_KEEP`). ``trial``: :func:`sweep_plan`'s options for trying the driver."""
    seeds = stage_seeds(stage, kind)
    if stage == "population":
        return sweep_plan(kind, [condition], seeds.start, len(seeds), budgets[0], (), **trial)
    return sweep_plan("both", [condition], seeds.start, len(seeds), budgets[0], rule_keep, **trial)


def continuation_plan(
    stage: str,
    condition: str,
    kind: str,
    budgets: tuple[int, ...] = BUDGETS,
    judged_seeds: int = len(JUDGED_SEEDS),
    **trial: Any,
) -> Any:
    """The plan of the same runs trained on from their first part to ``budgets[-1]``, every
    other budget's checkpoint kept (the first's is the first part's end, copied). A judged
    stage trains on seeds 0 … ``judged_seeds`` − 1 (fewer than 10 only by PROTOCOL.md's cut)."""
    seeds = stage_seeds(stage, kind)
    if stage == "judged":
        if isinstance(judged_seeds, bool) or not MIN_CUT_SEEDS <= judged_seeds <= len(JUDGED_SEEDS):
            raise ValueError(f"judged_seeds={judged_seeds!r}: expected {MIN_CUT_SEEDS} to {len(JUDGED_SEEDS)}")
        seeds = range(seeds.start, seeds.start + judged_seeds)
    which = kind if stage == "population" else "both"
    return sweep_plan(which, [condition], seeds.start, len(seeds), budgets[-1], tuple(budgets[:-1]), **trial)


def population_name(budget: int) -> str:
    """The population of one budget (the package's folder ``populations/<name>/<condition>/``)."""
    return f"budget-study-ep{budget}"


def committed_member(condition: str, member: str, root: Path | None = None) -> Path:
    """The committed prey of a rule-study member (its 15,000-episode weights)."""
    import pursuit_bench

    if (Path(pursuit_bench.__file__).parent / "benchmark").is_dir():  # 0.2's paths; else the pinned build's
        from pursuit_bench.benchmark import populations
    else:
        from pursuit_bench.pretrained import populations

    base = root if root is not None else populations.FOLDER
    return base / RULE_POPULATION / condition / member / "prey_0.safetensors"


def prey_weights(run: Path, checkpoint: str) -> dict[str, Any]:
    """A run folder's prey weights at one checkpoint, as the population format ships them."""
    from pursuit_bench.training import runs

    _, agents, _ = runs.described(run, checkpoint)
    prey = agents["prey_0"]
    return {k: v.contiguous() for k, v in prey.learner.member_weights(prey.member).items()}  # type: ignore[union-attr]


def prey_equals_committed(
    run: Path, checkpoint: str, condition: str, member: str, root: Path | None = None
) -> tuple[bool, list[str]]:
    """Whether a run's prey at ``checkpoint`` has the committed member's weights to the bit:
    (equal, the names of the tensors that differ or are missing on either side)."""
    import torch

    from pursuit_bench import pretrained

    ours = prey_weights(run, checkpoint)
    theirs, _ = pretrained.read(committed_member(condition, member, root))
    names = sorted(set(ours) | set(theirs))
    differs = [
        n
        for n in names
        if n not in ours
        or n not in theirs
        or ours[n].dtype != theirs[n].dtype
        or ours[n].shape != theirs[n].shape
        or not torch.equal(ours[n], theirs[n])
    ]
    return not differs, differs


def fingerprints(listing: str) -> dict[str, str]:
    """The build's fingerprints from ``git ls-files -s -- pursuit_bench``'s output: ``code``, the
    package's tracked .py files (as the rule study's driver computes it), and ``training_code``,
    those of the layers a training worker imports (the package's ``__init__``, ``io``, ``env``,
    ``rules``, ``agents``, ``training``; ``studies/residual-value/design.py``'s set, with
    ``training/evaluate.py``)."""
    lines = [_as_ls_files(line) for line in listing.splitlines() if line.endswith(".py")]
    code = hashlib.sha256("\n".join(lines).encode()).hexdigest()[:16]
    layers = (
        "pursuit_bench/__init__.py",
        *(f"pursuit_bench/{d}/" for d in ("io", "env", "rules", "agents", "training")),
    )
    training = sorted(
        (line.split("\t", 1)[1], line.split()[1]) for line in lines if line.split("\t", 1)[1].startswith(layers)
    )
    blob = "".join(f"{sha} {path}\n" for path, sha in training)
    return {"code": code, "training_code": hashlib.sha256(blob.encode()).hexdigest()[:16]}


def _as_ls_files(line: str) -> str:
    """A line of ``git ls-tree -r`` (``mode blob sha<TAB>path``) as ``git ls-files -s`` writes it
    (``mode sha 0<TAB>path``); a line of the latter unchanged."""
    about, path = line.split("\t", 1)
    mode, second, third = about.split()
    return f"{mode} {third} 0\t{path}" if second == "blob" else line


def plan() -> list[dict[str, Any]]:
    """What the study trains, in order: each condition's population (cheapest first), then the
    judged runs: each a first part by the rule study's plan, then trained on to 10^6."""
    rows = []
    for stage in ("population", "judged"):
        for condition in CONDITIONS:
            for kind in KINDS if stage == "population" else ("both",):
                first = first_part(stage, condition, kind if kind != "both" else KINDS[0])
                rows.append(
                    {
                        "stage": stage,
                        "condition": condition,
                        "kinds": list(first.predators),
                        "seeds": list(stage_seeds(stage, kind if kind != "both" else KINDS[0])),
                        "first_part": {"episodes": first.episodes, "keep": list(first.keep_checkpoints)},
                        "budgets": list(BUDGETS),
                    }
                )
    return rows


if __name__ == "__main__":
    print(fingerprints(sys.stdin.read()))
