"""The rule study (issue 47; REPRODUCTION.md, "Protocol of the rule study"): does the rule inside
the learner help the final policy? Its fixed design, its population, each judged run's
evaluation against the population, and the seed rule.

- **Population** of a condition (:func:`members`): FleeingPrey and the prey of
  :data:`POPULATION_RUNS` hierarchical and as many flat runs, each on its own seed from
  :data:`POPULATION_FIRST_SEED` up (the hierarchical runs first, then the flat ones: no two members
  share initial weights or arena seeds, and none shares them with a judged run, seeds 0–999). Written
  in the population format (OWNERS.md; :func:`write_population`), read back by :func:`load_member`.
- **Judged runs**: both kinds on seeds 0 … n-1, n from the seed rule (:func:`seeds_wanted`),
  every one evaluated at every budget of :data:`BUDGETS` against its condition's population by
  the CRN protocol (:func:`evaluate_run`); each run's compact result is one file under
  ``results/rule-study/runs/`` (:func:`write_run`).
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.agents.names import FLEEING, WITH_AND_WITHOUT_RULE
from pursuit_bench.env.conditions import CONDITIONS

FORMAT = "pursuit-bench-rule-study-1"
POPULATION = "rule-study"
KINDS = WITH_AND_WITHOUT_RULE
#: Training budgets every judged run is evaluated at (checkpoints kept; the last is the run's end).
BUDGETS = (1500, 5000, 10500, 12750, 15000)
#: Learned prey of each kind in a condition's population.
POPULATION_RUNS = 4
#: The population's seeds start here: the judged runs' seeds are 0–999.
POPULATION_FIRST_SEED = 1000
JUDGED_SEEDS_END = 1000
#: Judged runs a kind: first, each step the seed rule adds, and the most.
FIRST_RUNS, STEP_RUNS, MOST_RUNS = 10, 10, 30
#: A judged run fails in a panel when its pool margin at the last budget is below this.
FAILURE_MARGIN = -0.05
#: Episodes per variant per population member, and the evaluation seed.
EPISODES, EVAL_SEED = 60, 12345


def population_seeds(kind: str) -> range:
    """The seeds of a kind's population runs: hierarchical 1000–1003, flat 1004–1007."""
    start = POPULATION_FIRST_SEED + KINDS.index(kind) * POPULATION_RUNS
    return range(start, start + POPULATION_RUNS)


def members(condition: str) -> list[dict[str, Any]]:
    """A condition's population: FleeingPrey first, then each learned member (name, kind, seed)."""
    if condition not in CONDITIONS:
        raise ValueError(f"condition={condition!r}: expected one of {', '.join(CONDITIONS)}")
    learned = [
        {"name": f"{kind}-seed{seed}", "kind": kind, "policy": None, "seed": seed}
        for kind in KINDS
        for seed in population_seeds(kind)
    ]
    return [{"name": FLEEING, "kind": "scripted", "policy": FLEEING, "seed": None}, *learned]


def check_design(judged: dict[str, list[int]], population: list[dict[str, Any]]) -> None:
    """ValueError unless the population's seeds are distinct, at least :data:`POPULATION_FIRST_SEED`,
    and disjoint from every judged seed (``judged``: seeds by kind), and no judged seed lies outside
    0–999: no two members, and no member and judged run, share initial weights or arena seeds."""
    seeds = [m["seed"] for m in population if m["seed"] is not None]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"population seeds repeat: {sorted(seeds)}")
    if any(s < POPULATION_FIRST_SEED for s in seeds):
        raise ValueError(f"population seeds below {POPULATION_FIRST_SEED}: {sorted(seeds)}")
    for kind, chosen in judged.items():
        if any(not 0 <= s < JUDGED_SEEDS_END for s in chosen):
            raise ValueError(f"judged {kind} seeds outside 0–{JUDGED_SEEDS_END - 1}: {chosen}")
        if shared := set(chosen) & set(seeds):
            raise ValueError(f"judged {kind} seeds {sorted(shared)} are population seeds")


# --- the population on disk (the format of OWNERS.md; H49's loader reads it) -------------------


