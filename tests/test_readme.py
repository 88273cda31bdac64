"""scripts/check_readme.py on a fast path: the shipped agents' figures evaluated afresh (seconds)
and the training run's spread over seeds from its committed source file."""

import json
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from cli_helpers import run_cli

sys.path.insert(0, str(Path(__file__).parents[1] / "scripts"))
import check_readme


def test_the_readme_quotes_the_shipped_agents_as_the_main_job_evaluates_them(tmp_path: Path) -> None:
    out = tmp_path / "demo-pretrained"
    code, output = run_cli(
        "eval", "--pretrained", "2p-high-individual", "--episodes", "300", "--out", str(out), "--no-record"
    )
    assert code == 0, output
    sentence = check_readme.shipped_sentence(json.loads((out / "eval.json").read_text()))
    assert sentence in check_readme.readme()


def test_the_readme_quotes_the_training_runs_spread_over_seeds() -> None:
    seeds = json.loads(check_readme.SEEDS.read_text())
    assert [s["seed"] for s in seeds["seeds"]] == [0, 1, 2, 3, 4]
    assert check_readme.spread_sentence(seeds) in check_readme.readme()
    seed0 = seeds["seeds"][0]
    assert check_readme.outside(seed0, seeds) == []
    moved = {**seed0, "always_chase": max(s["always_chase"] for s in seeds["seeds"]) + 0.01}
    assert check_readme.outside(moved, seeds) and "always_chase" in check_readme.outside(moved, seeds)[0]


def python_blocks() -> list[str]:
    """Every ```python block of the README, dedented (some sit in a list item)."""
    text = check_readme.ROOT.joinpath("README.md").read_text()
    blocks = re.findall(r"^( *)```python\n(.*?)^\1```", text, flags=re.S | re.M)
    return [textwrap.dedent("\n".join(line[len(indent) :] for line in body.splitlines())) for indent, body in blocks]


@pytest.mark.slow
def test_every_python_block_of_the_readme_runs_as_written_in_a_fresh_interpreter(tmp_path: Path) -> None:
    code, output = run_cli(
        "train", "--condition", "1p-high", "--episodes", "2", "--no-record", "--out", str(tmp_path / "runs" / "demo")
    )
    assert code == 0, output
    blocks = python_blocks()
    assert len(blocks) >= 2 and "pursuit_v0" in blocks[0]
    for block in blocks:
        done = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True, text=True)
        assert done.returncode == 0, f"{block}\n{done.stderr}"
