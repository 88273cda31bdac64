"""Populations of held-out opponents, shipped with the package, against which ``pursuit-bench
score`` plays an agent (docs/leaderboard.md).

One folder per population and condition, ``populations/<population>/<condition>/``, holds
``population.json`` and one sub-folder per learned member with that member's agents of the
population's role, each in the shipped agents' safetensors format (:mod:`pursuit_bench.pretrained`:
weights and a text header, nothing else), named ``<member>/<agent name>.safetensors``::

    {"population": "rule-study", "condition": "1p-high", "role": "prey", "provisional": false,
     "members": [{"name": "hierarchical-seed1000", "kind": "hierarchical", "policy": null,
                  "seed": 1000, "trained": {"preset": …, "episodes": …, "predator_kind": …, "build": …},
                  "files": {"prey_0": "hierarchical-seed1000/prey_0.safetensors"}},
                 {"name": "FleeingPrey", "kind": "scripted", "policy": "FleeingPrey", "seed": null,
                  "trained": null, "files": {}}]}

``kind`` is how the member's run trained its predators (``hierarchical``, ``flat``, ``residual``) or
``scripted``; ``policy`` names a scripted member's policy (:data:`SCRIPTED`). Reading a population
reads JSON and safetensors only: no code from the files runs.

The rule study's population is ``rule-study`` (prey, for the predator role). Until it is
committed, :func:`default` falls back on the provisional ones built from the shipped agents
(:func:`build_provisional`): ``provisional-prey`` (FleeingPrey and the shipped prey of the *other*
conditions with the same number of agents) and ``provisional-predators`` (the shipped predator
teams of the other such conditions, and the scripted pursuers). A condition's own shipped agents
are never in its population: they are the hierarchical reference a score is normalized by.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import pursuit_bench.agents.names as kind_names
from pursuit_bench import pretrained
from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.task import obs_size
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey, PurePursuitPredator
from pursuit_bench.training.train import TrainConfig, build_agents

FOLDER = Path(__file__).parents[1] / "pretrained" / "populations"
"""Where the shipped populations lie (package data)."""
INDEX = "population.json"
ROLES = ("predator", "prey")
KINDS = (kind_names.HIERARCHICAL, kind_names.FLAT, kind_names.RESIDUAL, kind_names.SCRIPTED)
"""The kinds a population's member may be."""
RULE_STUDY = "rule-study"
"""The rule study's population of prey (issue 47), the predator role's population once committed."""
PROVISIONAL = {"predator": "provisional-predators", "prey": "provisional-prey"}
"""The provisional population of each role (of opponents), built by :func:`build_provisional`."""
#: The budget for every shipped population together (tests/test_score.py checks it): 15 MiB until
#: the budget study's populations (issue 63: 3 conditions × 5 budgets of 9 members, about 2 MiB a
#: condition) came; 20 MiB holds them beside the 11.5 MiB shipped before.
SIZE_BUDGET_BYTES = 20 * 1024 * 1024


#: The scripted policies a member may name: the role each plays, and the policy.
SCRIPTED: dict[str, tuple[str, Any]] = {
    "FleeingPrey": ("prey", FleeingPrey),
    "AlwaysChase": ("predator", AlwaysChase),
    "AlwaysStalk": ("predator", AlwaysStalk),
    "PurePursuitPredator": ("predator", PurePursuitPredator),
}


@dataclass(frozen=True)
class Member:
    """One opponent (a prey, or a team of predators) of a population."""

    name: str
    """Unique within the population."""
    kind: str
    """How its run trained the predators (``hierarchical``, ``flat``, ``residual``) or ``scripted``."""
    policy: str | None
    """A scripted member's policy (a key of :data:`SCRIPTED`); None for a learned one."""
    seed: int | None
    """Its run's seed (learned members)."""
    trained: dict[str, Any] | None
    """``preset``, ``episodes``, ``predator_kind``, ``build`` (learned members); ``condition`` where
    it was trained in another condition than the population's (the provisional populations)."""
    files: dict[str, Path]
    """Agent name -> its weights file (learned members)."""

    @property
    def learned(self) -> bool:
        return self.policy is None

    def digests(self) -> set[str]:
        """The fingerprints of its weights (:func:`weights_digest`), to tell it in a scored run."""
        return {weights_digest(pretrained.read(path)[0]) for path in self.files.values()}

    def agents(self, condition: str, names: list[str]) -> dict[str, LearningAgent | ScriptedAgent]:
        """Its agents for the slots ``names`` of ``condition`` (scripted: one copy per slot)."""
        if self.policy is not None:
            return {name: ScriptedAgent(name, SCRIPTED[self.policy][1]()) for name in names}
        return {name: agent_from_file(self.files[name], name, condition) for name in names}


