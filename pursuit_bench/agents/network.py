"""The dueling Q-network (Wang et al. 2016), with parameters stacked over M independent members.

Trunk ``in → 64 → 64`` (ReLU), value head ``64 → 32 → 1``, advantage head ``64 → 32 → A``,
``Q = V + A - mean(A)`` (docs/spec.md, the agents). Member m's parameters are slice m of every tensor, so M
agents' forward and backward passes run as batched matrix products while their parameters stay
separate: no gradient flows between members.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch
from torch import nn

TRUNK = (64, 64)
HEAD = 32


def member_seeds(seed: int | Sequence[int], members: int) -> list[int]:
    """One seed per member: the given ones, or ``members`` seeds derived from one."""
    if isinstance(seed, int):
        return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(members)]
    if len(seed) != members:
        raise ValueError(f"seed: expected one seed per member ({members}), got {len(seed)}")
    return [int(s) for s in seed]


class StackedLinear(nn.Module):
    """M independent ``Linear(in, out)`` layers applied to (M, B, in) inputs; member m's
    initial weights come from ``generators[m]`` alone."""

    def __init__(self, n_in: int, n_out: int, generators: list[torch.Generator]) -> None:
        super().__init__()
        bound = 1.0 / math.sqrt(n_in)  # torch.nn.Linear's default initialisation, per member

        def draw(*shape: int) -> torch.Tensor:
            return torch.stack([torch.empty(shape).uniform_(-bound, bound, generator=g) for g in generators])

        self.weight = nn.Parameter(draw(n_in, n_out))
        self.bias = nn.Parameter(draw(1, n_out))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.weight.shape[-1] == 1:
            # A one-output layer as a product and a sum: torch's batched matrix product takes
            # another path (matrix-vector) for one member than for several, and its rounding
            # would then depend on how many members are stacked.
            return (x * self.weight.transpose(1, 2)).sum(dim=-1, keepdim=True) + self.bias
        return torch.baddbmm(self.bias, x, self.weight)


class DuelingQNetwork(nn.Module):
    """Dueling MLP for M members: ``forward`` maps (M, B, obs) to Q-values (M, B, A). ``seed``:
    one per member, or one from which the members' are derived; a member's initial weights
    depend on its own seed only, not on its place in the stack or on M."""

    def __init__(self, n_obs: int, n_actions: int, *, members: int = 1, seed: int | Sequence[int] = 0) -> None:
        super().__init__()
        generators = [torch.Generator().manual_seed(s) for s in member_seeds(seed, members)]
        self.n_obs, self.n_actions, self.members = n_obs, n_actions, members
        self.trunk1 = StackedLinear(n_obs, TRUNK[0], generators)
        self.trunk2 = StackedLinear(TRUNK[0], TRUNK[1], generators)
        self.value1 = StackedLinear(TRUNK[1], HEAD, generators)
        self.value2 = StackedLinear(HEAD, 1, generators)
        self.advantage1 = StackedLinear(TRUNK[1], HEAD, generators)
        self.advantage2 = StackedLinear(HEAD, n_actions, generators)

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
