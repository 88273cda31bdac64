"""The ground floor: files written atomically, the run folder's lock, stopping cleanly on SIGINT
and SIGTERM. Imports nothing of the package; any layer may import it."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