def agent_from_file(path: Path, slot: str, condition: str | None = None) -> LearningAgent:
    """The learned agent a member's weights file holds, named ``slot``, greedy by default; with
    ``condition``, checked to observe what an agent of that condition observes. ValueError naming
    the file where it is the wrong role, size or kind."""
    weights, header = pretrained.read(path)
    config = TrainConfig.from_dict(json.loads(header["training"]))
    role, given = _role(slot), _role(header["agent"])
    if given != role:
        raise ValueError(f"{path}: holds {header['agent']}, a {given}, for the slot {slot}; expected a {role}")
    n_agents = len(CONDITIONS[config.condition].agent_names)
    if condition is not None and obs_size(n_agents) != obs_size(len(CONDITIONS[condition].agent_names)):
        expected = obs_size(len(CONDITIONS[condition].agent_names))
        raise ValueError(
            f"{path}: a {role} trained in {config.condition}, observing {obs_size(n_agents)} numbers; "
            f"a {role} of {condition} observes {expected}"
        )
    _, (built,) = build_agents([config], [obs_size(n_agents, config.obstacles > 0)])  # + range readings
    agent = built[header["agent"]]
    if not isinstance(agent, LearningAgent) or agent.kind != header.get("kind"):
        raise ValueError(
            f"{path}: agent {header['agent']!r} is not a learning {header.get('kind')} agent in its config"
        )
    try:
        agent.learner.load_member_weights(agent.member, weights)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None
    agent.name = slot
    return agent


def _role(agent: str) -> str:
    """The role of an agent by its name (``predator_0``, …, ``prey_0``)."""
    return "prey" if agent.startswith("prey") else "predator"


@dataclass(frozen=True)
class Population:
    """A population of one condition: the opponents an agent of the other role is scored against."""

    name: str
    condition: str
    role: str
    """The members' role: ``prey`` (opponents of a scored predator) or ``predator``."""
    provisional: bool
    members: tuple[Member, ...]

    def without(self, names: set[str]) -> Population:
        return Population(
            self.name,
            self.condition,
            self.role,
            self.provisional,
            tuple(m for m in self.members if m.name not in names),
        )


