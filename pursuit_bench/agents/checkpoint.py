"""Saving and loading learning agents.

A checkpoint holds tensors and plain Python values only and is read with
``torch.load(weights_only=True)``, which refuses to run code: loading a file never executes
anything from it. Each agent's entry names its kind, the condition it was trained in and its
network's sizes; loading it into another kind or condition is a ``ValueError``.
"""

from __future__ import annotations

import io
import os
import pickle
from typing import Any

import torch

from pursuit_bench.agents.kinds import LearningAgent
from pursuit_bench.io.files import atomic_write_bytes

FORMAT = "pursuit-bench-checkpoint-1"


def agent_state(agent: LearningAgent, condition: str) -> dict[str, Any]:
    """Everything needed to resume one agent, with what it is and where it was trained."""
    learner = agent.learner
    return {
        "kind": agent.kind,
        "condition": condition,
        "name": agent.name,
        "n_obs": learner.n_obs,
        "n_actions": learner.n_actions,
        "config": learner.config.to_dict(),
        "learner": learner.member_state(agent.member),
    }


def load_agent_state(agent: LearningAgent, state: dict[str, Any], condition: str) -> None:
    """Restore ``agent`` from :func:`agent_state`, refusing a foreign kind, condition or size."""
    if state.get("kind") != agent.kind:
        raise ValueError(f"checkpoint of {state.get('name')} is a {state.get('kind')!r} agent, not {agent.kind!r}")
    if state.get("condition") != condition:
        raise ValueError(f"checkpoint was trained in condition {state.get('condition')!r}, not {condition!r}")
    learner = agent.learner
    if (state.get("n_obs"), state.get("n_actions")) != (learner.n_obs, learner.n_actions):
        raise ValueError(
            f"checkpoint network has {state.get('n_obs')} inputs and {state.get('n_actions')} actions, "
            f"not {learner.n_obs} and {learner.n_actions}"
        )
    learner.load_member_state(agent.member, state["learner"])


def save(path: str | os.PathLike[str], payload: dict[str, Any]) -> None:
    """Write a checkpoint atomically."""
    buffer = io.BytesIO()
    torch.save({"format": FORMAT, **payload}, buffer)
    atomic_write_bytes(path, buffer.getvalue())


def _reason(error: Exception) -> str:
    """torch's complaint in a few words (its own runs to several sentences of advice)."""
    text = str(error).strip()
    if "zip archive" in text or isinstance(error, EOFError):
        return "truncated or corrupted"
    if "Weights only load failed" in text:
        return "not a file of tensors torch saved, or corrupted"
    first = text.splitlines()[0].split(". ")[0] if text else type(error).__name__
    return first if len(first) <= 80 else first[:77] + "..."


def read(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a checkpoint without running any code from it; ``ValueError`` if it is not one."""
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise ValueError(f"{path}: no such checkpoint") from None
    except (pickle.UnpicklingError, RuntimeError, EOFError, ValueError, OSError) as error:
        raise ValueError(f"{path}: not a readable pursuit-bench checkpoint ({_reason(error)})") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ValueError(f"{path}: not a pursuit-bench checkpoint (format {FORMAT!r} expected)")
    return payload


def save_agent(agent: LearningAgent, path: str | os.PathLike[str], *, condition: str) -> None:
    """Save one agent (weights, optimizer, replay, schedule step)."""
    save(path, {"agents": {agent.name: agent_state(agent, condition)}})


def load_agent(agent: LearningAgent, path: str | os.PathLike[str], *, condition: str) -> None:
    """Load one agent saved by :func:`save_agent` (or by a training run) into ``agent``."""
    agents = read(path).get("agents", {})
    if agent.name not in agents:
        raise ValueError(f"{path}: holds no agent named {agent.name!r} (it has {sorted(agents)})")
    load_agent_state(agent, agents[agent.name], condition)
