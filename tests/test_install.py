"""The package as users install it (issue 50): a wheel built from the sources, with its licence;
the environment alone in a fresh venv (no torch, no Rerun) passing PettingZoo's API test, its
command line naming the extra to install; and the wheel with the ``train`` extra evaluating the
shipped agents outside the repository. The venvs are made from PyPI (and the machine's own
wheels) in temporary folders, removed whatever happens; nothing runs with this checkout on the path.
"""

import email
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from pursuit_bench.cli.entry import EXTRA_OF

ROOT = Path(__file__).resolve().parents[1]
#: What a build needs of the checkout (pyproject.toml's readme, license-files and packages).
SOURCES = ("pyproject.toml", "DESCRIPTION.md", "LICENSE", "pursuit_bench")

#: Minutes of installing (the training stack from PyPI): slow, and selectable on its own (-m install).
pytestmark = [pytest.mark.slow, pytest.mark.install]


def _clean_env() -> dict[str, str]:
    """This process's environment without the worktree on the path or a venv activated."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}


def _run(*args: str | Path, cwd: Path, timeout: float = 900) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(a) for a in args], cwd=cwd, env=_clean_env(), capture_output=True, text=True, timeout=timeout
    )


def _ok(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result.stdout


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The wheel, built from a copy of the sources (a build in the checkout would leave build/ there)."""
    where = tmp_path_factory.mktemp("wheel")
    try:
        source = where / "source"
        source.mkdir()
        for name in SOURCES:
            if (ROOT / name).is_dir():
                shutil.copytree(
                    ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc")
                )
            else:
                shutil.copy2(ROOT / name, source / name)
        _ok(_run(sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", where / "dist", source, cwd=where))
        (built,) = (where / "dist").glob("pursuit_bench-*.whl")
        yield built
    finally:
        shutil.rmtree(where, ignore_errors=True)


@pytest.fixture
def venv(tmp_path: Path) -> Iterator[Path]:
    """A fresh venv (its python), removed whatever happens."""
    folder = tmp_path / "venv"
    try:
        _ok(_run(sys.executable, "-m", "venv", folder, cwd=tmp_path))
        yield folder / "bin" / "python"
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _pip(python: Path, *args: str | Path) -> None:
    _ok(
        _run(
            python,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-compile",
            "--disable-pip-version-check",
            *args,
            cwd=python.parents[2],
        )
    )


def test_the_wheel_holds_the_licence_and_says_mit(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        licence = next(n for n in names if n.endswith(".dist-info/licenses/LICENSE"))
        assert (
            "MIT License" in archive.read(licence).decode()
            and "pursuit-bench developers" in archive.read(licence).decode()
        )
        metadata = email.message_from_bytes(archive.read(next(n for n in names if n.endswith(".dist-info/METADATA"))))
    assert metadata["License-Expression"] == "MIT" and metadata["License-File"] == "LICENSE"
    assert metadata["Description-Content-Type"] == "text/markdown"
    page = metadata.get_payload(decode=True).decode()  # what a package index shows
    assert page.strip() == (ROOT / "DESCRIPTION.md").read_text().strip()
    assert {"train", "ray", "test", "docs"} <= set(metadata.get_all("Provides-Extra"))
    plain = [r for r in metadata.get_all("Requires-Dist") if "extra ==" not in r]
    assert sorted(r.split(">")[0].split("<")[0] for r in plain) == [
        "click",
        "gymnasium",
        "numba",
        "numpy",
        "pettingzoo",
        "pymunk",
    ]


#: Run in the environment-only venv: the env imported, PettingZoo's own API test, a step of each
#: view; then what got loaded, which must hold no module of an extra.
ENV_ONLY = """
import sys
import gymnasium
import pursuit_bench
from pettingzoo.test import parallel_api_test
parallel_api_test(pursuit_bench.parallel_env(condition="2p-high-shared"), num_cycles=200)
single = gymnasium.make("pursuit_bench/Pursuit-v0", agent="prey_0", condition="1p-high")
single.reset(seed=0)
single.step(single.action_space.sample())
vector = pursuit_bench.VectorPursuitEnv(4, "1p-high")
vector.reset(seed=0)
vector.step(vector.action_space.sample())
print(pursuit_bench.__file__)
print(" ".join(sorted({name.split(".")[0] for name in sys.modules})))
"""


def test_the_wheel_installs_the_environment_alone_then_the_training_stack(wheel: Path, venv: Path) -> None:
    """One venv, as a user grows it: the environment alone (PettingZoo's API test, the command
    line's one line for each missing extra), then the ``train`` extra (the shipped agents evaluated
    outside the repository). One venv, not two: the training stack takes minutes to install."""
    _pip(venv, wheel, "pytest")  # pytest: pettingzoo.test imports it
    work = venv.parents[2]
    listed = _ok(_run(venv, "-m", "pip", "list", "--format=freeze", cwd=work)).lower()
    for distribution, _ in EXTRA_OF.values():
        assert f"\n{distribution}==" not in f"\n{listed}", f"{distribution} installed with the environment alone"
    output = _ok(_run(venv, "-c", ENV_ONLY, cwd=work))
    location, loaded = output.strip().splitlines()[-2:]
    assert "Passed Parallel API test" in output and location.startswith(str(venv.parents[1]))
    assert not set(loaded.split()) & set(EXTRA_OF), loaded

    script = venv.parent / "pursuit-bench"  # the command line without the training stack
    assert "train" in _ok(_run(script, "--help", cwd=work))
    assert "3p-high-individual" in _ok(_run(script, "conditions", cwd=work))
    result = _run(script, "train", "--episodes", "5", "--out", work / "run", cwd=work)
    assert result.returncode == 1 and result.stderr.strip() == (
        "Error: pursuit-bench train needs torch, which pursuit-bench's 'train' extra installs: in a clone, run "
        "scripts/install.sh (it installs torch's CPU build, then -e '.[train]'); from a wheel, "
        "pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu, "
        f"then pip install 'path/to/{wheel.name}[train]'"
    ), result.stderr
    assert not (work / "run").exists()

    _pip(venv, "torch==2.13.0")  # the CPU build, from the machine's wheels, before the extra pulls another
    _pip(venv, f"{wheel}[train]")
    result = _run(script, "eval", "--pretrained", "1p-high", "--episodes", "20", cwd=work)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "predator_0: hierarchical" in result.stdout
    assert (work / "runs" / "pretrained-1p-high" / "eval.json").is_file()
    agents = "import pursuit_bench; print(pursuit_bench.__file__, pursuit_bench.parallel_env().possible_agents)"
    output = _ok(_run(venv, "-c", agents, cwd=work))
    assert output.startswith(str(venv.parents[1])) and "prey_0" in output, output