def write_population(where: Path, condition: str, prey: dict[str, Any], trained: dict[str, dict[str, Any]]) -> Path:
    """Write ``where/<condition>/population.json`` and each learned member's prey
    (``prey[name]``: (agent, TrainConfig)) as ``<member>/prey_0.safetensors`` in the population
    format (:func:`pursuit_bench.benchmark.populations.write_index`); ``trained[name]``: preset,
    episodes, predator_kind, build. Returns the population.json path."""
    from pursuit_bench.benchmark import populations

    folder = where / condition
    entries = []
    for member in members(condition):
        name = member["name"]
        files: dict[str, str] = {}
        if member["policy"] is None:
            agent, config = prey[name]
            provenance = {"population": POPULATION, "member": name, "build": str(trained[name]["build"])}
            episodes = int(trained[name]["episodes"])
            stored = populations.store_agent(
                folder, name, "prey_0", agent, config, episodes=episodes, provenance=provenance
            )
            files = {"prey_0": stored}
        entries.append({**member, "trained": trained.get(name) if member["policy"] is None else None, "files": files})
    return populations.write_index(folder, POPULATION, condition, "prey", entries)


def load_member(path: Path) -> Any:
    """One member's prey from its safetensors file: the agent, greedy by default."""
    from pursuit_bench.benchmark.populations import agent_from_file

    return agent_from_file(path, "prey_0")


def read_population(folder: Path) -> list[dict[str, Any]]:
    """A condition's population.json (its members, as the format's entries), read and checked by
    the population format's reader and against the design."""
    from pursuit_bench.benchmark import populations

    read = populations.read(folder)
    names = [m.name for m in read.members]
    expected = [m["name"] for m in members(read.condition)]
    if names != expected:
        raise ValueError(f"{folder}: members {names}, expected {expected}")
    return list(json.loads((folder / populations.INDEX).read_text())["members"])


# --- evaluation of a judged run -----------------------------------------------------------------


def evaluate_run(
    folder: Path,
    population: Path,
    *,
    episodes: int = EPISODES,
    seed: int = EVAL_SEED,
    budgets: tuple[int, ...] = BUDGETS,
) -> dict[str, Any]:
    """A judged run's predators at every budget of :data:`BUDGETS` against each member of its
    condition's population (``population``: the condition's folder), by the CRN protocol: per
    budget and member, each predator's mean return as trained, as always-chase and as always-stalk
    (``panels``), its standard error as trained and the capture rate."""
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import PROTOCOL

    out: dict[str, Any] = {}
    for budget in budgets:
        checkpoint = runs.CHECKPOINT if budget == budgets[-1] else runs.milestone_checkpoint(budget)
        out[str(budget)] = evaluate_checkpoint(folder, checkpoint, population, episodes=episodes, seed=seed)
    return {"protocol": PROTOCOL, "episodes": episodes, "eval_seed": seed, "pool": out}


def evaluate_checkpoint(
    folder: Path,
    checkpoint: str,
    population: Path,
    *,
    episodes: int = EPISODES,
    seed: int = EVAL_SEED,
    outcomes: bool = False,
) -> dict[str, Any]:
    """One checkpoint of a run folder against each member of a population (the condition's
    folder), every member in one batch of arenas: per member, :func:`evaluate_run`'s entries;
    with ``outcomes`` also the prey's (``prey``: return, wall exits, captures, survival in the
    trained variant's episodes)."""
    from pursuit_bench.agents.kinds import ScriptedAgent
    from pursuit_bench.rules.policies import FleeingPrey
    from pursuit_bench.training import runs
    from pursuit_bench.training.evaluate import evaluate_together

    opponents = read_population(population)
    config, agents, _ = runs.described(folder, checkpoint)
    protocol = dict(config.protocol)
    learned_epsilon = protocol.pop("prey_epsilon")
    predators = {k: v for k, v in agents.items() if k != "prey_0"}
    setups: list[tuple[dict[str, Any], float | None]] = []
    for member in opponents:
        if member["policy"] == FLEEING:
            fleeing = FleeingPrey(obstacles=bool(config.task_options.get("obstacles")))
            setups.append(({**predators, "prey_0": ScriptedAgent("prey_0", fleeing)}, None))
        else:
            setups.append(
                ({**predators, "prey_0": load_member(population / member["files"]["prey_0"])}, learned_epsilon)
            )
    results = evaluate_together(
        config.condition, setups, episodes=episodes, seed=seed, prey_check=False, outcomes=outcomes, **protocol
    )
    evaluations = {}
    for member, result in zip(opponents, results, strict=True):
        evaluations[member["name"]] = {
            "panels": {p["predator"]: [p["trained"], p["always_chase"], p["always_stalk"]] for p in result["panels"]},
            "stderr": {p["predator"]: p["stderr"]["trained"] for p in result["panels"]},
            "capture_rate": result["capture_rate"],
            **({"prey": result["prey_outcomes"]} if outcomes else {}),
        }
    return evaluations


