"""The folders are the layers: io, stats ← env ← rules ← agents ← trajectories ← training ← marl ← pretrained
← benchmark ← laws ← figures ← analysis ← reports ← cli (docs/layout.md).
Every import in the package (function-local ones too) is read from the source; one that runs
upward fails, as does a cycle between modules."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "pursuit_bench"
LAYERS = (
    "io", "stats", "env", "rules", "agents", "trajectories", "training", "marl", "pretrained", "benchmark", "laws",
    "figures", "analysis", "reports", "cli",
)  # fmt: skip
#: The ground floor: layers that import nothing of pursuit-bench but themselves.
GROUND = ("io", "stats")


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else None


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imports(path: Path) -> set[str]:
    """Every pursuit_bench module ``path`` imports (``from pursuit_bench.x import y`` counts
    ``pursuit_bench.x`` and, where y is a module, ``pursuit_bench.x.y``)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("pursuit_bench")}
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("pursuit_bench"):
            found.add(node.module)
            found |= {f"{node.module}.{a.name}" for a in node.names} & set(MODULES)
    return found


def test_every_module_lives_in_a_layer() -> None:
    loose = sorted(m for m in MODULES if m != "pursuit_bench" and layer(m) is None)
    assert not loose, f"modules outside the layers' folders: {loose}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m != "pursuit_bench"))
def test_no_import_runs_upward(module: str) -> None:
    own = LAYERS.index(layer(module))  # type: ignore[arg-type]
    upward = sorted(
        target
        for target in imports(MODULES[module])
        if layer(target) and LAYERS.index(layer(target)) > own  # type: ignore[arg-type]
    )
    assert not upward, f"{module} ({LAYERS[own]}) imports from above: {upward}"


def test_no_cycles_between_modules() -> None:
    graph = {m: {t for t in imports(p) if t in MODULES and t != m} for m, p in MODULES.items() if m != "pursuit_bench"}
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for target in graph.get(node, ()):
            if target == "pursuit_bench" or target not in graph:
                continue
            assert state.get(target) != 1, f"import cycle: {' -> '.join([*path, node, target])}"
            if target not in state:
                visit(target, [*path, node])
        state[node] = 2

    for module in graph:
        if module not in state:
            visit(module, [])


def test_the_walk_sees_an_upward_import(tmp_path: Path) -> None:
    """The check can fail: an env module importing training is caught."""
    source = tmp_path / "bad.py"
    source.write_text(
        "def f():\n    from pursuit_bench.training import runs\n    from pursuit_bench.figures.plots import fig\n"
    )
    assert {"pursuit_bench.training.runs", "pursuit_bench.figures.plots"} <= imports(source)


def test_every_import_names_a_module_that_exists() -> None:
    """A path the move left behind (``from pursuit_bench import runs``) is caught here, not at run time."""
    import pursuit_bench

    public = {*pursuit_bench.__all__, "__version__", *LAYERS}
    stale = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module == "pursuit_bench":
                stale += [f"{module}: {a.name}" for a in node.names if a.name not in public]
            elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("pursuit_bench."):
                if node.module not in MODULES:
                    stale.append(f"{module}: {node.module}")
    assert not stale, stale


@pytest.mark.parametrize("module", sorted(m for m in MODULES if layer(m) in GROUND))
def test_the_ground_floor_imports_only_itself(module: str) -> None:
    """``io`` and ``stats`` stand on nothing of ours: each imports only its own folder."""
    own = layer(module)
    other = sorted(t for t in imports(MODULES[module]) if t != "pursuit_bench" and layer(t) != own)
    assert not other, f"{module} ({own}) imports {other}"


def test_no_module_of_the_package_imports_an_old_path() -> None:
    """The old names (io/moved.py) are for users for one release; the package itself uses the new ones."""
    from pursuit_bench.io.moved import GONE, MOVED

    old = set(MOVED) | set(GONE)
    stale = sorted(f"{m}: {t}" for m, p in MODULES.items() for t in imports(p) if t in old)
    assert not stale, stale


@pytest.mark.parametrize("old", ["pursuit_bench.study.score", "pursuit_bench.pretrained.populations"])
def test_an_old_path_gives_the_moved_module_and_warns(old: str) -> None:
    import importlib
    import subprocess
    import sys

    from pursuit_bench.io.moved import MOVED

    # a fresh interpreter: in this one the old name may already be imported (no second warning)
    parent, name = old.rsplit(".", 1)
    code = (
        "import warnings, importlib\n"
        "warnings.simplefilter('error', DeprecationWarning)\n"
        "import pursuit_bench\n"
        "try:\n"
        f"    from {parent} import {name}\n"
        "except DeprecationWarning as e:\n"
        "    print('warned:', e)\n"
        "warnings.simplefilter('ignore', DeprecationWarning)\n"
        f"from {parent} import {name} as old\n"
        f"print('same:', old is importlib.import_module({MOVED[old]!r}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True).stdout
    assert f"warned: {old} moved to {MOVED[old]}" in out
    assert "same: True" in out
    assert importlib.import_module(MOVED[old]).__name__ == MOVED[old]
