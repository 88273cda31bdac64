"""The reports ``pursuit-bench report`` writes over a study's folders: the reproduction over seeds
(Fig. 2, the compact results: ``reproduction``), the N-kind rule study (``rule_study``: its design and
members; ``rule_report``) and the frozen pool study (``pool``). Imports ``analysis`` and every layer
below; the command line imports it."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
