"""The budget study (issue 63, studies/budget/): its design as PROTOCOL.md states it, its build
pin, and the one mechanism its runs rest on: a run's first part by the rule study's plan, carried
on by the driver to a longer budget, equals the same run trained in one go, bit for bit."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import torch

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "studies" / "budget"


def _driver() -> Any:
    """studies/budget/run.py as a module of its own name (other studies have a ``run.py`` too)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("budget_run", STUDY / "run.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["budget_run"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


driver = _driver()
design = driver.design


def _evaluation() -> Any:
    """studies/budget/evaluate.py as a module of its own name."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("budget_evaluate", STUDY / "evaluate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


from pursuit_bench.reports import rule_study  # noqa: E402
from pursuit_bench.training import runs  # noqa: E402
from pursuit_bench.training.stack import FolderRun, train_stack  # noqa: E402


def test_the_design_is_the_protocol_s() -> None:
    protocol = (STUDY / "PROTOCOL.md").read_text()
    assert design.CONDITIONS == ("3p-low-shared", "2p-high-shared", "1p-high")
    assert len(design.PANELS) == 6 and {c for c, _ in design.PANELS} == set(design.CONDITIONS)
    assert design.KINDS == rule_study.KINDS == ("hierarchical", "flat")
    assert design.BUDGETS == (15_000, 50_000, 150_000, 500_000, 1_000_000)
    assert design.JUDGED_SEEDS == tuple(range(10))
    assert (design.EVAL_EPISODES, design.EVAL_SEED) == (rule_study.EPISODES, rule_study.EVAL_SEED)
    assert design.RULE_EPISODES == rule_study.BUDGETS[-1] and design.RULE_KEEP == rule_study.BUDGETS[:-1]
    for condition in design.CONDITIONS:  # the rule study's population, member for member
        assert design.members(condition) == rule_study.members(condition)
        rule_study.check_design({k: list(design.JUDGED_SEEDS) for k in design.KINDS}, design.members(condition))
    for needle in ("10^6", "Welch", "Holm", "±0.05", "seeds 0–9", "no seed is added", "crn-1", "80 core-hours"):
        assert needle in protocol, needle
    assert re.search(r"^Fixed on 2026-12-06", protocol, re.M)
    for verdict in ("rule helps", "flat better", "equivalent", "not resolved"):
        assert f"**{verdict}**" in protocol


def test_the_plans_are_the_rule_study_s_but_for_length_and_kept_checkpoints() -> None:
    for condition in design.CONDITIONS:
        for kind in design.KINDS:
            first = design.first_part("population", condition, kind)
            assert first.episodes == 15_000 and first.keep_checkpoints == () and first.preset == "reproduction"
            assert list(first.runs()) == [f"{condition}-{kind}-seed{s}" for s in rule_study.population_seeds(kind)]
            on = design.continuation_plan("population", condition, kind)
            assert on.episodes == 1_000_000 and on.keep_checkpoints == design.BUDGETS[:-1]
            assert list(on.runs()) == list(first.runs())
            for name, config in on.runs().items():  # nothing but the length differs, ε's and β's schedules included
                assert config.to_dict() | {"episodes": 15_000, "agent": first.runs()[name].agent.to_dict()} == (
                    first.runs()[name].to_dict()
                )
        judged = design.first_part("judged", condition, "hierarchical")
        assert judged.predators == design.KINDS and judged.keep_checkpoints == rule_study.BUDGETS[:-1]
        assert sorted(judged.runs()) == sorted(
            f"{condition}-{k}-seed{s}" for k in design.KINDS for s in design.JUDGED_SEEDS
        )
    with pytest.raises(ValueError, match="stage='pool'"):
        design.first_part("pool", "1p-high", "flat")
    with pytest.raises(ValueError, match="condition='1p-low'"):
        design.members("1p-low")


def test_the_build_is_pinned() -> None:
    pinned = json.loads((STUDY / "build.json").read_text())
    assert pinned["commit"] == design.BUILD_COMMIT
    known = subprocess.run(["git", "cat-file", "-e", pinned["commit"]], cwd=ROOT, capture_output=True)
    if known.returncode != 0:
        pytest.skip("the pinned commit is not in this clone")
    listing = subprocess.run(
        ["git", "ls-tree", "-r", pinned["commit"], "--", "pursuit_bench"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert design.fingerprints(listing) == {"code": pinned["code"], "training_code": pinned["training_code"]}
    other = listing.replace(listing.split()[2], "0" * 40, 1)  # one file changed: both prints move
    assert design.fingerprints(other)["code"] != pinned["code"]
    with pytest.raises(SystemExit, match="not the study's build: code"):
        driver.check_build(Path("/nonexistent"), {**pinned, "code": "0" * 16}, pinned)


def train_folder(folder: Path, config, settings: dict, state: dict | None = None) -> None:
    if state is None:
        folder.mkdir(parents=True)
        runs.write_config(folder, config, settings)
    with runs.locked(folder):
        train_stack([FolderRun(folder, config, settings, state)], record=False)


def agents_of(path: Path) -> dict:
    return torch.load(path, weights_only=True)["agents"]


def same(a: object, b: object, where: str = "agents", but: str = "") -> None:
    """Equal to the bit, all the way down (``but``: a path ending left out)."""
    if but and where.endswith(but):
        return
    if isinstance(a, torch.Tensor):
        assert isinstance(b, torch.Tensor) and torch.equal(a, b), where
    elif isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), where
        for key in a:
            same(a[key], b[key], f"{where}/{key}", but)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            same(x, y, f"{where}[{k}]", but)
    else:
        assert a == b, where


def test_a_first_part_carried_on_equals_the_run_trained_in_one_go(tmp_path: Path) -> None:
    """What the study's 10^6-episode runs rest on (PROTOCOL.md, "Runs"): a run trained to the
    first budget by the rule study's plan, copied by the driver and trained on, equals the run
    trained to the last budget in one go, weights, optimiser, replay and generators, and every
    metrics row (ε and β included); its first budget's checkpoint is the one-go run's there."""
    trial: dict[str, Any] = {"preset": "quick", "num_envs": 2, "checkpoint_every": 3}
    budgets = (5, 9)
    first_plan = design.first_part("population", "3p-low-shared", "flat", budgets, **trial)
    on_plan = design.continuation_plan("population", "3p-low-shared", "flat", budgets, **trial)
    name = "3p-low-shared-flat-seed1004"
    settings = {"preset": "quick", "record_every": 100, "checkpoint_every": 3, "keep_checkpoints": []}
    first = tmp_path / "first" / name
    train_folder(first, first_plan.runs()[name], settings)
    (tmp_path / "on" / "runs").mkdir(parents=True)
    driver.carry_on(first, tmp_path / "on", on_plan, name)
    carried = tmp_path / "on" / "runs" / name
    config, carried_settings = runs.read_config(carried)
    assert config == on_plan.runs()[name] and carried_settings["keep_checkpoints"] == [5]
    train_folder(carried, config, carried_settings, runs.load_checkpoint(carried))
    one_go = tmp_path / "one-go"
    train_folder(one_go, on_plan.runs()[name], {**settings, "keep_checkpoints": [5]})
    same(agents_of(carried / "checkpoint.pt"), agents_of(one_go / "checkpoint.pt"))
    # the first part's end is the one-go run's at 5 episodes; only the training length it records differs
    same(agents_of(carried / "checkpoint-ep5.pt"), agents_of(one_go / "checkpoint-ep5.pt"), but="config/episodes")
    with pytest.raises(AssertionError, match="config/episodes"):
        same(agents_of(carried / "checkpoint-ep5.pt"), agents_of(one_go / "checkpoint-ep5.pt"))
    assert (carried / "metrics.jsonl").read_text() == (one_go / "metrics.jsonl").read_text()
    with pytest.raises(SystemExit, match="not the plan's"):
        driver.carry_on(first, tmp_path / "on", design.continuation_plan("population", "1p-high", "flat"), name)


def driver_command(work: Path) -> list[str]:
    tiny = ["--preset", "quick", "--budgets", "3,150,300", "--num-envs", "2", "--checkpoint-every", "25"]
    options = ["--conditions", "3p-low-shared", "--stages", "population", "--no-population-check"]
    return [sys.executable, str(STUDY / "run.py"), "--work", str(work), *tiny, *options, "--skip-build-check"]


@pytest.mark.slow
@pytest.mark.long
def test_the_driver_stopped_by_sigterm_resumes_to_the_same_runs_and_populations(tmp_path: Path) -> None:
    """A tiny population stage: stopped by SIGTERM while it trains on (exit 143), refused while
    it runs by a second driver (its lock), then resumed by the same command; every run's final
    checkpoint and every budget's population equal those of a driver that never stopped."""
    import os
    import signal
    import time

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    whole = subprocess.run(driver_command(tmp_path / "a"), env=env, capture_output=True, text=True, timeout=600)
    assert whole.returncode == 0, whole.stderr
    process = subprocess.Popen(
        driver_command(tmp_path / "b"), env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    log = tmp_path / "b" / "progress.log"
    deadline = time.monotonic() + 300
    while "on to 300 episodes" not in (log.read_text() if log.exists() else ""):
        assert time.monotonic() < deadline and process.poll() is None, "the driver never reached its second part"
        time.sleep(0.2)
    second = subprocess.run(driver_command(tmp_path / "b"), env=env, capture_output=True, text=True, timeout=60)
    assert second.returncode == 2 and "in use" in second.stderr
    time.sleep(1.0)
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=300)
    assert process.returncode == 143, stderr
    assert "stopped: rerun the same command" in log.read_text()
    again = subprocess.run(driver_command(tmp_path / "b"), env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    for run in sorted((tmp_path / "a" / "on").glob("*/runs/*")):
        twin = tmp_path / "b" / run.relative_to(tmp_path / "a")
        same(agents_of(run / "checkpoint.pt"), agents_of(twin / "checkpoint.pt"), str(run.name))
    from pursuit_bench import pretrained

    written = sorted((tmp_path / "a" / "populations").glob("*/*/*/prey_0.safetensors"))
    assert len(written) == 3 * 8
    for path in written:
        twin = tmp_path / "b" / path.relative_to(tmp_path / "a")
        ours, theirs = pretrained.read(path)[0], pretrained.read(twin)[0]
        assert set(ours) == set(theirs) and all(torch.equal(ours[k], theirs[k]) for k in ours), path


@pytest.mark.slow
@pytest.mark.long
def test_a_new_machine_trains_only_the_members_not_stored(tmp_path: Path) -> None:
    """A new machine (a work folder of its own) given the populations an earlier one stored, less
    one member: it trains on only that member's run, and stores it and writes each budget's
    population as the earlier machine did (the same tensors and header; population.json to the
    byte)."""
    from pursuit_bench import pretrained

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    first = subprocess.run(driver_command(tmp_path / "a"), env=env, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    shutil.copytree(tmp_path / "a" / "populations", tmp_path / "b" / "populations")
    for folder in (tmp_path / "b" / "populations").glob("*/3p-low-shared"):
        shutil.rmtree(folder / "flat-seed1006")
        (folder / "population.json").unlink()
    command = [*driver_command(tmp_path / "b"), "--populations", str(tmp_path / "b" / "populations")]
    again = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert [p.name for p in (tmp_path / "b" / "on").glob("*/runs/*")] == ["3p-low-shared-flat-seed1006"]
    assert (
        "population-hierarchical-3p-low-shared: every run's outcome is kept: not trained again"
        in (tmp_path / "b" / "progress.log").read_text()
    )
    written = sorted((tmp_path / "a" / "populations").rglob("*.*"))
    assert len(written) == 3 * 9
    for path in written:
        twin = tmp_path / "b" / path.relative_to(tmp_path / "a")
        if path.name == "population.json":
            assert twin.read_bytes() == path.read_bytes(), path
            continue
        (ours, header), (theirs, their_header) = pretrained.read(path), pretrained.read(twin)
        assert header == their_header, path  # safetensors orders its header's keys as it likes
        assert set(ours) == set(theirs) and all(torch.equal(ours[k], theirs[k]) for k in ours), path


@pytest.mark.slow
@pytest.mark.long
def test_the_judged_stage_evaluates_each_run_as_it_ends_and_a_new_machine_trains_only_the_rest(
    tmp_path: Path,
) -> None:
    """A tiny study of one condition, both stages (6 judged seeds a kind): every judged run's
    compact result holds its evaluations at every budget against the same-budget population and
    at the later ones against the first budget's, and the paper's comparison at the last; a new
    machine given the populations and all results but one trains only that run, its first part
    included, and writes the same result."""
    import gzip

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    judged = ["--stages", "population,judged", "--judged-seeds", "6", "--eval-episodes", "3", "--no-replay-check"]
    a = tmp_path / "a"  # two workers: chunks of two runs stacked, then one run alone on the new machine
    first = subprocess.run(
        [*driver_command(a), *judged, "--workers", "2"], env=env, capture_output=True, text=True, timeout=1200
    )
    assert first.returncode == 0, first.stderr
    results = sorted((a / "results").glob("*.json.gz"))
    assert [p.name for p in results] == sorted(
        f"3p-low-shared-{kind}-seed{seed}.json.gz" for kind in design.KINDS for seed in range(6)
    )
    members = [m["name"] for m in design.members("3p-low-shared")]

    def read(path: Path) -> dict[str, Any]:
        return json.loads(gzip.decompress(path.read_bytes()))

    for path in results:
        result = read(path)
        assert result["format"] == "budget-study-run-1" and result["budgets"] == [3, 150, 300]
        assert list(result["same_budget"]) == ["3", "150", "300"] and list(result["first_population"]) == ["150", "300"]
        for evaluations in [*result["same_budget"].values(), *result["first_population"].values()]:
            assert list(evaluations) == members
            assert all(set(e) == {"panels", "stderr", "capture_rate", "prey"} for e in evaluations.values())
        assert list(result["paper"]["panels"]) == ["predator_0", "predator_1", "predator_2"]
    b = tmp_path / "b"
    shutil.copytree(a / "populations", b / "populations")
    shutil.copytree(a / "results", b / "results")
    (b / "results" / "3p-low-shared-flat-seed3.json.gz").unlink()
    command = [*driver_command(b), *judged, "--populations", str(b / "populations")]
    again = subprocess.run(command, env=env, capture_output=True, text=True, timeout=1200)
    assert again.returncode == 0, again.stderr
    assert [p.name for p in (b / "on").glob("*/runs/*")] == ["3p-low-shared-flat-seed3"]
    assert [p.name for p in (b / "first").glob("*/runs/*")] == ["3p-low-shared-flat-seed3"]  # not both kinds' 12
    ours, theirs = (
        read(a / "results" / "3p-low-shared-flat-seed3.json.gz"),
        read(b / "results" / "3p-low-shared-flat-seed3.json.gz"),
    )
    assert ours == theirs


@pytest.mark.slow
@pytest.mark.long
def test_paper_first_plays_each_judged_run_s_first_part_and_a_new_machine_plays_only_the_rest(tmp_path: Path) -> None:
    """``--paper-first`` (PLAN.md, "Fig. 2 at 15,000 episodes"): every judged seed's first part of
    one kind is trained and played by the paper's protocol at its end, nothing past it; a new
    machine given all results but one trains only that run and writes the same result."""
    import gzip

    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    options = ["--paper-first", "--kinds", "flat", "--eval-episodes", "3", "--no-replay-check"]

    def read(path: Path) -> dict[str, Any]:
        return json.loads(gzip.decompress(path.read_bytes()))

    a = tmp_path / "a"
    first = subprocess.run([*driver_command(a), *options], env=env, capture_output=True, text=True, timeout=1200)
    assert first.returncode == 0, first.stderr
    names = sorted(f"3p-low-shared-flat-seed{s}.json.gz" for s in design.JUDGED_SEEDS)
    assert sorted(p.name for p in (a / "results").glob("*.json.gz")) == names
    for path in (a / "results").glob("*.json.gz"):
        result = read(path)
        assert result["format"] == "budget-study-paper-1" and result["budget"] == 3 and result["kind"] == "flat"
        assert result["eval_seed"] == 12345 and result["same_as_judged"] is False  # --no-replay-check: unchecked
        assert list(result["paper"]["panels"]) == ["predator_0", "predator_1", "predator_2"]
        assert result["paper"]["episodes"] == 3
    assert not (a / "on").exists()  # first parts only: nothing trained on
    b = tmp_path / "b"
    shutil.copytree(a / "results", b / "results")
    (b / "results" / "3p-low-shared-flat-seed4.json.gz").unlink()
    again = subprocess.run([*driver_command(b), *options], env=env, capture_output=True, text=True, timeout=1200)
    assert again.returncode == 0, again.stderr
    assert [p.name for p in (b / "first").glob("*/runs/*")] == ["3p-low-shared-flat-seed4"]
    name = "3p-low-shared-flat-seed4.json.gz"
    assert read(a / "results" / name) == read(b / "results" / name)
    refused = subprocess.run(
        [sys.executable, str(STUDY / "run.py"), "--paper-first"], env=env, capture_output=True, text=True, timeout=120
    )
    assert refused.returncode == 2 and "another --work" in refused.stderr, refused.stderr


def test_the_replay_check_passes_the_rule_study_s_result_only_to_the_bit(tmp_path: Path, monkeypatch) -> None:
    import argparse
    import gzip

    played: dict[str, Any] = {
        "protocol": "crn-1",
        "episodes": 60,
        "eval_seed": 12345,
        "pool": {"15000": {"FleeingPrey": {"panels": {"predator_0": [0.5, 0.25, 0.125]}, "capture_rate": 0.5}}},
    }
    committed = {**played, "pool": {**played["pool"], "1500": {}}, "name": "1p-high-flat-seed3"}
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "1p-high-flat-seed3.json.gz").write_bytes(gzip.compress(json.dumps(committed).encode()))
    monkeypatch.setattr(rule_study, "evaluate_run", lambda run, population, budgets: json.loads(json.dumps(played)))
    args = argparse.Namespace(
        work=tmp_path, budgets=design.BUDGETS, rule_results=tmp_path / "results", rule_population=tmp_path
    )
    driver.replay_check(args, "1p-high", tmp_path / "1p-high-flat-seed3")
    assert json.loads((tmp_path / "replay" / "1p-high-flat-seed3.json").read_text())["equal"] is True
    played["pool"]["15000"]["FleeingPrey"]["panels"]["predator_0"][2] += 2**-40  # one variant, the last bits
    with pytest.raises(SystemExit, match="not the rule study's run"):
        driver.replay_check(args, "1p-high", tmp_path / "1p-high-flat-seed3")
    with pytest.raises(SystemExit, match="no committed rule-study result"):
        driver.replay_check(args, "1p-high", tmp_path / "1p-high-flat-seed4")


def test_a_first_part_must_end_at_the_first_budget_and_equal_the_judged_run_there(tmp_path: Path, monkeypatch) -> None:
    """``evaluate.py --first-part``'s checks: the run's checkpoint at the first budget, and its
    play against that budget's population equal, to the bit, to the judged run's committed
    ``same_budget`` there (none committed: nothing to check, said so)."""
    import gzip

    evaluation = _evaluation()
    played = {"FleeingPrey": {"panels": {"predator_0": [0.5, 0.25, 0.125]}, "capture_rate": 0.5}}
    seen: list[tuple[str, int, int]] = []

    def evaluate_checkpoint(run, checkpoint, folder, episodes, seed, outcomes):  # type: ignore[no-untyped-def]
        seen.append((checkpoint, episodes, seed))
        assert folder == tmp_path / "budget-study-ep15000" / "1p-high" and outcomes
        return json.loads(json.dumps(played))

    monkeypatch.setattr(rule_study, "evaluate_checkpoint", evaluate_checkpoint)
    judged = tmp_path / "judged"
    judged.mkdir()
    committed = {"same_budget": {"15000": json.loads(json.dumps(played)), "50000": {}}}
    (judged / "1p-high-flat-seed3.json.gz").write_bytes(gzip.compress(json.dumps(committed).encode()))
    run = tmp_path / "1p-high-flat-seed3"
    assert evaluation.same_as_judged(run, "1p-high", tmp_path, judged, 15_000, 60)
    assert seen == [(runs.CHECKPOINT, 60, 12345)]  # the first part's last checkpoint, by the protocol
    assert not evaluation.same_as_judged(tmp_path / "1p-high-flat-seed4", "1p-high", tmp_path, judged, 15_000, 60)
    played["FleeingPrey"]["panels"]["predator_0"][1] += 2**-40
    with pytest.raises(SystemExit, match="differs from the budget study's judged run at 15000 episodes"):
        evaluation.same_as_judged(run, "1p-high", tmp_path, judged, 15_000, 60)
    monkeypatch.setattr(runs, "load_checkpoint", lambda folder: {"episodes_done": 15_000})
    evaluation.first_part_episodes(run, 15_000)
    with pytest.raises(SystemExit, match="holds 15000 episodes, not the first part's 50000"):
        evaluation.first_part_episodes(run, 50_000)


def test_only_the_protocol_s_cut_shortens_the_judged_runs() -> None:
    assert len(design.continuation_plan("judged", "1p-high", "both").runs()) == 20
    cut = design.continuation_plan("judged", "1p-high", "both", judged_seeds=6)
    assert sorted(cut.runs()) == sorted(f"1p-high-{k}-seed{s}" for k in design.KINDS for s in range(6))
    for wrong in (5, 11):
        with pytest.raises(ValueError, match="expected 6 to 10"):
            design.continuation_plan("judged", "1p-high", "both", judged_seeds=wrong)


@pytest.mark.parametrize("kinds", ["flat,flat", "prey", "hierarchical,"])
def test_the_driver_refuses_kinds_not_of_the_study_in_one_line(tmp_path: Path, kinds: str) -> None:
    command = [sys.executable, str(STUDY / "run.py"), "--work", str(tmp_path), "--kinds", kinds, "--skip-build-check"]
    refused = subprocess.run(command, env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True)
    assert refused.returncode == 2 and refused.stderr.count("\n") == 1 and "--kinds" in refused.stderr
    assert not (tmp_path / "progress.log").exists()


def test_judged_runs_go_in_chunks_of_consecutive_seeds_at_most_the_workers_long() -> None:
    assert driver.consecutive([0, 1, 2, 3, 4], 2) == [[0, 1], [2, 3], [4]]
    assert driver.consecutive([0, 2, 3, 7, 8, 9], 3) == [[0], [2, 3], [7, 8, 9]]
    assert driver.consecutive([5], 1) == [[5]] and driver.consecutive([], 4) == []
