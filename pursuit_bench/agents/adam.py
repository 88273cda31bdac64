"""Adam (Kingma & Ba 2015) over one flat buffer holding every parameter of a network.

The network's parameters are rebound as views of one flat tensor, and their gradients as views
of another, so that one Adam step is six element-wise operations on the whole buffer instead of
six per parameter tensor: with twelve small tensors per network, that per-call overhead is most
of an update's cost. The arithmetic is torch's own single-tensor Adam (no weight decay, no
AMSGrad). Element-wise operations round each element alike wherever it lies in the buffer (torch's
fused Adam does not), so a member's updates do not depend on its place in a stack.
"""

from __future__ import annotations

import math

import torch
from torch import nn


class FlatAdam:
    """Adam for every parameter of ``module``. ``exp_avg[i]`` and ``exp_avg_sq[i]`` are views
    shaped like parameter i; ``step`` counts the steps taken (shared by all parameters)."""

    def __init__(
        self, module: nn.Module, lr: float, betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8
    ) -> None:
        self.lr, self.betas, self.eps = lr, betas, eps
        self.params = list(module.parameters())
        total = sum(p.numel() for p in self.params)
        self.flat = torch.zeros(total)
        self.grad = torch.zeros(total)
        self._m = torch.zeros(total)
        self._v = torch.zeros(total)
        self.exp_avg: list[torch.Tensor] = []
        self.exp_avg_sq: list[torch.Tensor] = []
        offset = 0
        for p in self.params:
            n = p.numel()
            self.flat[offset : offset + n].copy_(p.detach().reshape(-1))
            p.data = self.flat[offset : offset + n].view_as(p)
            p.grad = self.grad[offset : offset + n].view_as(p)  # backward adds into it in place
            self.exp_avg.append(self._m[offset : offset + n].view_as(p))
            self.exp_avg_sq.append(self._v[offset : offset + n].view_as(p))
            offset += n
        self.step_count = 0

    def zero_grad(self) -> None:
        self.grad.zero_()

    @torch.no_grad()
    def step(self) -> None:
        beta1, beta2 = self.betas
        self.step_count += 1
        self._m.lerp_(self.grad, 1 - beta1)
        self._v.mul_(beta2).addcmul_(self.grad, self.grad, value=1 - beta2)
        step_size = self.lr / (1 - beta1**self.step_count)
        denom = (self._v.sqrt() / math.sqrt(1 - beta2**self.step_count)).add_(self.eps)
        self.flat.addcdiv_(self._m, denom, value=-step_size)
