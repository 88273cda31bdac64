"""Submodules as attributes on first use (PEP 562): after ``import pursuit_bench``, a dotted name
such as ``pursuit_bench.training.evaluate.evaluate_agents`` works as written, without importing
each module first, and ``import pursuit_bench`` stays quick (nothing is imported until used)."""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Iterable
from typing import Any


def submodule_getattr(
    package: str, path: Iterable[str], also: Callable[[str], Any] | None = None
) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` (its ``__name__`` and ``__path__``): a name that
    is one of its modules is imported and returned; any other goes to ``also`` (the package's own
    lazy names), else AttributeError as Python words it."""
    modules = {m.name for m in pkgutil.iter_modules(list(path))}

    def __getattr__(name: str) -> Any:
        if name in modules:
            return importlib.import_module(f"{package}.{name}")
        if also is not None:
            return also(name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
