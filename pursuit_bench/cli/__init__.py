"""The command line: ``pursuit-bench``. The top layer: it may import every other one."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
