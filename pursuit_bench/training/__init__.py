"""Training and evaluating: the training loop and its config, stacks of runs trained as one, run
folders, sweeps (local and Ray), the paper's evaluation protocol, and the studies' jobs (``jobs``).
Imports ``trajectories``, ``agents``, ``rules``, ``env`` and ``io``; figures are handed to it (e.g.
the eval bar chart, drawn by ``figures``), never imported."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