def write_run(where: Path, name: str, condition: str, kind: str, seed: int, build: str, result: dict[str, Any]) -> Path:
    """One judged run's compact result, ``where/<name>.json.gz`` (written whole or not at all)."""
    from pursuit_bench.io.files import atomic_write_bytes

    identity = {"format": FORMAT, "name": name, "condition": condition, "kind": kind, "seed": seed, "build": build}
    document = {**result, **identity}  # the run's own seed, whatever the evaluation's result holds
    path = where / f"{name}.json.gz"
    atomic_write_bytes(path, gzip.compress(json.dumps(document).encode(), mtime=0))
    return path


def read_runs(where: Path) -> list[dict[str, Any]]:
    """Every judged run's compact result in ``where`` (sorted by name); ValueError for a file of
    another format."""
    found = []
    for path in sorted(where.glob("*.json.gz")):
        document = json.loads(gzip.decompress(path.read_bytes()))
        if document.get("format") != FORMAT:
            raise ValueError(f"{path}: not a rule-study run (format {FORMAT!r})")
        found.append(document)
    return found


# --- the seed rule ------------------------------------------------------------------------------


def pooled(evaluations: dict[str, Any], predator: str, leave_out: str | None = None) -> dict[str, float]:
    """A predator's pool return and margin from its evaluations against each member (equal
    weight), without member ``leave_out`` if given."""
    rows = [e["panels"][predator] for name, e in evaluations.items() if name != leave_out]
    variants = np.mean(rows, axis=0)
    return {"return": float(variants[0]), "margin": float(variants[0] - max(variants[1], variants[2]))}


def failed(run: dict[str, Any], predator: str, margin: float = FAILURE_MARGIN) -> bool:
    """Whether a judged run fails in a panel: its pool margin at the last budget below ``margin``
    (by more than :data:`~pursuit_bench.stats.TIE`: a margin equal to the line in exact
    arithmetic does not fail by a rounding)."""
    return pooled(run["pool"][last_budget(run)], predator)["margin"] < margin - stats.TIE


def last_budget(run: dict[str, Any]) -> str:
    """The key of a run's last budget (its end of training)."""
    return str(max(int(b) for b in run["pool"]))


def seeds_wanted(
    runs: list[dict[str, Any]],
    first: int = FIRST_RUNS,
    step: int = STEP_RUNS,
    most: int = MOST_RUNS,
    kinds: tuple[str, ...] = KINDS,
) -> int:
    """Judged runs a kind one condition needs by the seed rule, from its runs evaluated so far:
    ``first``; once the first n of every kind of ``kinds`` are in (n < ``most``), n + ``step`` (at
    most ``most``) where some panel has a failed run of any kind among them, else n (the study's:
    :data:`FIRST_RUNS`, :data:`STEP_RUNS`, :data:`MOST_RUNS`)."""
    wanted = first
    while wanted < most:
        chosen = [r for r in runs if r["seed"] < wanted]
        complete = all(sum(r["kind"] == k for r in chosen) >= wanted for k in kinds)
        if not complete:
            return wanted
        predators = chosen[0]["pool"][last_budget(chosen[0])][FLEEING]["panels"]
        if not any(failed(r, p) for r in chosen for p in predators):
            return wanted
        wanted = min(wanted + step, most)
    return wanted


def order(conditions: list[str] | None = None) -> list[str]:
    """Conditions cheapest first: by the sweep's expected cost of a hierarchical and a flat run."""
    from pursuit_bench.training.sweep import expected_cost
    from pursuit_bench.training.train_config import TrainConfig

    def cost(condition: str) -> float:
        return expected_cost(TrainConfig(condition=condition, predator="hierarchical")) + expected_cost(
            TrainConfig(condition=condition, predator="flat")
        )

    chosen = conditions or list(CONDITIONS)
    return sorted(chosen, key=lambda c: (cost(c), list(CONDITIONS).index(c)))
