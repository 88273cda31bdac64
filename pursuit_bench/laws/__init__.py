"""Guidance laws: pure pursuit, proportional and parallel navigation fitted to attack segments
(``guidance``), to the agents' own episodes (``pursuit_laws``), to tracked animals read as movement
datasets (``tracked_laws``), and synthetic attacks with a known answer to validate the fits
(``synthetic_attacks``). Imports ``stats``, ``training``, ``agents``, ``rules``, ``env`` and ``io``."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
