"""Biological pursuit rules and the scripted agents built on them: parallel navigation, pure
pursuit, obstacle avoidance, the fixed-mode predators and the fleeing prey, and the single-agent
views with those as default opponents. Imports ``env`` and ``io``."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
