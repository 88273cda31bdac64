"""The residual study's design and driver (issue 48; docs/residual.md, "Protocol of the residual
study"): the population is disjoint from the judged runs and holds no twins, the plan lists what
the protocol says, the seed rule reads all three kinds, the driver runs only on a build whose
training code is the rule study's and, once pinned, only on that build, and a tiny run of the driver
reuses a rule study's runs (one of them trained again, exactly) and writes every compact result."""

import ast
import gzip
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from cli_helpers import load_script

from pursuit_bench import pretrained
from pursuit_bench.reports import rule_study

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "studies" / "residual-value"


def _study_module(name: str) -> ModuleType:
    """studies/residual-value/NAME.py, loaded as a module (the study's scripts are not a package)."""
    spec = importlib.util.spec_from_file_location(f"residual_{name}", STUDY / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


design = _study_module("design")


def test_the_population_is_disjoint_from_the_judged_runs_and_holds_no_twins() -> None:
    everyone = []
    for setting in design.SETTINGS:
        members = design.members(setting)
        seeds = [m["seed"] for m in members if m["seed"] is not None]
        assert len(seeds) == 12 and len(set(seeds)) == 12 and min(seeds) >= 1000
        assert [m["name"] for m in members[:9]] == [m["name"] for m in rule_study.members(design.condition_of(setting))]
        assert {m["kind"] for m in members} == {"scripted", "hierarchical", "flat", "residual"}
        design.check_design({k: list(range(design.MOST_RUNS)) for k in design.KINDS}, members)
        everyone.append(sorted(seeds))
    assert design.population_seeds("residual") == range(1008, 1012)
    assert all(s == list(range(1000, 1012)) for s in everyone)
    with pytest.raises(ValueError, match="outside 0–999"):  # a judged residual run on a member's seed
        design.check_design({"residual": [0, 1009]}, design.members("1p-high"))
    twin = [*design.members("1p-high"), {"name": "again", "kind": "residual", "policy": None, "seed": 1004}]
    with pytest.raises(ValueError, match="repeat"):
        design.check_design({}, twin)


def test_the_committed_populations_follow_the_design() -> None:
    """Every setting's committed population: the members the design names; the
    rule study's members of a plain setting byte for byte the rule study's files; every learned
    member's header saying its seed, condition, obstacles and kind; no two members with the same
    weights."""
    populations = ROOT / "pursuit_bench" / "pretrained" / "populations"
    for setting in design.SETTINGS:
        folder = populations / design.population_name(setting) / design.condition_of(setting)
        document = json.loads((folder / "population.json").read_text())  # all six are committed
        assert (document["condition"], document["obstacles"]) == (
            design.condition_of(setting),
            design.obstacles_of(setting),
        )
        members = document["members"]
        assert [m["name"] for m in members] == [m["name"] for m in design.members(setting)], setting
        seen: list[np.ndarray] = []
        for member in members:
            if member["policy"] is not None:
                continue
            path = folder / member["files"]["prey_0"]
            weights, header = pretrained.read(path)
            training = json.loads(header["training"])
            assert (header["condition"], header["seed"]) == (design.condition_of(setting), str(member["seed"]))
            assert (training["obstacles"], training["predator"]) == (design.obstacles_of(setting), member["kind"])
            if design.plain(setting) and member["kind"] != "residual":
                rule = populations / rule_study.POPULATION / folder.name / path.relative_to(folder)
                assert path.read_bytes() == rule.read_bytes(), (setting, member["name"])
            flat = np.concatenate([w.numpy().ravel() for w in weights.values()])
            assert not any(np.array_equal(flat, other) for other in seen), (setting, member["name"])
            seen.append(flat)


def test_the_plan_lists_what_the_protocol_says() -> None:
    plan = {row["setting"]: row for row in design.plan()}
    assert set(plan) == {
        "1p-high",
        "2p-high-individual",
        "3p-low-individual",
        "3p-high-shared",
        "1p-high-obstacles4",
        "2p-high-individual-obstacles4",
    }
    for setting, row in plan.items():
        obstacles = setting.endswith("obstacles4")
        assert row["obstacles"] == (4 if obstacles else 0)
        assert row["budgets"] == [1500, 5000, 10500, 12750, 15000]
        assert row["comparisons"] == [["residual", "hierarchical"], ["residual", "flat"]]
        assert row["judged_trained_here"] == (["hierarchical", "flat", "residual"] if obstacles else ["residual"])
        assert row["judged_reused"] == ([] if obstacles else ["hierarchical", "flat"])
        assert row["population_trained_here"] == row["judged_trained_here"]
        assert row["population"] == ("residual-study-obstacles4" if obstacles else "residual-study")
        assert set(row["ladders"]) == ({"obs-noise", "delay"} if obstacles else {"obs-noise", "delay", "obstacles"})
        assert row["ladder_kinds"] == ["residual", "hierarchical"]
    protocol = (ROOT / "docs" / "residual.md").read_text()
    assert "## Protocol of the residual study" in protocol
    assert f"`{design.TRAINING_CODE}`" in protocol  # the training code it runs with, named in the protocol


def test_the_build_is_the_rule_study_s() -> None:
    """The build the driver insists on is the one the rule study records (studies/rule-value/build.json,
    where the checkout has it)."""
    recorded = ROOT / "studies" / "rule-value" / "build.json"
    if not recorded.exists():
        pytest.skip("no studies/rule-value/build.json in this checkout")
    build = json.loads(recorded.read_text())
    assert (build["code"], build["commit"]) == (design.RULE_STUDY_CODE, design.RULE_STUDY_COMMIT)


def _run(seed: int, kind: str, margin: float) -> dict:
    """A compact result whose every member gives ``margin`` (the trained return over the baselines)."""
    panels = {"predator_0": [margin, 0.0, 0.0]}
    return {"seed": seed, "kind": kind, "pool": {"8": {"FleeingPrey": {"panels": panels}, "x": {"panels": panels}}}}


def test_the_seed_rule_reads_all_three_kinds() -> None:
    good = [_run(s, k, 0.1) for s in range(10) for k in design.KINDS]
    assert design.seeds_wanted(good) == 10
    assert design.seeds_wanted(good[:-1]) == 10  # not all in: still the first ten
    split = [*good[:-1], _run(9, "flat", -0.2)]  # one failed run of one kind
    assert design.seeds_wanted(split) == 20
    more = split + [_run(s, k, 0.1) for s in range(10, 20) for k in design.KINDS]
    assert design.seeds_wanted(more) == 30  # the failure is still among the first 20
    assert design.seeds_wanted(more + [_run(s, k, 0.1) for s in range(20, 30) for k in design.KINDS]) == 30


def _tiny_rule_study(tmp: Path) -> None:
    """What the rule study leaves for 1p-high, tiny: its population (one prey in every learned
    member's place), its judged runs' folders (seeds 0–1 of both kinds) and their compact results."""
    from pursuit_bench.agents.config import PRESETS
    from pursuit_bench.training import runs
    from pursuit_bench.training.sweep import SweepPlan, open_sweep, run_sweep

    plan = SweepPlan(
        conditions=("1p-high",),
        seeds=2,
        predators=("hierarchical", "flat"),
        agent=PRESETS["quick"].replace(episodes=8),
        episodes=8,
        eval_episodes=1,
        num_envs=2,
        checkpoint_every=4,
        preset="quick",
        keep_checkpoints=(4,),
    )
    sweep = tmp / "rule-work" / "judged-1p-high-from0"
    open_sweep(sweep, plan)
    assert run_sweep(sweep, plan, workers=1, record=False)
    config, agents, _ = runs.described(sweep / "runs" / "1p-high-hierarchical-seed0")
    prey = {m["name"]: (agents["prey_0"], config) for m in rule_study.members("1p-high") if m["policy"] is None}
    trained = {n: {"preset": "quick", "episodes": 8, "predator_kind": "x", "build": "test"} for n in prey}
    rule_study.write_population(tmp / "rule-pop", "1p-high", prey, trained)
    for kind in rule_study.KINDS:
        for seed in range(2):
            name = f"1p-high-{kind}-seed{seed}"
            result = rule_study.evaluate_run(
                sweep / "runs" / name, tmp / "rule-pop" / "1p-high", episodes=2, budgets=(4, 8)
            )
            rule_study.write_run(tmp / "rule-results" / "runs", name, "1p-high", kind, seed, "test", result)


@pytest.mark.slow
@pytest.mark.long
def test_a_tiny_run_of_the_driver_reuses_the_rule_study_s_runs(tmp_path: Path) -> None:
    import shutil

    _tiny_rule_study(tmp_path)
    shutil.rmtree(
        tmp_path / "rule-work" / "judged-1p-high-from0" / "runs" / "1p-high-flat-seed1"
    )  # a new machine's loss
    options = ["--preset", "quick", "--episodes", "8", "--budgets", "4,8", "--eval-episodes", "2", "--num-envs", "2"]
    options += ["--checkpoint-every", "4", "--first", "2", "--step", "1", "--most", "2", "--rule-first", "2"]
    where = {k: str(tmp_path / k) for k in ("work", "results", "population", "rule-work", "rule-results")}
    command = [sys.executable, str(STUDY / "run.py"), "--workers", "1", "--settings", "1p-high", "--poll", "0"]
    command += [f"--{k}={v}" for k, v in where.items()] + [f"--rule-population={tmp_path / 'rule-pop'}"]
    done = subprocess.run(
        command + options + ["--skip-build-check"], capture_output=True, text=True, timeout=600, env=os.environ.copy()
    )
    assert done.returncode == 0, done.stdout + done.stderr
    index = json.loads((tmp_path / "population" / "residual-study" / "1p-high" / "population.json").read_text())
    assert [m["name"] for m in index["members"]] == [m["name"] for m in design.members("1p-high")]
    copied = tmp_path / "population" / "residual-study" / "1p-high" / "flat-seed1004" / "prey_0.safetensors"
    assert (
        copied.read_bytes() == (tmp_path / "rule-pop" / "1p-high" / "flat-seed1004" / "prey_0.safetensors").read_bytes()
    )
    from pursuit_bench.benchmark import populations

    loaded = populations.load("residual-study", "1p-high", folder=tmp_path / "population")
    assert len(loaded.members) == 13
    results = {p.name: json.loads(gzip.decompress(p.read_bytes())) for p in (tmp_path / "results" / "runs").iterdir()}
    assert sorted(results) == sorted(f"1p-high-{k}-seed{s}.json.gz" for k in design.KINDS for s in range(2))
    for name, run in results.items():
        assert list(run["pool"]) == ["4", "8"] and list(run["pool"]["8"]) == index_names(index)
        earlier = tmp_path / "rule-results" / "runs" / name
        if run["kind"] == "residual":
            assert not earlier.exists() and set(run["evaluated_by"].values()) == {"residual-study"}
            assert 0.0 <= run["corrections"]["predator_0"]["corrected"] <= 1.0
        else:  # the rule study's nine evaluations, as it wrote them; the residual members played here
            rule = json.loads(gzip.decompress(earlier.read_bytes()))
            for budget in ("4", "8"):
                assert {k: run["pool"][budget][k] for k in rule["pool"][budget]} == rule["pool"][budget]
        assert ("ladders" in run) == (run["kind"] != "flat")
    assert "runs the rule study's folders lack" in (tmp_path / "work" / "progress.log").read_text()
    about = json.loads((tmp_path / "results" / "residual-study.json").read_text())
    assert about["seed_rule"] == {"first": 2, "step": 1, "most": 2} and about["seed_floor"] == {"1p-high": 2}
    again = subprocess.run(command + options + ["--skip-build-check"], capture_output=True, text=True, timeout=600)
    assert again.returncode == 0 and "evaluating" not in again.stdout  # a rerun redoes nothing
    moved = [f"--work={tmp_path / 'new-machine'}" if c.startswith("--work=") else c for c in command]
    fresh = subprocess.run(moved + options + ["--skip-build-check"], capture_output=True, text=True, timeout=600)
    assert fresh.returncode == 0, fresh.stdout + fresh.stderr
    trained = [p.name for p in (tmp_path / "new-machine").iterdir() if p.is_dir()]
    assert trained == [], f"a new machine (the run folders gone, the results kept) trained again: {trained}"


def index_names(index: dict) -> list[str]:
    return [m["name"] for m in index["members"]]


def _git(root: Path, *args: str) -> str:
    command = ["git", "-c", "user.name=test", "-c", "user.email=test@example.com", *args]
    return subprocess.run(command, cwd=root, capture_output=True, text=True, check=True).stdout


def _rule_study_s_training_code() -> dict[str, str]:
    """The training code's files at the rule study's build, from this checkout's history."""
    try:
        listing = _git(ROOT, "ls-tree", "-r", design.RULE_STUDY_COMMIT, "--", "pursuit_bench")
    except (subprocess.CalledProcessError, FileNotFoundError):
        pytest.skip("the rule study's commit is not in this checkout's history")
    return design.training_files(listing)


def test_the_training_code_is_every_file_training_imports_and_its_fingerprint_the_rule_study_s() -> None:
    """TRAINING_CODE is the fingerprint of the rule study's build's training files (from git); the
    set holds the package's __init__ and every module of io, env, rules, agents and training but
    the evaluation; what those modules import at that build (function-local imports and module
    names in strings too) is in the set, or the evaluation."""
    files = _rule_study_s_training_code()
    assert design.training_code(files) == design.TRAINING_CODE and len(files) == 42
    assert "pursuit_bench/__init__.py" in files and "pursuit_bench/training/sweep.py" in files
    assert not set(design.NOT_TRAINING) & set(files)
    listing = _git(ROOT, "ls-tree", "-r", "--name-only", design.RULE_STUDY_COMMIT, "--", "pursuit_bench")
    modules = {
        ".".join(Path(p).with_suffix("").parts).removesuffix(".__init__"): p
        for p in listing.splitlines()
        if p.endswith(".py")
    }
    allowed = {m for m, p in modules.items() if p in files or p in design.NOT_TRAINING}
    assert len(allowed) == 43
    for path in files:
        source = _git(ROOT, "show", f"{design.RULE_STUDY_COMMIT}:{path}")
        for node in ast.walk(ast.parse(source)):
            named = []
            if isinstance(node, ast.Import):
                named = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:  # a module, or a name of one
                named = [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                named = [node.value.split(":")[0]] if node.value.startswith("pursuit_bench.") else []
            for name in (n for n in named if n.startswith("pursuit_bench")):
                module = name if name in modules else name.rsplit(".", 1)[0]
                assert module in allowed, f"{path} imports {name}, outside the training code"


def _checkout(tmp: Path) -> Path:
    """A git checkout holding the rule study's build's training code (and its evaluate.py)."""
    _rule_study_s_training_code()
    paths = [p.rstrip("/") for p in design.TRAINING_CODE_PATHS]
    archive = subprocess.run(
        ["git", "archive", design.RULE_STUDY_COMMIT, "--", *paths], cwd=ROOT, capture_output=True, check=True
    ).stdout
    root = tmp / "checkout"
    root.mkdir()
    subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    _git(root, "init", "-q")
    _git(root, "add", "-A")
    _git(root, "commit", "-q", "-m", "the rule study's training code")
    return root


def _commit(root: Path, path: str, line: str) -> None:
    with (root / path).open("a") as file:
        file.write(line + "\n")
    _git(root, "add", "-A")
    _git(root, "commit", "-q", "-m", f"changed {path}")


def test_a_package_whose_training_code_is_not_the_rule_study_s_is_refused_naming_the_files(tmp_path: Path) -> None:
    run = _study_module("run")
    root = _checkout(tmp_path)
    first = run.package_build(root)
    assert first["training_code"] == design.TRAINING_CODE
    _commit(root, "pursuit_bench/training/evaluate.py", "# the evaluation is not training")
    second = run.package_build(root)
    assert second["training_code"] == first["training_code"] and second["code"] != first["code"]
    (root / "pursuit_bench/agents/dqn.py").write_text((root / "pursuit_bench/agents/dqn.py").read_text() + "#\n")
    with pytest.raises(SystemExit, match="uncommitted code changes"):
        run.package_build(root)
    _git(root, "commit", "-q", "-a", "-m", "dqn")
    _commit(root, "pursuit_bench/env/extra.py", "X = 1")
    with pytest.raises(SystemExit) as refused:
        run.package_build(root)
    message = str(refused.value)
    assert "\n" not in message and "not the rule study's" in message and design.TRAINING_CODE in message
    assert message.endswith(": pursuit_bench/agents/dqn.py, pursuit_bench/env/extra.py")


def test_the_pinned_build_is_refused_once_the_package_changes(tmp_path: Path) -> None:
    """The first start writes build.json; a later start with other package code (the training
    code still the rule study's) is refused, the same code goes on; a lost build.json is not
    written again over the study's results."""
    run = _study_module("run")
    root = _checkout(tmp_path)
    pinned, results = tmp_path / "build.json", tmp_path / "results"
    started = run.package_build(root)
    run.pin(pinned, started, results)
    assert {k: v for k, v in json.loads(pinned.read_text()).items() if k != "pinned"} == started
    run.pin(pinned, run.package_build(root), results)  # a resume: the same build
    _commit(root, "pursuit_bench/training/evaluate.py", "# main went on")
    later = run.package_build(root)
    with pytest.raises(SystemExit) as refused:
        run.pin(pinned, later, results)
    message = str(refused.value)
    assert "\n" not in message and "not mixed" in message
    with pytest.raises(SystemExit, match="not mixed"):  # a try-out is held to the pinned build too
        run.pin(pinned, later, results, write=False)
    run.pin(tmp_path / "none.json", later, results, write=False)  # and writes no build.json of its own
    assert not (tmp_path / "none.json").exists()
    assert started["code"] in message and later["code"] in message
    pinned.unlink()
    (results / "runs").mkdir(parents=True)
    (results / "runs" / "1p-high-residual-seed0.json.gz").write_bytes(b"")
    with pytest.raises(SystemExit, match="restore it from git"):
        run.pin(pinned, later, results)
    assert not pinned.exists()


@pytest.mark.slow
@pytest.mark.long
def test_a_tiny_run_of_an_obstacle_setting_trains_its_own_population_and_all_three_kinds(tmp_path: Path) -> None:
    """An obstacle setting needs nothing of the rule study: its 12 learned members and the judged
    runs of all three kinds are trained here with the obstacles; a SIGTERM stops the driver
    cleanly (143) and the same command finishes the study."""
    import signal
    import time

    options = ["--preset", "quick", "--episodes", "8", "--budgets", "4,8", "--eval-episodes", "2", "--num-envs", "2"]
    options += ["--checkpoint-every", "4", "--first", "1", "--step", "1", "--most", "1", "--skip-build-check"]
    where = [f"--{k}={tmp_path / k}" for k in ("work", "results", "population", "rule-work", "rule-results")]
    where.append(f"--rule-population={tmp_path / 'none'}")  # the rule study is not needed here
    command = [sys.executable, str(STUDY / "run.py"), "--workers", "1", "--settings", "1p-high-obstacles4"]
    command += ["--poll", "0", *where, *options]
    log = tmp_path / "work" / "progress.log"
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 300
        while not (log.exists() and "trained 1p-high-obstacles4" in log.read_text()):
            assert process.poll() is None and time.monotonic() < deadline, (
                process.stderr.read() if process.stderr else ""
            )
            time.sleep(0.2)
        process.send_signal(signal.SIGTERM)
        assert process.wait(timeout=300) == 143
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert "stopped: rerun the same command to resume" in log.read_text()
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    index = json.loads(
        (tmp_path / "population" / "residual-study-obstacles4" / "1p-high" / "population.json").read_text()
    )
    assert index["obstacles"] == 4 and [m["name"] for m in index["members"]] == [
        m["name"] for m in design.members("1p-high")
    ]
    member = tmp_path / "population" / "residual-study-obstacles4" / "1p-high" / "flat-seed1004" / "prey_0.safetensors"
    header = json.loads(pretrained.read(member)[1]["training"])
    assert header["obstacles"] == 4 and header["seed"] == 1004 and header["predator"] == "flat"
    results = {p.name: json.loads(gzip.decompress(p.read_bytes())) for p in (tmp_path / "results" / "runs").iterdir()}
    assert sorted(results) == sorted(f"1p-high-obstacles4-{k}-seed0.json.gz" for k in design.KINDS)
    for run in results.values():
        assert run["setting"] == "1p-high-obstacles4" and run["obstacles"] == 4 and len(run["pool"]["8"]) == 13
        assert set(run["evaluated_by"].values()) == {"residual-study"}
        if "ladders" in run:  # no obstacles ladder for runs trained with obstacles
            assert sorted(run["ladders"]) == [
                "delay=1",
                "delay=3",
                "delay=6",
                "none",
                "obs-noise=0.02",
                "obs-noise=0.05",
                "obs-noise=0.1",
            ]


def _descriptives() -> ModuleType:
    """studies/residual-value/residual_descriptives.py, loaded as a module."""
    module = load_script("studies/residual-value/residual_descriptives.py")
    return module


def _run_with_corrections(kind: str, seed: int, corrected: float, trained: float, fixed: float) -> dict[str, object]:
    """A compact run of one predator of 1p-high: against one member, ``trained`` its return and
    ``fixed`` both fixed modes' (pool margin ``trained - fixed``); a residual run corrects a share
    ``corrected`` of 100 stalking states near the prey, half that of 100 further, and all of 50
    chasing states."""
    run: dict[str, object] = {
        "format": rule_study.FORMAT,
        "study": "residual-study",
        "setting": "1p-high",
        "condition": "1p-high",
        "kind": kind,
        "seed": seed,
        "pool": {"15000": {rule_study.FLEEING: {"panels": {"predator_0": [trained, fixed, fixed]}}}},
    }
    if kind == "residual":
        run["corrections"] = {
            "predator_0": {
                "corrected": corrected,
                "p_chase": 0.2,
                "correction_by_distance": {
                    "bins": [0.0, 0.5, 1.0],
                    "stalk": {"states": [100, 100], "corrected": [corrected, corrected / 2]},
                    "chase": {"states": [50, 0], "corrected": [1.0, None]},
                    "used": {},
                },
            }
        }
    return run


def _write_runs(folder: Path, shares: list[float]) -> list[dict[str, Any]]:
    """One residual and one hierarchical run a seed, residual seed s correcting ``shares[s]``: its
    margin gain over the hierarchical run (0) is +c, its return gain −c (fixed modes at −2c)."""
    (folder / "runs").mkdir()
    for seed, c in enumerate(shares):
        for kind, trained, fixed in (("residual", -c, -2 * c), ("hierarchical", 0.0, 0.0)):
            document = _run_with_corrections(kind, seed, c, trained, fixed)
            name = f"1p-high-{kind}-seed{seed}.json.gz"
            (folder / "runs" / name).write_bytes(gzip.compress(json.dumps(document).encode()))
    return rule_study.read_runs(folder / "runs")


def _row(lines: list[str], start: str) -> list[str]:
    return [cell.strip() for cell in next(line for line in lines if line.startswith(start)).strip("|").split("|")]


def test_the_corrections_summary_places_corrected_states_and_ranks_them_against_both_gaps(tmp_path: Path) -> None:
    """Known answers: runs correcting shares c = 0.1, 0.3, 0.2 of their near stalking states, c/2
    of the further ones and every chasing state have 60, 30 and 150 corrected states in all (25 %,
    12.5 %, 62.5 %); their margin gains rise with c (ρ +1) and their return gains fall (ρ −1)."""
    summary = _descriptives()
    lines = summary.corrections_table(_write_runs(tmp_path, [0.1, 0.3, 0.2]))
    cells = _row(lines, "| 1p-high |")
    assert cells[1:9] == ["3", "20.0%", "30.0%", "1/3", "20.0%", "25%", "12%", "62%"]
    assert (cells[9], cells[12]) == ("+1.00", "-1.00")
    assert any("over the table's 2 correlations" in line for line in lines)


def test_the_corrections_summary_gives_no_correlation_below_three_seeds(tmp_path: Path) -> None:
    summary = _descriptives()
    cells = _row(summary.corrections_table(_write_runs(tmp_path, [0.1, 0.3])), "| 1p-high |")
    assert cells[9:] == ["—"] * 6


def test_the_ladder_levels_are_each_kind_s_mean_margin_at_each_level() -> None:
    """Known answer: two residual runs with margins 0.1 and 0.3 under noise 0.05 read +0.200 in
    that column; a level one run of the group lacks reads —."""
    summary = _descriptives()
    runs = []
    for seed, margin in enumerate([0.1, 0.3]):
        run = _run_with_corrections("residual", seed, 0.0, 0.0, 0.0)
        run["ladders"] = {"none": {"margin": 0.5}, "obs-noise=0.05": {"margin": margin}}
        if seed == 0:
            run["ladders"]["delay=1"] = {"margin": 0.0}
        runs.append(run)
    lines = summary.ladder_levels_table(runs)
    assert "| none | obs-noise=0.05 | delay=1 |" in lines[3]
    assert _row(lines, "| 1p-high | residual |")[2:] == ["2", "+0.500", "+0.200", "—"]


def test_the_committed_descriptives_are_what_their_script_gives() -> None:
    """results/residual-study/descriptives.md (docs/residual.md cites it) is what
    studies/residual-value/residual_descriptives.py computes from the committed runs, its first line (the
    command) aside."""
    summary = _descriptives()
    committed = (ROOT / "results" / "residual-study" / "descriptives.md").read_text().splitlines()
    assert committed[1:] == summary.tables(ROOT / "results" / "residual-study").splitlines()[1:]


def test_the_descriptives_script_refuses_a_folder_without_residual_runs_in_one_line(tmp_path: Path) -> None:
    """No runs, no residual run (a hierarchical one only), or a file that is not a compact run:
    one line naming the folder, exit status 1."""
    script = STUDY / "residual_descriptives.py"
    (tmp_path / "runs").mkdir()
    hierarchical = gzip.compress(json.dumps(_run_with_corrections("hierarchical", 0, 0.0, 0.0, 0.0)).encode())
    for content in (None, hierarchical, b"not gzip"):
        if content is not None:
            (tmp_path / "runs" / "a.json.gz").write_bytes(content)
        done = subprocess.run([sys.executable, str(script), str(tmp_path)], capture_output=True, text=True, timeout=120)
        assert done.returncode == 1
        assert done.stderr.count("\n") == 1 and done.stderr.startswith(f"error: {tmp_path / 'runs'}")
