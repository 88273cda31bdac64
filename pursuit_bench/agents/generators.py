"""Members' random generators as compiled kernels take them.

numba draws from a numpy ``Generator`` with numpy's own algorithms on the generator's own state:
the same numbers, and the Python object moves on as if numpy had drawn them
(``tests/test_generators.py``). Passed one by one, each generator is unpacked at every call, which
costs more than numpy's call; a numba typed list of them is unpacked once, when it is built (tens
of microseconds), and then passes into a kernel for about a microsecond. :class:`CompiledGenerators`
keeps that list for a learner's members and builds it again only when they change.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from typing import Any

import numpy as np
from numba.typed import List


def compiled_generators(rngs: Sequence[np.random.Generator]) -> Any:
    """``rngs`` as a numba typed list (the generators themselves, not copies); one already is
    returned as it is."""
    if isinstance(rngs, List):
        return rngs
    if not rngs:
        raise ValueError("no generators: expected one per member")
    return List(rngs)


class CompiledGenerators:
    """The typed list of a learner's member generators, built again when the generators change.

    Holds the generators it was built from, so that a generator is never freed while the list
    still points at its state (and an identity is never reused under it)."""

    def __init__(self) -> None:
        self._of: list[np.random.Generator] = []
        self._compiled: Any = None

    def of(self, rngs: Sequence[np.random.Generator]) -> Any:
        """The typed list of ``rngs``: the one built before if they are the same objects."""
        if len(rngs) != len(self._of) or not all(map(operator.is_, rngs, self._of)):
            self._compiled = compiled_generators(rngs)
            self._of = list(rngs)
        return self._compiled

    def __getstate__(self) -> dict[str, Any]:
        return {"_of": [], "_compiled": None}  # a typed list does not pickle: built again on use
