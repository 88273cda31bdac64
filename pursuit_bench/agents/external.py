"""Agents from other people's code, evaluated by the paper's protocol (``pursuit-bench eval
--agent NAME=MODULE:FACTORY``).

The agent protocol: an object with

- ``act(observation) -> action`` for *one* observation, a float32 array of the agent's
  observation space (``6n - 2`` numbers, docs/spec.md); the action as the agent's action space
  has it: a predator ``(mode, direction)`` (two integers, mode 0 stalk / 1 chase, direction
  0..11), the prey a direction 0..11;
- optionally ``act_batch(observations) -> actions`` for a stack (B, 6n - 2), returning (B, 2)
  for a predator or (B,) for the prey; used instead of ``act`` when present (faster).

The factory, ``MODULE:FACTORY``, is a callable taking no argument that returns such an object.
A Stable-Baselines3 model needs none: ``NAME=MODEL.zip`` loads its policy (``sb3_model.py``);
nor does a team file: ``NAME=TEAM.safetensors`` plays the team's agent of NAME's slot (``team_file.py``).
An external agent acts as it is: the ε = 0.1 the paper gives a learned prey during evaluation is
applied to our own agents only.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from pursuit_bench.agents import sb3_model, team_file


def load_factory(spec: str) -> Callable[[], Any]:
    """The callable ``MODULE:FACTORY`` names, or for a Stable-Baselines3 model file (``PATH.zip``)
    one that loads its policy (``agents/sb3_model.py``); ValueError saying what is wrong."""
    if sb3_model.is_model_path(spec):
        return sb3_model.make_factory(spec)
    module_name, _, attribute = spec.partition(":")
    if not module_name or not attribute:
        raise ValueError(f"{spec!r}: expected MODULE:FACTORY, e.g. my_agents:make_predator")
    here = os.getcwd()
    if here not in sys.path:  # the working directory, as ``python -m`` has it
        sys.path.insert(0, here)
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise ValueError(f"{spec!r}: cannot import {module_name!r} ({error})") from None
    except Exception as error:  # the module itself failed while importing
        raise ValueError(f"{spec!r}: importing {module_name!r} raised {type(error).__name__}: {error}") from None
    factory = getattr(module, attribute, None)
    if not callable(factory):
        raise ValueError(f"{spec!r}: {module_name} has no callable {attribute!r}")
    return factory


class ExternalAgent:
    """An object of the agent protocol made usable where our agents are (``act_batch`` with the
    evaluation's keywords); ``kind`` names it in eval.json."""

    def __init__(self, name: str, agent: Any, spec: str, predator: bool) -> None:
        if not (hasattr(agent, "act") or hasattr(agent, "act_batch")):
            raise ValueError(f"{spec!r} returned {type(agent).__name__}, which has neither act nor act_batch")
        self.name, self.agent, self.kind, self.predator = name, agent, f"external ({spec})", predator
        self.spec = spec

    def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> np.ndarray:
        call = "act_batch" if hasattr(self.agent, "act_batch") else "act"
        try:
            if call == "act_batch":
                raw = np.asarray(self.agent.act_batch(obs))
            else:
                raw = np.array([np.asarray(self.agent.act(o)) for o in obs])
        except Exception as error:
            raise ValueError(
                f"agent {self.name} ({self.spec}): {call} raised {type(error).__name__}: {error}"
            ) from None
        shape = (len(obs), 2) if self.predator else (len(obs),)
        if raw.size != int(np.prod(shape)):
            if call == "act":  # said as the agent sees it: one observation in, one action out
                one = "(mode, direction), shape (2,)" if self.predator else "one direction, shape ()"
                got = f"shape {raw.shape[1:]} for one observation"
            else:
                one = (
                    f"(mode, direction) per observation, {shape}"
                    if self.predator
                    else f"one direction per observation, {shape}"
                )
                got = f"shape {raw.shape}"
            raise ValueError(f"agent {self.name} ({self.spec}): {call} returned {got}; expected {one}")
        if not np.issubdtype(raw.dtype, np.number) or not np.all(np.isfinite(raw)) or np.any(raw != np.round(raw)):
            raise ValueError(f"agent {self.name} ({self.spec}): {call} returned non-integer actions ({raw.dtype})")
        actions = raw.astype(np.int64).reshape(shape)
        directions = actions[:, 1] if self.predator else actions
        if np.any((directions < 0) | (directions > 11)) or (
            self.predator and np.any((actions[:, 0] < 0) | (actions[:, 0] > 1))
        ):
            raise ValueError(
                f"agent {self.name} ({self.spec}): {call} returned an action out of range; expected "
                + ("mode 0 or 1 and direction 0..11" if self.predator else "a direction 0..11")
            )
        return actions

    def act(self, observation: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> Any:
        return self.act_batch(np.asarray(observation)[None])[0]


def replaced(agents: dict[str, Any], specs: dict[str, str]) -> dict[str, Any]:
    """``agents`` with the named ones replaced by what their factories return."""
    names = list(agents)
    unknown = sorted(set(specs) - set(names))
    if unknown:
        raise ValueError(f"--agent {unknown[0]}=…: no such agent here; expected one of {', '.join(names)}")
    out = dict(agents)
    for name, spec in specs.items():
        predator = name != names[-1]
        if team_file.is_team_path(spec):
            out[name] = ExternalAgent(
                name, team_member(spec, names.index(name) if predator else 0, predator), spec, predator
            )
            continue
        factory = load_factory(spec)
        try:
            made = factory()
        except Exception as error:
            raise ValueError(f"--agent {name}={spec}: the factory raised {type(error).__name__}: {error}") from None
        if isinstance(made, sb3_model.SB3Policy):
            made.check_role(predator=name != names[-1])
        out[name] = ExternalAgent(name, made, spec, predator=predator)
    return out


def team_member(spec: str, slot: int, predator: bool) -> team_file.TeamMember:
    """The agent of a team file that plays ``slot`` of its role; ValueError if the file's role is the other."""
    team = team_file.Team(spec)
    role = "predator" if predator else "prey"
    if team.role != role:
        raise ValueError(f"{spec}: a {team.role} team; it cannot play the {role}")
    return team.member(slot)
