"""What a new user hit in round four (issue 50): the progress ETA, the recordings hint, the
opponents error for the shipped agents, the message for a missing extra, sweep's help."""

import io
import tomllib
from pathlib import Path

import pytest
from cli_helpers import run_cli
from packaging.requirements import Requirement

from pursuit_bench.cli import entry, progress

ROOT = Path(__file__).resolve().parents[1]


def test_the_eta_leaves_out_the_start_up_and_says_when_it_is_a_floor(monkeypatch) -> None:
    clock = [0.0]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    log = io.StringIO()
    bar = progress.Progress("train", 1000, 0, lambda: "", every_episodes=100, file=log, eta=True)
    clock[0] = 20.0  # imports and compiling: no episode's time
    for done in range(1, 1001):
        clock[0] += 1 / 64 if done <= 200 else 1 / 8  # 64 episodes a second, then 8 (they lengthen)
        bar.update(done)
    lines = {int(line.split("episode ")[1].split("/")[0]): line for line in log.getvalue().splitlines()}

    def eta(done: int) -> tuple[bool, float]:  # (a floor?, seconds)
        text = lines[done].split("| ETA ")[1].split(" |")[0]
        h, m, sec = text.removeprefix("≥ ").split(" ")[0].split(":")
        return text.startswith("≥ "), 3600 * int(h) + 60 * int(m) + int(sec)

    # at 100: 900 left at 64 a second (counting the start-up, 4.5 a second, would say 3 min 20 s)
    assert eta(100) == (False, 14), lines[100]
    # at 300: 700 left at the last tenth's 8 a second (87.5 s; the window's first point is an episode
    # early), a floor, for the tenth before ran at 64
    floor, seconds = eta(300)
    assert floor and 85 <= seconds <= 87 and "(a lower bound while episodes lengthen" in lines[300], lines[300]
    # at 500: steady at 8 a second, 500 left
    assert eta(500) == (False, 62), lines[500]


def test_the_sweep_s_first_eta_is_marked_as_a_floor() -> None:
    """The sweep's ETA at the rate since the command started: a floor (``≥ … (early)``) until a
    tenth of the work left at the start is done, then plain; ``?`` before any work."""
    from pursuit_bench.cli.sweep import eta_text

    assert eta_text(done=10.0, start=10.0, total=1000.0, elapsed=5.0) == "?"
    # 50 of the 990 left done in 100 s: 0.5 a second, 940 left take 1880 s, under a tenth done
    assert eta_text(done=60.0, start=10.0, total=1000.0, elapsed=100.0) == "≥ 00:31:20 (early)"
    # 200 done in 400 s: 800 left at 0.5 a second
    assert eta_text(done=200.0, start=0.0, total=1000.0, elapsed=400.0) == "00:26:40"


def _train(out: Path, *extra: str) -> str:
    code, output = run_cli(
        "train", "--condition", "1p-high", "--episodes", "2", "--num-envs", "2", "--out", str(out), *extra
    )
    assert code == 0, output
    return output


def test_no_record_prints_no_recordings_hint(tmp_path: Path) -> None:
    assert "pursuit-bench view" not in _train(tmp_path / "quiet", "--no-record")
    assert f"recordings: pursuit-bench view {tmp_path / 'recorded'}" in _train(tmp_path / "recorded")


def test_the_shipped_agents_mismatch_names_opponents_not_a_training(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    args = ["eval", "--pretrained", "1p-high", "--episodes", "4", "--no-record"]
    code, output = run_cli(*args, "--opponents", "pretrained:2p-low-shared")
    assert code == 2 and "choose opponents with 1 predator(s)" in output, output
    _train(tmp_path / "run", "--no-record")  # the quick preset: wall features off, the shipped agents' on
    code, output = run_cli(*args, "--opponents", str(tmp_path / "run"))
    assert code == 2 and "choose opponents trained with --wall-features" in output, output
    assert "train" not in output.replace("trained", ""), output


def test_a_missing_module_names_its_extra_in_one_line(monkeypatch) -> None:
    monkeypatch.setattr(entry.sys, "argv", ["pursuit-bench", "train", "--episodes", "5"])
    message = entry.missing_extra(ModuleNotFoundError("No module named 'torch'", name="torch"))
    assert message == (
        "Error: pursuit-bench train needs torch, which pursuit-bench's 'train' extra installs: in a clone, run "
        "scripts/install.sh (it installs torch's CPU build, then -e '.[train]'); from a wheel, "
        "pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu, "
        f"then pip install 'path/to/pursuit_bench-{entry._version()}-py3-none-any.whl[train]'"
    )
    # pursuit-bench is on no index (issue 67): the message names what works from a clone or a wheel
    assert "pursuit-bench[" not in message
    ray = str(entry.missing_extra(ModuleNotFoundError(name="ray.util")))
    assert "run scripts/install.sh ray (" in ray and ray.endswith("-py3-none-any.whl[ray]'"), ray
    assert entry.missing_extra(ModuleNotFoundError(name="stable_baselines3")) is None


def test_every_module_of_the_extras_is_named_and_the_environment_needs_none() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    named = {distribution: extra for distribution, extra in entry.EXTRA_OF.values()}
    for extra in ("train", "ray"):
        own = {Requirement(r).name for r in extras[extra] if not r.startswith("pursuit-bench")}
        assert own == {d for d, e in named.items() if e == extra}, extra
    assert not {Requirement(r).name for r in project["dependencies"]} & set(named)
    for extra in ("ray", "test", "docs", "bench"):  # each stack brings the training stack with it
        assert "pursuit-bench[train]" in extras[extra], extra
    assert project["scripts"]["pursuit-bench"] == "pursuit_bench.cli.entry:main"


@pytest.mark.parametrize("command", ["sweep"])
def test_sweep_help_offers_all_predator_kinds(command: str) -> None:
    code, output = run_cli(command, "--help")
    assert code == 0 and "'all' or comma-separated predator kinds" in " ".join(output.split())
