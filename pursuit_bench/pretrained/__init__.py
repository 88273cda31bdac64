"""Trained agents shipped with the package: for each of the paper's ten conditions, the agents of
one seed of the reproduction sweep (REPRODUCTION.md), the median seed by the predators' mean
return, not the best.

Each agent is one file, ``pretrained/<condition>/<agent name>.safetensors``: the online
network's weights and a text header saying how it was trained (sweep command, preset, seed,
episodes, the full training configuration, project version). safetensors holds tensors and
strings only, so reading a file never runs code from it.

>>> from pursuit_bench import pretrained
>>> agents = pretrained.load("2p-high-individual")   # {"predator_0": …, "predator_1": …, "prey_0": …}
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import save

from pursuit_bench.agents import weights_file
from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.task import obs_size
from pursuit_bench.io.files import atomic_write_bytes
from pursuit_bench.training.train import TrainConfig, build_agents

FOLDER = Path(__file__).parent
"""Where the shipped agents lie (package data)."""
FORMAT = "pursuit-bench-pretrained-1"
SUFFIX = ".safetensors"


def available() -> list[str]:
    """The conditions whose agents are shipped, in the paper's order."""
    return [c for c in CONDITIONS if any((FOLDER / c).glob(f"*{SUFFIX}"))]


def _condition_folder(condition: str, folder: Path | None) -> Path:
    shipped = available() if folder is None else [c for c in CONDITIONS if (folder / c).is_dir()]
    if condition not in shipped:
        raise ValueError(f"no trained agents for condition {condition!r}: expected one of {', '.join(shipped)}")
    return (folder or FOLDER) / condition


def read(path: Path) -> tuple[dict[str, torch.Tensor], dict[str, str]]:
    """One agent's file: (weights by parameter name, header). ``ValueError`` if it is not one."""
    return weights_file.read(path, FORMAT, "pursuit-bench trained agent")


def info(condition: str, *, folder: Path | None = None) -> dict[str, Any]:
    """How the shipped agents of ``condition`` were trained: the header of each agent's file,
    by agent name, with ``training`` parsed back into a dict and numbers as numbers (a
    safetensors header holds strings only)."""
    found = {}
    for path in sorted(_condition_folder(condition, folder).glob(f"*{SUFFIX}")):
        header: dict[str, Any] = {key: _typed(value) for key, value in read(path)[1].items()}
        header["training"] = json.loads(header["training"])
        found[path.name.removesuffix(SUFFIX)] = header
    return found


def described(condition: str) -> tuple[TrainConfig, dict[str, LearningAgent | ScriptedAgent], dict[str, Any]]:
    """The shipped agents of ``condition`` with how they were trained: (training config,
    agents by name, what an evaluation says of them: ``pretrained`` header and ``trained_episodes``)."""
    header = next(iter(info(condition).values()))
    shown = {k: v for k, v in header.items() if k not in ("training", "agent", "kind", "format")}
    about = {"pretrained": shown, "trained_episodes": int(header["trained_episodes"])}
    return TrainConfig.from_dict(header["training"]), load(condition), about


def _typed(value: str) -> Any:
    """A header value as what it says: an int, a float, or the string itself."""
    for kind in (int, float):
        try:
            return kind(value)
        except ValueError:
            continue
    return value


def load(condition: str, *, folder: Path | None = None) -> dict[str, LearningAgent | ScriptedAgent]:
    """The shipped agents of ``condition`` by name (``predator_0`` …, ``prey_0``), ready for
    ``act(observation)`` (greedy) and :func:`~pursuit_bench.training.evaluate.evaluate_agents`.
    ``folder``: read from there instead of the package (for agents you exported yourself)."""
    where = _condition_folder(condition, folder)
    files = {path.name.removesuffix(SUFFIX): (path, *read(path)) for path in sorted(where.glob(f"*{SUFFIX}"))}
    config = TrainConfig.from_dict(json.loads(next(iter(files.values()))[2]["training"]))
    _, (agents,) = build_agents([config], [obs_size(len(CONDITIONS[condition].agent_names))])
    for name, agent in agents.items():
        if not isinstance(agent, LearningAgent):
            continue
        if name not in files:
            raise ValueError(f"{where}: no file for agent {name!r}")
        path, weights, header = files[name]
        if (header.get("condition"), header.get("agent"), header.get("kind")) != (condition, name, agent.kind):
            raise ValueError(
                f"{path}: holds the {header.get('kind')} agent {header.get('agent')!r} of "
                f"{header.get('condition')!r}, not the {agent.kind} agent {name!r} of {condition!r}"
            )
        try:
            agent.learner.load_member_weights(agent.member, weights)
        except ValueError as error:
            raise ValueError(f"{path}: {error}") from None
    return agents


def training_config(condition: str, *, folder: Path | None = None) -> TrainConfig:
    """The training configuration the shipped agents of ``condition`` came from."""
    headers = info(condition, folder=folder)
    return TrainConfig.from_dict(next(iter(headers.values()))["training"])


def export(
    agents: dict[str, LearningAgent | ScriptedAgent],
    config: TrainConfig,
    dest: Path,
    *,
    trained_episodes: int,
    provenance: dict[str, str],
) -> list[Path]:
    """Write each learning agent's weights into ``dest/<condition>/<name>.safetensors``, its
    header saying how it was trained: ``config`` (as JSON), the episodes it trained, the project
    version, and ``provenance`` (e.g. the sweep command, preset, how the seed was chosen)."""
    from pursuit_bench import __version__

    where = dest / config.condition
    where.mkdir(parents=True, exist_ok=True)
    written = []
    for name, agent in agents.items():
        if not isinstance(agent, LearningAgent):
            continue
        header = {
            **provenance,
            "format": FORMAT,
            "condition": config.condition,
            "agent": name,
            "kind": agent.kind,
            "seed": str(config.seed),
            "trained_episodes": str(trained_episodes),
            "training": json.dumps(config.to_dict(), sort_keys=True),
            "version": __version__,
        }
        weights = {k: v.contiguous() for k, v in agent.learner.member_weights(agent.member).items()}
        path = where / f"{name}{SUFFIX}"
        atomic_write_bytes(path, save(weights, metadata=header))
        written.append(path)
    return written


def median_seed(scores: dict[Path, float]) -> Path:
    """Of runs scored by their predators' mean return, the median one (the lower of the two
    middle ones for an even count; ties broken by the folder's name)."""
    if not scores:
        raise ValueError("no runs to choose from: expected at least one evaluated run")
    ranked = sorted(scores, key=lambda path: (scores[path], path.name))
    return ranked[(len(ranked) - 1) // 2]
