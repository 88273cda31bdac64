"""The pursuit env as PettingZoo names its environments: a versioned module with ``env()``,
``parallel_env()`` and ``raw_env`` (as ``pettingzoo.mpe.simple_tag_v3``)::

    from pursuit_bench import pursuit_v0

    env = pursuit_v0.env(condition="2p-high-shared")            # AEC, PettingZoo's order-enforcing wrapper
    par = pursuit_v0.parallel_env(condition="2p-high-shared")   # ParallelEnv (the native form)
    raw = pursuit_v0.raw_env(condition="2p-high-shared")        # AEC without wrappers

The version (``v0``) changes whenever the environment's dynamics, spaces or rewards change, so
that results name what they ran on; ``pursuit_bench.aec_env`` and ``pursuit_bench.parallel_env``
stay as aliases of ``env`` and ``parallel_env``.
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils.conversions import parallel_to_aec_wrapper

from pursuit_bench.env.pettingzoo_env import PursuitParallelEnv, env, parallel_env

__all__ = ["PursuitParallelEnv", "env", "parallel_env", "raw_env"]


class raw_env(parallel_to_aec_wrapper):
    """The AEC env without PettingZoo's order-enforcing wrapper: the parallel env turned
    agent by agent (``env()`` is this, wrapped). Takes ``condition`` and the options of
    :func:`parallel_env`."""

    def __init__(self, condition: str | None = None, **options: Any) -> None:
        super().__init__(parallel_env(condition, **options))
