"""The rule study's design (issue 47): the population is disjoint from the judged runs and holds no
twins, members round-trip through the population format, and the seed rule adds seeds where a
condition's runs split and nowhere else."""

import gzip
import json
from pathlib import Path

import numpy as np
import pytest

from pursuit_bench import pretrained
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.reports import rule_study
from pursuit_bench.training.train_config import TrainConfig

ROOT = Path(__file__).resolve().parents[1]


def test_the_population_is_disjoint_from_the_judged_runs_and_holds_no_twins() -> None:
    for condition in CONDITIONS:
        members = rule_study.members(condition)
        seeds = [m["seed"] for m in members if m["seed"] is not None]
        assert len(seeds) == 2 * rule_study.POPULATION_RUNS and len(set(seeds)) == len(seeds)
        assert min(seeds) >= rule_study.POPULATION_FIRST_SEED
        assert {m["kind"] for m in members} == {"scripted", "hierarchical", "flat"}
        # every judged seed the seed rule can ask for
        rule_study.check_design({k: list(range(rule_study.MOST_RUNS)) for k in rule_study.KINDS}, members)
    twins = [*rule_study.members("1p-high"), {"name": "again", "kind": "flat", "policy": None, "seed": 1000}]
    with pytest.raises(ValueError, match="repeat"):
        rule_study.check_design({}, twins)
    with pytest.raises(ValueError, match="outside 0–999"):  # a judged seed in the population's range
        rule_study.check_design({"flat": [3, 1001]}, rule_study.members("1p-high"))
    low = [{"name": "x", "kind": "flat", "policy": None, "seed": 7}]
    with pytest.raises(ValueError, match="below 1000"):
        rule_study.check_design({}, low)


def test_the_committed_populations_follow_the_design() -> None:
    """The population the study committed, in every one of the ten conditions: the members the
    design names, each file's header saying the seed, kind and condition it claims; no two members
    with the same weights."""
    where = ROOT / "pursuit_bench" / "pretrained" / "populations" / rule_study.POPULATION
    for condition in CONDITIONS:
        folder = where / condition
        assert (folder / "population.json").is_file(), f"no population in {condition}"
        members = rule_study.read_population(folder)
        assert len(members) == 9, condition
        seen: list[np.ndarray] = []
        for member in members:
            if member["policy"] is not None:
                continue
            weights, header = pretrained.read(folder / member["files"]["prey_0"])
            assert (header["condition"], header["seed"]) == (folder.name, str(member["seed"]))
            flat = np.concatenate([w.numpy().ravel() for w in weights.values()])
            assert not any(np.array_equal(flat, other) for other in seen), member["name"]
            seen.append(flat)


def test_a_member_round_trips_through_the_population_format(tmp_path: Path) -> None:
    agents = pretrained.load("1p-low")
    config = pretrained.training_config("1p-low")
    prey = {
        m["name"]: (agents["prey_0"], TrainConfig.from_dict({**config.to_dict(), "seed": m["seed"]}))
        for m in rule_study.members("1p-low")
        if m["policy"] is None
    }
    trained = {
        name: {"preset": "reproduction", "episodes": 15000, "predator_kind": "x", "build": "abc"} for name in prey
    }
    path = rule_study.write_population(tmp_path, "1p-low", prey, trained)
    document = json.loads(path.read_text())
    assert document["population"] == "rule-study" and document["role"] == "prey"
    assert document["members"][0] == {
        "name": "FleeingPrey", "kind": "scripted", "policy": "FleeingPrey", "seed": None, "trained": None, "files": {},
    }  # fmt: skip
    member = document["members"][1]
    assert (
        member["files"] == {"prey_0": "hierarchical-seed1000/prey_0.safetensors"}
        and member["trained"]["build"] == "abc"
    )
    loaded = rule_study.load_member(tmp_path / "1p-low" / member["files"]["prey_0"])
    obs = np.random.default_rng(0).normal(size=(5, agents["prey_0"].learner.n_obs)).astype(np.float32)
    assert np.array_equal(loaded.act_batch(obs), agents["prey_0"].act_batch(obs))
    assert [m["name"] for m in rule_study.read_population(tmp_path / "1p-low")] == [
        m["name"] for m in rule_study.members("1p-low")
    ]


