"""Training and evaluating: the training loop and its config, stacks of runs trained as one,
run folders, sweeps (local and Ray), the paper's evaluation protocol and Rerun recordings.
Imports ``agents``, ``rules``, ``env`` and ``io``; figures are handed to it (e.g. the eval bar
chart, drawn by ``study``), never imported."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
