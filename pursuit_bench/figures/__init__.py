"""The figures: matplotlib drawings of results handed to them (``plots``). Imports nothing of
pursuit-bench but ``stats`` and ``io``; the analyses and reports call it."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
