"""The environment: the pymunk world (and its numpy twin), obstacles, the task's rules and
rewards, the batched core, the conditions, rendering, the agents' spaces, and its views
(PettingZoo, single-agent Gymnasium, the batched env and Gymnasium's vector env) with the
perturbation wrapper. Imports only ``io``: everything a benchmark user needs, without the
training code. The single-agent views are given their scripted opponents (``rules.opponents``)."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
