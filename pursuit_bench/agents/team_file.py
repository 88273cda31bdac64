"""A team trained by another library, as a file of weights: ``score TEAM.safetensors`` and
``eval --agent predator_0=TEAM.safetensors``.

A team file (``pursuit-bench marl train`` writes one, ``pursuit_bench/marl/``) holds one
multi-layer perceptron per agent of a role: dense layers with one activation between them,
observation in, one score per action out, the agent acting by the largest (a policy's logits, a
Q-learner's values: both greedy). A predator's scores are over the 24 joint actions
(``env/joint_actions.py``: ``divmod(a, 12)`` is (mode, direction)), the prey's over its 12
directions. The file is safetensors: tensors and a text header, so loading it runs no code.

Tensors ``{agent}.{k}.weight`` (out, in) and ``{agent}.{k}.bias`` for layers k = 0, 1, …; the
header names the format (:data:`FORMAT`), the role, the agents in slot order, the activation,
the condition trained in and where the team came from (library, algorithm, seed, frames)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import torch
from safetensors.torch import save

from pursuit_bench.agents import weights_file
from pursuit_bench.env.joint_actions import N_JOINT, split
from pursuit_bench.env.task import N_DIRECTIONS
from pursuit_bench.io.files import atomic_write_bytes

FORMAT = "pursuit-bench team 1"
#: The activations a team file may name, as torch computes them.
ACTIVATIONS = {"tanh": torch.tanh, "relu": torch.relu}
SUFFIX = ".safetensors"


def is_team_path(spec: str) -> bool:
    """Whether an ``--agent`` value or a score's AGENT names a team file."""
    return spec.endswith(SUFFIX)


def write(path: Path, layers: dict[str, list[tuple[torch.Tensor, torch.Tensor]]], header: dict[str, Any]) -> None:
    """Write a team file: ``layers`` by agent name (slot order), each a list of (weight, bias);
    ``header`` (role, condition, activation, provenance) as text. Complete or not there."""
    tensors = {
        f"{agent}.{k}.{part}": tensor.detach().to(torch.float32).contiguous().clone()
        for agent, stack in layers.items()
        for k, pair in enumerate(stack)
        for part, tensor in zip(("weight", "bias"), pair, strict=True)
    }
    metadata = {key: value if isinstance(value, str) else json.dumps(value) for key, value in header.items()}
    metadata |= {"format": FORMAT, "agents": json.dumps(list(layers))}
    atomic_write_bytes(path, save(tensors, metadata=metadata))


class TeamMember:
    """One agent of a team file, behind ``act_batch`` (the agent protocol, ``agents/external.py``):
    greedy (mode, direction) pairs for a predator, directions for the prey."""

    def __init__(self, team: Team, name: str) -> None:
        self.team, self.name = team, name
        self.layers = team.layers[name]

    def scores(self, observations: np.ndarray) -> torch.Tensor:
        x = torch.as_tensor(np.asarray(observations, dtype=np.float32))
        activation = ACTIVATIONS[self.team.activation]
        for k, (weight, bias) in enumerate(self.layers):
            x = torch.nn.functional.linear(x, weight, bias)
            if k < len(self.layers) - 1:
                x = activation(x)
        return x

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        if observations.shape[-1] != self.team.observes:
            raise ValueError(
                f"{self.team.path}: its agents observe {self.team.observes} numbers, this one {observations.shape[-1]}:"
                " it was trained in a condition with another number of agents"
            )
        with torch.no_grad():
            best = self.scores(observations).argmax(dim=-1).numpy()
        return split(best) if self.team.role == "predator" else best.astype(np.int64)


class Team:
    """A team file read (the format above); ValueError in one line if it is not one."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise ValueError(f"{self.path}: no such team file")
        tensors, header = weights_file.read(self.path, FORMAT, "pursuit-bench team file")
        self.header = header
        self.role = header.get("role", "")
        self.activation = header.get("activation", "")
        self.condition = header.get("condition", "")
        if self.role not in ("predator", "prey") or self.activation not in ACTIVATIONS:
            raise ValueError(
                f"{self.path}: a team file needs role predator/prey and activation {'/'.join(ACTIVATIONS)}"
            )
        try:
            self.agents: list[str] = json.loads(header["agents"])
            if not isinstance(self.agents, list) or not self.agents:
                raise ValueError
        except (KeyError, ValueError):
            raise ValueError(f"{self.path}: a team file's header names its agents (a JSON list)") from None
        self.layers: dict[str, list[tuple[torch.Tensor, torch.Tensor]]] = {}
        for agent in self.agents:
            stack: list[tuple[torch.Tensor, torch.Tensor]] = []
            while f"{agent}.{len(stack)}.weight" in tensors:
                k = len(stack)
                weight, bias = tensors[f"{agent}.{k}.weight"], tensors.get(f"{agent}.{k}.bias")
                if bias is None or weight.dim() != 2 or bias.shape != (weight.shape[0],):
                    raise ValueError(f"{self.path}: {agent}'s layer {k} is not a (out, in) weight with its bias (out,)")
                stack.append((weight, bias))
            if not stack:
                raise ValueError(f"{self.path}: no layers for {agent}")
            self.layers[agent] = stack
        self.observes = int(self.layers[self.agents[0]][0][0].shape[1])
        outputs = N_JOINT if self.role == "predator" else N_DIRECTIONS
        for agent, stack in self.layers.items():
            shapes_chain = all(a[0].shape[0] == b[0].shape[1] for a, b in itertools.pairwise(stack))
            if stack[0][0].shape[1] != self.observes or stack[-1][0].shape[0] != outputs or not shapes_chain:
                raise ValueError(
                    f"{self.path}: {agent}'s layers do not chain from {self.observes} observations to {outputs} actions"
                )

    def member(self, slot: int) -> TeamMember:
        """The agent that plays slot ``slot`` of the role (0-based)."""
        if not 0 <= slot < len(self.agents):
            raise ValueError(f"{self.path}: a team of {len(self.agents)}; no agent for slot {slot}")
        return TeamMember(self, self.agents[slot])

    def describe(self) -> str:
        how = ", ".join(f"{k} {self.header[k]}" for k in ("library", "algorithm", "seed", "frames") if k in self.header)
        return f"{self.path} (a {self.role} team of {len(self.agents)} trained in {self.condition}; {how})"
