"""Episodes as trajectories: the traces kept while playing and Rerun recordings (``recording``, the
one module that knows Rerun), and the evaluated episodes out as CSV (``trajectory_csv``) and as
movement datasets (``movement_tracks``). Imports ``agents``, ``rules``, ``env`` and ``io``."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
