"""The benchmark's public product: the populations (one type, one reader and writer:
``populations``) and the score of an agent or team against them, the contestants and the leaderboard
(``score``, ``leaderboard.json``). Imports ``pretrained``, ``training``, ``agents``, ``rules``, ``env``, ``stats``
and ``io``."""

from pursuit_bench.io.lazy import submodule_getattr

__getattr__ = submodule_getattr(__name__, __path__)
