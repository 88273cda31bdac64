"""pursuit-bench: a predator–prey benchmark for multi-agent RL (Tsutsui, Takeda, Fujii 2023).

``pursuit_v0`` is the PettingZoo environment module (``env()``, ``parallel_env()``,
``raw_env``, as PettingZoo names them); ``parallel_env(condition=…)`` and
``aec_env(condition=…)`` are the same builders at the top (the AEC one is not called ``env``
here: ``pursuit_bench.env`` is the environment's layer);
``VectorPursuitEnv`` steps B arenas at once; ``gymnasium.make("pursuit_bench/Pursuit-v0",
agent=…, condition=…)`` is a single-agent view, and ``gymnasium.make_vec`` with the same
arguments N of them as one Gymnasium ``VectorEnv`` over the batched core; ``load_agents(RUN)``
returns the trained agents of a run folder by name.

The package's layers are folders (each ``__init__`` says what it holds and may import; docs/layout.md):
``io`` and ``stats`` ← ``env`` ← ``rules`` ← ``agents`` ← ``trajectories`` ← ``training`` ←
``pretrained`` (the shipped agents) ← ``benchmark`` ← ``laws`` ← ``figures`` ← ``analysis`` ←
``reports`` ← ``cli``. Modules that moved in 0.2 import by their old names for one release
(``io/moved.py``). The envs, numba's kernels and torch are imported when
first used, so that ``import pursuit_bench`` (and the command line's ``--help``) stays quick.
"""

from __future__ import annotations

import importlib
import os
from typing import TYPE_CHECKING, Any

# MKL picks its matrix kernels by CPU, and evaluations' bits follow its pick (MKL_CBWR=COMPATIBLE
# changes them; docs/departures.md, "Reproducibility across machines"): pinned to its AVX2 path,
# the same on every x86 CPU since 2013, unless the user set it. MKL reads this when first used:
# before torch is.
os.environ.setdefault("MKL_CBWR", "AVX2")
# OpenBLAS (numpy's and SciPy's, whose products the compiled update calls: agents/fused.py) also
# picks its kernels by CPU, and training's bytes follow its pick: on a CPU with AVX-512 it took its
# SkylakeX kernels and the README's main job trained to other figures. Pinned to its Haswell
# kernels (AVX2, every x86 CPU since 2013) unless the user set it; OpenBLAS reads this when its
# library loads, so before numpy is imported (docs/departures.md, "Reproducibility across machines").
# Worker processes (sweeps, Ray) inherit the setting from this process's environment.
os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")

import gymnasium

from pursuit_bench.env.conditions import CONDITIONS, TaskConfig
from pursuit_bench.io import moved

if TYPE_CHECKING:
    from pursuit_bench.env import pursuit_v0
    from pursuit_bench.env.pettingzoo_env import PursuitParallelEnv, parallel_env
    from pursuit_bench.env.pettingzoo_env import env as aec_env
    from pursuit_bench.env.vector import VectorPursuitEnv
    from pursuit_bench.training.runs import load_agents

__all__ = [
    "CONDITIONS",
    "PursuitParallelEnv",
    "TaskConfig",
    "VectorPursuitEnv",
    "aec_env",
    "load_agents",
    "parallel_env",
    "pursuit_v0",
]
__version__ = "0.1.0"

_LAZY = {
    "PursuitParallelEnv": "pursuit_bench.env.pettingzoo_env",
    "aec_env": "pursuit_bench.env.pettingzoo_env",
    "parallel_env": "pursuit_bench.env.pettingzoo_env",
    "VectorPursuitEnv": "pursuit_bench.env.vector",
    "load_agents": "pursuit_bench.training.runs",
}


#: The layers and the shipped agents, imported on first use as attributes
#: (``pursuit_bench.pretrained.info``, ``pursuit_bench.env.task``).
_SUBPACKAGES = {
    "agents", "analysis", "benchmark", "cli", "env", "figures", "io", "laws", "pretrained", "reports", "rules",
    "stats", "training", "trajectories",
}  # fmt: skip


def __getattr__(name: str) -> Any:
    if name in _SUBPACKAGES:
        return importlib.import_module(f"pursuit_bench.{name}")
    if name == "pursuit_v0":
        return importlib.import_module("pursuit_bench.env.pursuit_v0")
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), "env" if name == "aec_env" else name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'pursuit_bench' has no attribute {name!r}")


moved.install()

if "pursuit_bench/Pursuit-v0" not in gymnasium.registry:
    gymnasium.register(
        id="pursuit_bench/Pursuit-v0",
        # the views live in env/, their scripted default opponents in rules/: the factories join them
        entry_point="pursuit_bench.rules.opponents:single_agent_env",
        vector_entry_point="pursuit_bench.rules.opponents:vector_env",
    )
