"""The science: statistics, the report over seeds, figures, Fig. 3 and chasing by distance,
pursuit laws and their validation, robustness. Imports every layer below it (``training``,
``pretrained``, ``agents``, ``rules``, ``env``, ``io``), never the command line."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
