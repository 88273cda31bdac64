"""Trained agents in files: export and load round trip, refusals, the median seed, the CLI."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from cli_helpers import run_cli

from pursuit_bench import pretrained
from pursuit_bench.training import runs

TINY = ["--num-envs", "4", "--learning-starts", "32", "--batch-size", "16", "--checkpoint-every", "5"]


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny trained 2-predator run with the wall features (a non-default observation)."""
    out = tmp_path_factory.mktemp("pretrained") / "run"
    args = ["train", "--condition", "2p-low-individual", "--out", str(out), "--episodes", "8", "--seed", "3"]
    code, output = run_cli(*args, *TINY, "--wall-features", "--no-record")
    assert code == 0, output
    return out


def export(run: Path, dest: Path) -> list[Path]:
    config, _ = runs.read_config(run)
    agents = runs.load_agents(run)
    return pretrained.export(agents, config, dest, trained_episodes=8, provenance={"sweep_command": "by a test"})


def test_exported_agents_load_with_the_same_weights_and_act_alike(trained: Path, tmp_path: Path) -> None:
    written = export(trained, tmp_path)
    assert sorted(p.name for p in written) == [f"{n}.safetensors" for n in ("predator_0", "predator_1", "prey_0")]
    ours = runs.load_agents(trained)
    loaded = pretrained.load("2p-low-individual", folder=tmp_path)
    assert list(loaded) == list(ours)
    obs = np.random.default_rng(0).normal(size=(16, ours["prey_0"].learner.n_obs)).astype(np.float32)
    for name, agent in ours.items():
        theirs = loaded[name]
        for key, tensor in agent.learner.member_weights(agent.member).items():  # type: ignore[union-attr]
            assert torch.equal(tensor, theirs.learner.member_weights(theirs.member)[key])  # type: ignore[union-attr]
        assert np.array_equal(agent.act_batch(obs), theirs.act_batch(obs))
    assert pretrained.training_config("2p-low-individual", folder=tmp_path) == runs.read_config(trained)[0]


def test_each_file_says_how_it_was_trained(trained: Path, tmp_path: Path) -> None:
    export(trained, tmp_path)
    headers = pretrained.info("2p-low-individual", folder=tmp_path)
    header = headers["predator_1"]
    assert header["agent"] == "predator_1" and header["kind"] == "hierarchical"
    assert header["seed"] == 3 and header["trained_episodes"] == 8  # numbers, not strings
    assert header["sweep_command"] == "by a test" and header["version"]
    assert header["training"]["agent"]["wall_features"] is True
    # the header is plain JSON at the start of the file: readable without this package
    raw = (tmp_path / "2p-low-individual" / "predator_1.safetensors").read_bytes()
    size = int.from_bytes(raw[:8], "little")
    assert json.loads(raw[8 : 8 + size])["__metadata__"]["condition"] == "2p-low-individual"


def test_a_foreign_or_corrupt_file_is_a_clear_error(trained: Path, tmp_path: Path) -> None:
    export(trained, tmp_path)
    folder = tmp_path / "2p-low-individual"
    shutil.copy(folder / "prey_0.safetensors", folder / "predator_0.safetensors")
    with pytest.raises(ValueError, match=r"holds the prey agent 'prey_0'.*not the hierarchical agent 'predator_0'"):
        pretrained.load("2p-low-individual", folder=tmp_path)
    torch.save({"weights": torch.zeros(3)}, folder / "predator_0.safetensors")  # a pickle in disguise
    with pytest.raises(ValueError, match="not a readable safetensors file"):
        pretrained.load("2p-low-individual", folder=tmp_path)
    with pytest.raises(ValueError, match="no trained agents for condition '1p-high': expected one of 2p-low-indiv"):
        pretrained.load("1p-high", folder=tmp_path)


def test_the_median_seed_is_chosen_not_the_best() -> None:
    scores = {Path(f"seed{i}"): value for i, value in enumerate([0.5, -0.1, 0.9, 0.2, 0.3])}
    assert pretrained.median_seed(scores) == Path("seed4")
    del scores[Path("seed2")]
    assert pretrained.median_seed(scores) == Path("seed3")  # the lower of the middle two
    with pytest.raises(ValueError, match="no runs to choose from"):
        pretrained.median_seed({})


def test_eval_and_analyze_take_exported_agents(trained: Path, tmp_path: Path, monkeypatch) -> None:
    export(trained, tmp_path / "shipped")
    monkeypatch.setattr(pretrained, "FOLDER", tmp_path / "shipped")
    out = tmp_path / "out"
    code, output = run_cli("eval", "--pretrained", "2p-low-individual", "--out", str(out), "--episodes", "8")
    assert code == 0, output
    result = json.loads((out / "eval.json").read_text())
    assert result["pretrained"]["sweep_command"] == "by a test" and result["trained_episodes"] == 8
    assert result["training"] == runs.read_config(trained)[0].to_dict()
    assert (out / "eval.rrd").exists() and (out / "eval.png").exists()
    code, output = run_cli("analyze", "--pretrained", "2p-low-individual", "--out", str(out), "--episodes", "3")
    assert code == 0, output
    assert {"fig3.png", "modes.png", "analysis.json", "analysis.rrd"} <= {p.name for p in out.iterdir()}


def test_eval_needs_a_run_or_pretrained_not_both(trained: Path, tmp_path: Path) -> None:
    code, output = run_cli("eval", str(trained), "--pretrained", "1p-low")
    assert code == 2 and "give a RUN folder or --pretrained CONDITION" in output
    code, output = run_cli("analyze")
    assert code == 2 and "give a RUN folder or --pretrained CONDITION" in output
    code, output = run_cli("eval", str(trained), "--out", str(tmp_path))
    assert code == 2 and "--out goes with --pretrained" in output
    code, output = run_cli("eval", "--pretrained", "1p-low", "--out", str(trained))
    assert code == 2 and "holds a training run" in output
    code, output = run_cli("eval", "--pretrained", "9p-high")
    assert code == 2 and "'9p-high' is not one of" in output