def test_a_population_that_would_not_read_back_is_not_written(tmp_path: Path) -> None:
    from pursuit_bench.benchmark import populations

    fleeing = {"name": "FleeingPrey", "kind": "scripted", "policy": "FleeingPrey", "seed": None, "trained": None}
    where = tmp_path / "p" / "1p-low"
    where.mkdir(parents=True)
    index = populations.write_index(where, "p", "1p-low", "prey", [{**fleeing, "files": {}}])
    before = index.read_bytes()
    assert populations.read(where, "p", "1p-low").members[0].policy == "FleeingPrey"
    for members, message in (
        ([], "at least one member"),
        ([{**fleeing, "files": {}}, {**fleeing, "files": {}}], "each named once"),
        ([{**fleeing, "kind": "learned", "files": {}}], "a kind among"),
    ):
        with pytest.raises(ValueError, match=message):
            populations.write_index(where, "p", "1p-low", "prey", members)
        assert index.read_bytes() == before
    with pytest.raises(ValueError, match="of condition '9p-low'"):
        populations.write_index(where, "p", "9p-low", "prey", [{**fleeing, "files": {}}])


def test_the_kinds_names_are_the_classes_own() -> None:
    from pursuit_bench.agents import names
    from pursuit_bench.agents.kinds import FlatPredator, HierarchicalPredator, Prey
    from pursuit_bench.agents.residual import ResidualPredator
    from pursuit_bench.rules.policies import FleeingPrey

    assert (HierarchicalPredator.kind, FlatPredator.kind, ResidualPredator.kind, Prey.kind) == (
        names.HIERARCHICAL, names.FLAT, names.RESIDUAL, names.PREY,
    )  # fmt: skip
    assert names.FLEEING == FleeingPrey.__name__ == rule_study.FLEEING


def fake_run(kind: str, seed: int, margin: float, budget: int = 15000) -> dict:
    """A judged run of 1p-high whose pool margin at the last budget is ``margin`` (always-stalk
    at 0, always-chase below, the trained predator at ``margin``) against every member."""
    evaluation = {"panels": {"predator_0": [margin, -0.5, 0.0]}, "stderr": {"predator_0": 0.01}, "capture_rate": 0.5}
    return {
        "kind": kind,
        "seed": seed,
        "condition": "1p-high",
        "pool": {str(budget): {m: evaluation for m in ("FleeingPrey", "a")}},
    }


def test_the_seed_rule_adds_seeds_to_a_split_and_nowhere_else() -> None:
    ok = [fake_run(k, s, 0.1) for k in rule_study.KINDS for s in range(10)]
    assert rule_study.seeds_wanted([]) == 10
    assert rule_study.seeds_wanted(ok[:15]) == 10  # not all in yet
    assert rule_study.seeds_wanted(ok) == 10
    near = [*ok[:-1], fake_run("flat", 9, -0.04)]  # below 0 but within the failure margin: not a failure
    assert rule_study.seeds_wanted(near) == 10
    split = [*ok[:-1], fake_run("flat", 9, -0.2)]
    assert rule_study.seeds_wanted(split) == 20
    more = split + [fake_run(k, s, 0.1) for k in rule_study.KINDS for s in range(10, 20)]
    assert rule_study.seeds_wanted(more) == 30  # the failure is still among the first 20
    most = more + [fake_run(k, s, -0.3) for k in rule_study.KINDS for s in range(20, 30)]
    assert rule_study.seeds_wanted(most) == 30


def test_a_margin_on_the_line_but_for_its_last_bits_does_not_fail() -> None:
    def run(trained: list[float], stalk: list[float]) -> dict:
        members = {
            f"m{i}": {"panels": {"predator_0": [t, -1.0, s]}}
            for i, (t, s) in enumerate(zip(trained, stalk, strict=True))
        }
        return {"pool": {"15000": members}}

    tied = run([0.3, 0.2, 0.1], [0.2, 0.2, 0.2])  # equal means in exact arithmetic
    assert rule_study.pooled(tied["pool"]["15000"], "predator_0")["margin"] != 0.0  # but not in floats
    assert not rule_study.failed(tied, "predator_0", 0.0)
    assert rule_study.failed(run([0.3, 0.2, 0.1], [0.2, 0.2, 0.21]), "predator_0", 0.0)