def weights_digest(weights: dict[str, Any]) -> str:
    """A fingerprint of one agent's weights: SHA-256 over the tensors' names, shapes and float32 bytes."""
    digest = hashlib.sha256()
    for name in sorted(weights):
        tensor = weights[name]
        array = np.ascontiguousarray(tensor.detach().cpu().numpy() if hasattr(tensor, "detach") else tensor, np.float32)
        digest.update(f"{name}{array.shape}".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def available(folder: Path | None = None) -> dict[str, list[str]]:
    """The shipped populations: name -> the conditions each covers (the paper's order)."""
    root = folder or FOLDER
    if not root.is_dir():
        return {}
    found = {}
    for where in sorted(p for p in root.iterdir() if p.is_dir()):
        conditions = [c for c in CONDITIONS if (where / c / INDEX).is_file()]
        if conditions:
            found[where.name] = conditions
    return found


def default(role: str, folder: Path | None = None) -> str:
    """The population of opponents a scored agent of ``role`` plays: the rule study's for a
    predator once it is shipped, else the provisional one of that role."""
    if role == "predator" and RULE_STUDY in available(folder):
        return RULE_STUDY
    return PROVISIONAL["prey" if role == "predator" else "predator"]


def _bad(path: Path, what: str) -> ValueError:
    return ValueError(f"{path}: {what}")


def load(name: str, condition: str, *, folder: Path | None = None) -> Population:
    """The population ``name`` of ``condition``, checked against the format; ValueError saying
    what is wrong. Reads ``population.json`` only: the weights are read when a member plays."""
    root = folder or FOLDER
    where = root / name / condition
    if not (where / INDEX).is_file():
        shipped = available(folder)
        if name not in shipped:
            raise ValueError(f"no population {name!r}: expected one of {', '.join(shipped) or '(none shipped)'}")
        raise ValueError(f"population {name!r} has no condition {condition!r}: it has {', '.join(shipped[name])}")
    return read(where, name, condition)


def read(where: Path, name: str | None = None, condition: str | None = None) -> Population:
    """The population whose ``population.json`` lies in the folder ``where``, checked against the
    format (and to be ``name`` of ``condition`` where given); ValueError saying what is wrong."""
    index = where / INDEX
    try:
        data = json.loads(index.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise _bad(index, f"not readable JSON ({error})") from None
    return _population(data, where, name, condition)


def _population(data: Any, where: Path, name: str | None = None, condition: str | None = None) -> Population:
    """The population a ``population.json`` document (``data``) in ``where`` describes, checked
    against the format (and to be ``name`` of ``condition`` where given): what :func:`read`
    reads and :func:`write_index` writes. ValueError saying what is wrong."""
    index = where / INDEX
    said = (data.get("population"), data.get("condition")) if isinstance(data, dict) else (None, None)
    known = isinstance(said[1], str) and said[1] in CONDITIONS and isinstance(said[0], str)
    if not known or (name or said[0], condition or said[1]) != said:
        raise _bad(index, f"expected population {name or '(a name)'!r} of condition {condition or '(a condition)'!r}")
    condition = data["condition"]
    if data.get("role") not in ROLES or not isinstance(data.get("provisional"), bool):
        raise _bad(index, "expected role 'prey' or 'predator' and provisional true or false")
    role = data["role"]
    slots = list(CONDITIONS[condition].agent_names)
    slots = slots[:-1] if role == "predator" else slots[-1:]
    members = []
    for entry in data.get("members") or []:
        members.append(_member(entry, where, index, role, slots))
    named = [m.name for m in members]
    if not members or len(set(named)) != len(named):
        raise _bad(index, "expected at least one member, each named once")
    trained_runs = [((m.trained or {}).get("condition", condition), m.seed) for m in members if m.seed is not None]
    if len(set(trained_runs)) != len(trained_runs):
        raise _bad(index, "two members are one run (trained in the same condition with the same seed)")
    return Population(data["population"], condition, role, data["provisional"], tuple(members))


def _member(entry: Any, where: Path, index: Path, role: str, slots: list[str]) -> Member:
    if not isinstance(entry, dict) or not isinstance(entry.get("name"), str) or entry.get("kind") not in KINDS:
        raise _bad(index, f"member {entry!r}: expected a name and a kind among {', '.join(KINDS)}")
    name, policy, files = entry["name"], entry.get("policy"), entry.get("files") or {}
    if entry["kind"] == "scripted":
        if not isinstance(policy, str) or SCRIPTED.get(policy, ("",))[0] != role:
            roles = [p for p, (r, _) in SCRIPTED.items() if r == role]
            raise _bad(index, f"member {name}: a scripted {role} needs a policy among {', '.join(roles)}")
        return Member(name, "scripted", policy, None, None, {})
    if policy is not None or sorted(files) != sorted(slots):
        raise _bad(index, f"member {name}: a learned member needs policy null and files for {', '.join(slots)}")
    paths = {}
    for slot, relative in files.items():
        path = (where / relative).resolve()
        if where.resolve() not in path.parents or not path.is_file():
            raise _bad(index, f"member {name}: file {relative!r} is missing or outside the population's folder")
        paths[slot] = path
    seed = entry.get("seed")
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise _bad(index, f"member {name}: a learned member needs an integer seed")
    return Member(name, entry["kind"], None, seed, entry.get("trained"), paths)


def store_agent(
    where: Path, member: str, slot: str, agent: LearningAgent, config: TrainConfig, *, episodes: int,
    provenance: dict[str, str],
) -> str:  # fmt: skip
    """Write ``agent``'s weights as member ``member``'s ``slot`` in the condition folder ``where``
    (``where/<member>/<slot>.safetensors``, the shipped agents' format, ``episodes`` trained),
    written beside and renamed into place; returns the path relative to ``where``, as
    ``population.json`` names it."""
    (where / member).mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=where) as scratch:
        (written,) = pretrained.export(
            {slot: agent}, config, Path(scratch), trained_episodes=episodes, provenance=provenance
        )
        os.replace(written, where / member / f"{slot}{pretrained.SUFFIX}")
    return f"{member}/{slot}{pretrained.SUFFIX}"


def write_index(
    where: Path, name: str, condition: str, role: str, members: list[dict[str, Any]], *, provisional: bool = False,
    **about: Any,
) -> Path:  # fmt: skip
    """``where/population.json`` (the folder of population ``name``'s ``condition``, by the
    shipped ones' layout ``<root>/<name>/<condition>``) for ``members`` (the format's entries:
    name, kind, policy, seed, trained, files relative to ``where``, which must be there), the
    document checked as :func:`read` checks it before anything is written (ValueError, and nothing
    written, if it would not read back); ``about``: further keys of the document (e.g.
    ``obstacles``). Returns its path."""
    index = where / INDEX
    document = {"population": name, "condition": condition, **about, "role": role, "provisional": provisional}
    document["members"] = members
    _population(document, where, name, condition)
    atomic_write_text(index, json.dumps(document, indent=2) + "\n")
    return index


def size_bytes(folder: Path | None = None) -> int:
    """The bytes every shipped population takes together."""
    root = folder or FOLDER
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file()) if root.is_dir() else 0


