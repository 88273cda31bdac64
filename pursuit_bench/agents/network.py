"""The dueling Q-network (Wang et al. 2016), with parameters stacked over M independent members.

Trunk ``in → 64 → 64`` (ReLU), value head ``64 → 32 → 1``, advantage head ``64 → 32 → A``,
``Q = V + A - mean(A)`` (docs/spec.md, the agents). Member m's parameters are slice m of every tensor, so M
agents' forward and backward passes run as batched matrix products while their parameters stay
separate: no gradient flows between members.
"""

from __future__ import annotations

import math

import torch
from torch import nn

TRUNK = (64, 64)
HEAD = 32


class StackedLinear(nn.Module):
    """M independent ``Linear(in, out)`` layers applied to (M, B, in) inputs."""

    def __init__(self, members: int, n_in: int, n_out: int, generator: torch.Generator) -> None:
        super().__init__()
        bound = 1.0 / math.sqrt(n_in)  # torch.nn.Linear's default initialisation, per member
        self.weight = nn.Parameter(torch.empty(members, n_in, n_out).uniform_(-bound, bound, generator=generator))
        self.bias = nn.Parameter(torch.empty(members, 1, n_out).uniform_(-bound, bound, generator=generator))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.baddbmm(self.bias, x, self.weight)


class DuelingQNetwork(nn.Module):
    """Dueling MLP for M members: ``forward`` maps (M, B, obs) to Q-values (M, B, A)."""

    def __init__(self, n_obs: int, n_actions: int, *, members: int = 1, seed: int = 0) -> None:
        super().__init__()
        generator = torch.Generator().manual_seed(seed)
        self.n_obs, self.n_actions, self.members = n_obs, n_actions, members
        self.trunk1 = StackedLinear(members, n_obs, TRUNK[0], generator)
        self.trunk2 = StackedLinear(members, TRUNK[0], TRUNK[1], generator)
        self.value1 = StackedLinear(members, TRUNK[1], HEAD, generator)
        self.value2 = StackedLinear(members, HEAD, 1, generator)
        self.advantage1 = StackedLinear(members, TRUNK[1], HEAD, generator)
        self.advantage2 = StackedLinear(members, HEAD, n_actions, generator)

    def streams(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``(value_hidden, value, advantage)``: the value stream's last hidden layer (M, B, 32),
        V(s) (M, B, 1) and the advantages (M, B, A)."""
        h = torch.relu(self.trunk2(torch.relu(self.trunk1(obs))))
        value_hidden = torch.relu(self.value1(h))
        return value_hidden, self.value2(value_hidden), self.advantage2(torch.relu(self.advantage1(h)))

    def q_and_value(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Q-values (M, B, A), ``V + A - mean(A)``, and V(s) (M, B)."""
        _, value, advantage = self.streams(obs)
        return value + advantage - advantage.mean(dim=-1, keepdim=True), value[..., 0]

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.q_and_value(obs)[0]
