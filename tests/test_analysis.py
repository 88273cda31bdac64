"""`pursuit-bench analyze`: the value stream's embedding and when predators chase."""

import json
from pathlib import Path

import numpy as np
import pytest
import rerun.chunk as rc
from cli_helpers import run_cli

from pursuit_bench.analysis.behaviour import DISTANCE_BINS, chase_by_distance, embed, onset_summary, organisation

TINY = ["--episodes", "12", "--num-envs", "4", "--learning-starts", "32", "--batch-size", "16", "--no-record"]


@pytest.mark.slow
def test_analyze_a_run_writes_four_files_that_agree_with_its_states(tmp_path: Path) -> None:
    out = tmp_path / "run"
    code, output = run_cli("train", "--condition", "2p-high-individual", "--out", str(out), *TINY)
    assert code == 0, output
    code, output = run_cli("analyze", str(out), "--episodes", "12", "--seed", "3")
    assert code == 0 and "organisation by distance" in output, output
    for name in ("fig3.png", "modes.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and (out / name).stat().st_size > 10_000
    result = json.loads((out / "analysis.json").read_text())
    assert result["episodes"] == 12 and set(result["predators"]) == {"predator_0", "predator_1"}
    for predator in result["predators"].values():
        distance, mode = np.array(predator["distance"]), np.array(predator["mode"])
        assert len(distance) == len(mode) == predator["states"] > 0
        table = predator["chase_by_distance"]
        assert sum(table["states"]) == predator["states"] and table["bins"] == DISTANCE_BINS.tolist()
        for lo, hi, p, n in zip(table["bins"], table["bins"][1:], table["p_chase"], table["states"], strict=False):
            inside = (distance >= lo) & (distance < hi) if hi < table["bins"][-1] else distance >= lo
            assert n == inside.sum()
            assert p is None if n == 0 else abs(p - mode[inside].mean()) < 1e-9
        assert predator["p_chase"] == mode.mean()
        assert len(predator["embedding"]["xy"]) == predator["embedded"] == min(predator["states"], 2000)
    chunks = list(rc.RrdReader(out / "analysis.rrd").store().stream())
    paths = {str(c.entity_path) for c in chunks}
    assert {"/embedding/states", "/embedding/current", "/arena/agents/predator_0", "/arena/agents/prey_0"} <= paths


@pytest.mark.slow
@pytest.mark.long
def test_the_organisation_score_sees_structure_and_not_its_absence() -> None:
    rng = np.random.default_rng(0)
    distance = rng.uniform(0.1, 2.0, 600)
    directions = rng.normal(size=(32,))
    features = np.outer(np.sin(2 * distance), directions) + np.outer(distance, directions[::-1])
    features += rng.normal(scale=0.05, size=features.shape)  # a noisy function of distance
    embedding = embed(features, seed=0)
    assert organisation(embedding, distance) > 0.8
    assert organisation(embedding, rng.permutation(distance)) < 0.2
    noise = embed(rng.normal(size=(600, 32)), seed=0)  # features that know nothing of distance
    assert organisation(noise, distance) < 0.2


def test_chase_tables_by_hand() -> None:
    table = chase_by_distance(np.array([0.05, 0.05, 0.15, 1.95, 3.0]), np.array([1, 0, 1, 0, 1]))
    assert table["states"][:2] == [2, 1] and table["states"][-1] == 2 and table["p_chase"][:2] == [0.5, 1.0]
    assert table["p_chase"][-1] == 0.5 and table["p_chase"][2] is None
    summary = onset_summary(np.array([0.2, 0.4, 0.6, 0.8]))
    assert summary["bouts"] == 4 and summary["median"] == pytest.approx(0.5)
    assert summary["quartiles"] == pytest.approx([0.35, 0.65])
    assert onset_summary(np.array([]))["median"] is None


def test_analyze_refuses_what_it_cannot_analyse(tmp_path: Path) -> None:
    code, output = run_cli("analyze", str(tmp_path / "nowhere"))
    assert code == 2 and "no such run folder" in output
    out = tmp_path / "stalker"
    code, output = run_cli("train", "--condition", "1p-low", "--predator", "always_stalk", "--out", str(out), *TINY)
    assert code == 0, output
    code, output = run_cli("analyze", str(out), "--episodes", "2")
    assert code == 2 and "not hierarchical" in output