# ------------------------------------------------------------------ the provisional populations


def _same_shape(condition: str) -> list[str]:
    """The other conditions whose agents see observations of the same size (the same number of agents)."""
    n = len(CONDITIONS[condition].agent_names)
    return [c for c in pretrained.available() if c != condition and len(CONDITIONS[c].agent_names) == n]


def _shipped_member(source: str, slots: list[str], where: Path) -> dict[str, Any]:
    """A member made of ``source``'s shipped agents in ``slots``, their files copied under ``where``."""
    name = f"shipped-{source}"
    headers = pretrained.info(source)
    files = {}
    for slot in slots:
        (where / name).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(
            pretrained.FOLDER / source / f"{slot}{pretrained.SUFFIX}", where / name / f"{slot}{pretrained.SUFFIX}"
        )
        files[slot] = f"{name}/{slot}{pretrained.SUFFIX}"
    header = headers[slots[0]]
    return {
        "name": name,
        "kind": header["training"]["predator"],
        "policy": None,
        "seed": int(header["seed"]),
        "trained": {
            "preset": header.get("preset"),
            "episodes": int(header["trained_episodes"]),
            "predator_kind": header["training"]["predator"],
            "condition": source,
            "build": f"pursuit-bench {header.get('version')} (the shipped agents of {source})",
        },
        "files": files,
    }


def build_provisional(dest: Path | None = None) -> list[Path]:
    """Write the provisional populations of every condition under ``dest`` (the package's
    folder by default), replacing what was there; returns the ``population.json`` files. (Each member is another
    condition's shipped run, its ``trained`` entry naming that condition: two may share a seed.)"""
    root = dest or FOLDER
    written = []
    for role, name in PROVISIONAL.items():
        shutil.rmtree(root / name, ignore_errors=True)
        for condition in pretrained.available():
            where = root / name / condition
            where.mkdir(parents=True)
            slots = list(CONDITIONS[condition].agent_names)
            slots = slots[:-1] if role == "predator" else slots[-1:]
            members = [_shipped_member(source, slots, where) for source in _same_shape(condition)]
            scripted = ["AlwaysChase", "AlwaysStalk", "PurePursuitPredator"] if role == "predator" else ["FleeingPrey"]
            members += [
                {"name": p, "kind": "scripted", "policy": p, "seed": None, "trained": None, "files": {}}
                for p in scripted
            ]
            written.append(write_index(where, name, condition, role, members, provisional=True))
    return written


if __name__ == "__main__":  # python -m pursuit_bench.benchmark.populations: rebuild the provisional ones
    for path in build_provisional():
        print(path)
