"""Analyses of trained agents: the behaviour behind the numbers (Fig. 3's value-stream embedding
and chasing by distance: ``behaviour``, ``fig3``), robustness ladders and cross-play (``robustness``).
Imports ``figures``, ``laws``, ``benchmark``, ``training`` and every layer below."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
