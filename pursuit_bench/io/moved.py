"""Modules that moved in 0.2's redesign (docs/layout.md), importable under their old names for one
release: ``import pursuit_bench.study.score`` gives ``pursuit_bench.benchmark.score`` itself (the
same module object, so monkeypatching and ``isinstance`` behave) with a DeprecationWarning naming
the new place. The study drivers pinned to an earlier build (studies/*/build.json) import by that
build's paths, which is why the old names are kept and not only listed in the CHANGELOG.

Nothing is imported here: the table holds names, and a moved module is imported when its old name
is, through a finder at the front of ``sys.meta_path``: at the end, ``pursuit_bench.pretrained.populations``
would import as the folder of the shipped populations' weights (a namespace package) instead.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from types import ModuleType
from typing import Any

#: The old dotted name of each moved module and its new one.
MOVED = {
    "pursuit_bench.study.statistics": "pursuit_bench.stats",
    "pursuit_bench.study.guidance": "pursuit_bench.laws.guidance",
    "pursuit_bench.study.pursuit_laws": "pursuit_bench.laws.pursuit_laws",
    "pursuit_bench.study.synthetic_attacks": "pursuit_bench.laws.synthetic_attacks",
    "pursuit_bench.study.tracked_laws": "pursuit_bench.laws.tracked_laws",
    "pursuit_bench.study.score": "pursuit_bench.benchmark.score",
    "pursuit_bench.pretrained.populations": "pursuit_bench.benchmark.populations",
    "pursuit_bench.study.plots": "pursuit_bench.figures.plots",
    "pursuit_bench.study.analysis": "pursuit_bench.analysis.behaviour",
    "pursuit_bench.study.fig3": "pursuit_bench.analysis.fig3",
    "pursuit_bench.study.robustness": "pursuit_bench.analysis.robustness",
    "pursuit_bench.study.report": "pursuit_bench.reports.reproduction",
    "pursuit_bench.study.rule_report": "pursuit_bench.reports.rule_report",
    "pursuit_bench.study.pool": "pursuit_bench.reports.pool",
    "pursuit_bench.study.rule_study": "pursuit_bench.reports.rule_study",
    "pursuit_bench.study.jobs": "pursuit_bench.training.jobs",
    "pursuit_bench.training.recording": "pursuit_bench.trajectories.recording",
    "pursuit_bench.training.movement_tracks": "pursuit_bench.trajectories.movement_tracks",
    "pursuit_bench.training.trajectory_csv": "pursuit_bench.trajectories.trajectory_csv",
}
#: Old packages that no longer exist at all: their names import as empty packages whose moved
#: submodules come through the table.
GONE = ("pursuit_bench.study",)


class MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the old names of :data:`MOVED` and :data:`GONE`; loading one puts the new module in
    ``sys.modules`` under the old name (the import system returns what ``sys.modules`` holds)."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if fullname in MOVED or fullname in GONE:
            return importlib.util.spec_from_loader(fullname, self, is_package=fullname in GONE)
        return None

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return None

    def exec_module(self, module: ModuleType) -> None:
        name = module.__name__
        if name in GONE:
            module.__path__ = []
            module.__doc__ = (
                f"Moved (docs/layout.md): {name}'s modules are importable by their old names for one release."
            )
            return
        warnings.warn(
            f"{name} moved to {MOVED[name]} (docs/layout.md); the old name goes in the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        sys.modules[name] = importlib.import_module(MOVED[name])


def install() -> None:
    """Put :class:`MovedFinder` at the front of ``sys.meta_path`` once."""
    if not any(isinstance(f, MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())
