"""Adam (Kingma & Ba 2015) over one flat buffer holding every parameter of a network.

The network's parameters are rebound as views of one flat tensor, and their gradients as views
of another, so that one Adam step is one compiled pass over the whole buffer instead of six
operations per parameter tensor. The formulas are torch's single-tensor Adam (no weight decay,
no AMSGrad), element by element in float32; torch's vectorised loops fuse some multiply-adds, so
the two agree to rounding, not bit for bit (``tests/test_dqn.py``). Each element is rounded alike
wherever it lies in the buffer (torch's fused Adam does not), so a member's updates do not
depend on its place in a stack.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
import torch
from torch import nn


@numba.njit(cache=True, error_model="numpy")
def adam_step_kernel(param, grad, exp_avg, exp_avg_sq, weight1, beta2, weight2, step_size, correction2, eps):
    """One Adam step over flat float32 buffers, in place (the scalars float32, as torch rounds them)."""
    for i in range(param.size):
        g = grad[i]
        m = exp_avg[i] + weight1 * (g - exp_avg[i])  # lerp towards g by 1 - β1
        v = exp_avg_sq[i] * beta2 + weight2 * g * g
        exp_avg[i] = m
        exp_avg_sq[i] = v
        param[i] = param[i] + -step_size * (m / (np.sqrt(v) / correction2 + eps))


def flatten_parameters(module: nn.Module) -> torch.Tensor:
    """Rebind every parameter of ``module`` as a view of one flat tensor, in
    ``module.parameters()`` order, and return it: a copy into the module's parameters (e.g.
    ``load_state_dict``) lands in the flat tensor, and the flat tensor is what the kernels read."""
    params = list(module.parameters())
    flat = torch.zeros(sum(p.numel() for p in params))
    offset = 0
    for p in params:
        n = p.numel()
        flat[offset : offset + n].copy_(p.detach().reshape(-1))
        p.data = flat[offset : offset + n].view_as(p)
        offset += n
    return flat


def parameter_offsets(module: nn.Module) -> np.ndarray:
    """Where each parameter starts in :func:`flatten_parameters`'s buffer."""
    sizes = [p.numel() for p in module.parameters()]
    return np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)


class FlatAdam:
    """Adam for every parameter of ``module``. ``exp_avg[i]`` and ``exp_avg_sq[i]`` are views
    shaped like parameter i; ``step`` counts the steps taken (shared by all parameters)."""

    def __init__(
        self, module: nn.Module, lr: float, betas: tuple[float, float] = (0.9, 0.999), eps: float = 1e-8
    ) -> None:
        self.lr, self.betas, self.eps = lr, betas, eps
        self.params = list(module.parameters())
        self.flat = flatten_parameters(module)
        total = self.flat.numel()
        self.grad = torch.zeros(total)
        self._m = torch.zeros(total)
        self._v = torch.zeros(total)
        self.exp_avg: list[torch.Tensor] = []
        self.exp_avg_sq: list[torch.Tensor] = []
        for p, offset in zip(self.params, parameter_offsets(module).tolist(), strict=True):
            n = p.numel()
            p.grad = self.grad[offset : offset + n].view_as(p)  # backward adds into it in place
            self.exp_avg.append(self._m[offset : offset + n].view_as(p))
            self.exp_avg_sq.append(self._v[offset : offset + n].view_as(p))
        self.step_count = 0
        # numpy views of the buffers (never rebound) for the compiled step
        self._buffers = (self.flat.numpy(), self.grad.numpy(), self._m.numpy(), self._v.numpy())

    def zero_grad(self) -> None:
        self.grad.zero_()

    def step(self) -> None:
        """One Adam step over every parameter (the gradient buffer as it stands)."""
        adam_step_kernel(*self.arguments(self.step_count + 1))
        self.step_count += 1

    def arguments(self, step: int) -> tuple[Any, ...]:
        """:func:`adam_step_kernel`'s arguments for the ``step``-th step (counting from 1): the
        buffers and the step's scalars, in float32 as torch rounds them. Counts nothing: the
        caller adds the step to ``step_count`` once it is taken."""
        beta1, beta2 = self.betas
        f32 = np.float32
        return (
            *self._buffers,
            f32(1 - beta1),
            f32(beta2),
            f32(1 - beta2),
            f32(self.lr / (1 - beta1**step)),
            f32(math.sqrt(1 - beta2**step)),
            f32(self.eps),
        )