def test_conditions_run_cheapest_first() -> None:
    ordered = rule_study.order()
    assert sorted(ordered) == sorted(CONDITIONS) and ordered[0].endswith("low") and ordered[-1] == "1p-high"


def test_a_run_s_compact_result_keeps_its_own_seed(tmp_path: Path) -> None:
    evaluation = {"protocol": "crn-1", "episodes": 60, "eval_seed": 12345, "seed": 12345, "pool": {}}
    rule_study.write_run(tmp_path, "1p-high-flat-seed3", "1p-high", "flat", 3, "abc", evaluation)
    (run,) = rule_study.read_runs(tmp_path)
    assert (run["seed"], run["kind"], run["build"], run["eval_seed"]) == (3, "flat", "abc", 12345)
    (tmp_path / "other.json.gz").write_bytes(gzip.compress(b'{"format": "x"}'))
    with pytest.raises(ValueError, match="not a rule-study run"):
        rule_study.read_runs(tmp_path)


QUICK = ["--preset", "quick", "--episodes", "4", "--budgets", "2,4", "--eval-episodes", "1", "--num-envs", "2"]
"""Tiny options: were the driver to train anything in the tests below, it would be brief."""


@pytest.mark.slow
def test_on_a_new_machine_the_driver_trains_nothing_the_committed_files_hold(tmp_path: Path) -> None:
    """A new machine keeps the committed population and compact results, not the run folders: the
    driver resumes from them without training a population or a judged run again (1p-low is done)."""
    import shutil
    import subprocess
    import sys

    results, population = tmp_path / "results", tmp_path / "population"
    (results / "runs").mkdir(parents=True)
    for path in (ROOT / "results" / "rule-study" / "runs").glob("1p-low-*.json.gz"):
        shutil.copy(path, results / "runs" / path.name)
    shutil.copytree(
        ROOT / "pursuit_bench" / "pretrained" / "populations" / "rule-study" / "1p-low", population / "1p-low"
    )
    wanted = rule_study.seeds_wanted(rule_study.read_runs(results / "runs"))
    command = [sys.executable, str(ROOT / "studies" / "rule-value" / "run.py"), "--workers", "1"]
    command += ["--conditions", "1p-low", f"--work={tmp_path / 'work'}", f"--results={results}"]
    command += [f"--population={population}", "--skip-build-check", *QUICK]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"1p-low: {wanted} judged runs a kind, done" in done.stdout and "judged seeds" not in done.stdout
    trained = [p.name for p in (tmp_path / "work").iterdir() if p.is_dir()]
    assert trained == [], f"trained again on a new machine: {trained}"


@pytest.mark.slow
def test_a_second_driver_on_the_same_work_folder_refuses_at_once(tmp_path: Path) -> None:
    """Two drivers on one study would train the same runs side by side: the second one, started
    while the first holds the work folder, says so in one line, exits 2 and writes nothing."""
    import subprocess
    import sys

    from pursuit_bench.io.files import locked

    work = tmp_path / "work"
    work.mkdir()
    command = [sys.executable, str(ROOT / "studies" / "rule-value" / "run.py"), "--workers", "1", "--conditions"]
    command += ["1p-low", f"--work={work}", f"--results={tmp_path / 'results'}", "--skip-build-check", *QUICK]
    with locked(work):  # as a running driver holds it
        refused = subprocess.run(command, capture_output=True, text=True, timeout=120)
        written = sorted(p.name for p in work.iterdir())  # the holder's lock only (it removes it as it leaves)
    assert refused.returncode == 2 and "in use by another pursuit-bench process" in refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1
    assert written == [".lock"] and not (tmp_path / "results").exists()
