"""`pursuit-bench sweep`: run folders trained in stacks over worker processes, resumable."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import lines, run_cli, wait_until

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.training import runs
from pursuit_bench.training.sweep import SweepPlan, expected_cost, stacks

SWEEP = ["sweep", "--conditions", "1p-high,2p-high-shared", "--seeds", "2", "--episodes", "40"]
SWEEP += ["--eval-episodes", "50", "--workers", "2", "--checkpoint-every", "10"]
NAMES = [f"{c}-hierarchical-seed{s}" for c in ("1p-high", "2p-high-shared") for s in (0, 1)]


def episodes_of(folder: Path) -> list[int]:
    return [json.loads(line)["episode"] for line in (folder / "metrics.jsonl").read_text().splitlines()]


@pytest.mark.slow
@pytest.mark.long
def test_a_small_sweep_leaves_evaluated_run_folders_that_match_runs_trained_alone(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    code, output = run_cli(*SWEEP, "--out", str(out))
    assert code == 0 and "4 of 4 runs trained and evaluated" in output, output
    plan = json.loads((out / "sweep.json").read_text())
    assert plan["runs"] == sorted(NAMES) and plan["plan"]["episodes"] == 40
    for name in NAMES:
        folder = out / "runs" / name
        assert episodes_of(folder) == list(range(1, 41))
        result = json.loads((folder / "eval.json").read_text())
        assert result["episodes"] == 50 and result["predator_kind"] == "hierarchical"
        assert result["trained_episodes"] == 40 and (folder / "train.rrd").exists()

    alone = tmp_path / "alone"  # the same run, trained by itself
    code, output = run_cli(
        "train", "--condition", "2p-high-shared", "--seed", "1", "--episodes", "40", "--out", str(alone), "--no-record"
    )
    assert code == 0, output
    assert (alone / "metrics.jsonl").read_text() == (out / "runs" / NAMES[3] / "metrics.jsonl").read_text()

    code, output = run_cli(*SWEEP, "--out", str(out))  # finished: nothing to do
    assert code == 0 and "4 of 4" in output
    assert episodes_of(out / "runs" / NAMES[0]) == list(range(1, 41))
    code, output = run_cli(*SWEEP[:-2], "--workers", "1", "--seeds", "3", "--out", str(out))
    assert code == 2 and "another plan" in output
    code, output = run_cli("eval", str(out / "runs" / NAMES[0]), "--episodes", "4", "--tag", "mine", "--no-record")
    assert code == 0, output

    code, output = run_cli("report", str(out))  # Fig. 2 over the two seeds
    assert code == 0 and "3 panels" in output, output
    for name in ("fig2.png", "curves.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and (out / name).stat().st_size > 20_000
    report = json.loads((out / "report.json").read_text())
    assert [(p["condition"], p["predator"]) for p in report["panels"]] == [
        ("1p-high", "predator_0"),
        ("2p-high-shared", "predator_0"),
        ("2p-high-shared", "predator_1"),
    ]
    for panel in report["panels"]:
        assert list(panel["variants"]) == ["hierarchical", "always_chase", "always_stalk"]
        for variant in panel["variants"].values():
            assert variant["seeds"] == [0, 1] and len(variant["values"]) == 2
            assert variant["mean"] == pytest.approx(sum(variant["values"]) / 2)
            assert variant["ci"][0] <= variant["mean"] <= variant["ci"][1]
        ours = panel["variants"]["hierarchical"]["values"]
        for baseline in ("always_chase", "always_stalk"):  # paired by seed, Holm-corrected over the family
            paired = panel["paired"][baseline]
            theirs = panel["variants"][baseline]["values"]
            assert paired["differences"] == pytest.approx([a - b for a, b in zip(ours, theirs, strict=True)])
            assert paired["p_greater"] <= paired["p_greater_holm"] <= 1.0
        assert panel["verdict"] in ("better", "not resolved", "worse")
        seed0 = json.loads((out / "runs" / panel["variants"]["hierarchical"]["runs"][0] / "eval.json").read_text())
        index = int(panel["predator"][-1])
        assert seed0["panels"][index]["trained"] == panel["variants"]["hierarchical"]["values"][0]
    assert report["summary"]["panels"] == 3 and "not resolved" in (out / "report.md").read_text()
    assert report["summary"]["per_seed"]["counts"] == [
        sum(
            all(
                p["variants"]["hierarchical"]["values"][i] > p["variants"][b]["values"][i]
                for b in ("always_chase", "always_stalk")
            )
            for p in report["panels"]
        )
        for i in range(2)
    ]

    code, output = run_cli("analyze", str(out), "--episodes", "6")  # chasing across costs, over seeds
    assert code == 0 and "2 predators, high cost: 2 runs" in output, output
    analysis = json.loads((out / "analysis.json").read_text())
    assert set(analysis) == {"1 predator, high cost", "2 predators, high cost"}
    assert all(len(a["p_chase"]) == 20 for a in analysis.values()) and (out / "modes.png").stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.long
def test_a_killed_sweep_finishes_on_rerun_with_nothing_trained_twice(tmp_path: Path, processes) -> None:
    out = tmp_path / "sweep"
    command = [sys.executable, "-m", "pursuit_bench.cli.main", *SWEEP, "--episodes", "120", "--out", str(out)]
    process = processes(command)
    # past the first checkpoint (episode 10): metrics rows beyond it must not survive the resume
    wait_until(lambda: any(lines(p) >= 14 for p in out.glob("runs/*/metrics.jsonl")), "a run past its checkpoint")
    os.killpg(process.pid, signal.SIGKILL)  # the sweep and its workers, at once
    process.wait()
    assert not all((out / "runs" / name / "eval.json").exists() for name in NAMES)
    rerun = subprocess.run(command, capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    for name in NAMES:
        folder = out / "runs" / name
        assert episodes_of(folder) == list(range(1, 121)), name
        assert runs.load_checkpoint(folder)["episodes_done"] == 120
        assert (folder / "eval.json").exists()


def test_stacks_share_shapes_and_spread_over_workers() -> None:
    plan = SweepPlan(conditions=("1p-low", "1p-high", "2p-low-shared"), seeds=4, predators=("hierarchical", "flat"))
    names = list(plan.runs())
    groups = stacks(plan, names, workers=4)
    assert sorted(n for g in groups for n in g) == sorted(names) and len(groups) >= 4
    for group in groups:
        shapes = {(n.split("-")[0], n.split("-")[-2]) for n in group}
        assert len(shapes) == 1, group


def test_bad_sweep_input_is_one_line() -> None:
    code, output = run_cli("sweep", "--conditions", "1p-high,9p", "--out", "x")
    assert code == 2 and "expected 'all' or a comma-separated list" in output
    with pytest.raises(ValueError, match="seeds=0"):
        SweepPlan(conditions=("1p-high",), seeds=0)


def test_the_ray_backend_without_ray_says_which_extra(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray fails as if not installed
    code, output = run_cli(
        "sweep",
        "--conditions",
        "1p-low",
        "--seeds",
        "1",
        "--episodes",
        "5",
        "--backend",
        "ray",
        "--out",
        str(tmp_path / "s"),
    )
    assert code == 2 and "pip install 'pursuit-bench[ray]'" in output and "Traceback" not in output
    assert not (tmp_path / "s").exists()  # refused before the plan is written


def test_stacks_are_planned_by_expected_cost() -> None:
    """The paper's sweep on 2 workers: stacks taken longest first by whichever worker is free
    give both workers about half the expected cost (by count they would not)."""
    plan = SweepPlan(conditions=tuple(CONDITIONS), seeds=5, episodes=15_000)
    configs = plan.runs()
    planned = stacks(plan, list(configs), workers=2)
    costs = [sum(expected_cost(configs[n]) for n in stack) for stack in planned]
    assert costs == sorted(costs, reverse=True)
    loads = [0.0, 0.0]
    for cost in costs:
        loads[loads.index(min(loads))] += cost
    assert max(loads) < 0.55 * sum(costs), loads
    assert expected_cost(configs["1p-high-hierarchical-seed0"]) > 5 * expected_cost(
        configs["1p-low-hierarchical-seed0"]
    )


@pytest.mark.slow
def test_kept_checkpoints_are_evaluated_like_the_final_one(tmp_path: Path) -> None:
    out = tmp_path / "s"
    command = ["sweep", "--conditions", "1p-low", "--seeds", "1", "--episodes", "16", "--eval-episodes", "8"]
    code, output = run_cli(*command, "--workers", "1", "--no-record", "--keep-checkpoints", "8", "--out", str(out))
    assert code == 0, output
    folder = out / "runs" / "1p-low-hierarchical-seed0"
    assert runs.load_checkpoint(folder, runs.milestone_checkpoint(8))["episodes_done"] == 8
    early, final = (json.loads((folder / name).read_text()) for name in ("eval-ep8.json", "eval.json"))
    assert early["trained_episodes"] == 8 and final["trained_episodes"] == 16
    code, output = run_cli(*command, "--workers", "1", "--keep-checkpoints", "20", "--out", str(tmp_path / "t"))
    assert code == 2 and "--keep-checkpoints 20" in output


@pytest.mark.slow
def test_a_sweep_extends_to_more_episodes_and_names_what_else_differs(tmp_path: Path) -> None:
    out = tmp_path / "s"
    command = ["sweep", "--conditions", "1p-low", "--seeds", "1", "--eval-episodes", "6", "--workers", "1"]
    command += ["--no-record", "--checkpoint-every", "4", "--out", str(out)]
    code, output = run_cli(*command, "--episodes", "8")
    assert code == 0, output
    folder = out / "runs" / "1p-low-hierarchical-seed0"
    assert json.loads((folder / "eval.json").read_text())["trained_episodes"] == 8
    code, output = run_cli(*command, "--episodes", "12")
    assert code == 0 and "extending the sweep from 8 to 12 episodes" in output, output
    assert episodes_of(folder) == list(range(1, 13))
    assert json.loads((folder / "eval.json").read_text())["trained_episodes"] == 12
    assert runs.read_config(folder)[0].episodes == 12
    code, output = run_cli(*command, "--episodes", "12", "--gamma", "0.5")
    assert code == 2 and "agent.gamma: 0.9 → 0.5" in output and len(output.strip().splitlines()) == 1, output
    code, output = run_cli(*command, "--episodes", "6")
    assert code == 2 and "episodes: 12 → 6" in output, output


def test_a_signal_just_after_the_plan_is_written_stops_the_sweep(tmp_path: Path, monkeypatch) -> None:
    """A SIGTERM that lands between writing the plan and starting the workers is acted on:
    no worker starts and the command exits 143. The process ignores SIGTERM until the command
    catches it (as a harness that starts tests with it ignored leaves it), so a signal that
    came before the catcher was in place would be lost and the sweep would train on."""
    from pursuit_bench.training import sweep as sweeps

    write_plan = sweeps.open_sweep

    def write_plan_then_signal(out: Path, plan: SweepPlan) -> str | None:
        note = write_plan(out, plan)
        os.kill(os.getpid(), signal.SIGTERM)
        return note

    monkeypatch.setattr(sweeps, "open_sweep", write_plan_then_signal)
    previous = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        code, output = run_cli(*SWEEP, "--workers", "1", "--no-record", "--out", str(tmp_path / "s"))
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert code == 143 and "0 of 4 runs with a checkpoint" in output, output
    assert not (tmp_path / "s" / "runs").exists() or not any((tmp_path / "s" / "runs").iterdir())


def test_a_stopped_sweep_says_what_it_saved(tmp_path: Path, processes) -> None:
    out = tmp_path / "s"
    command = [sys.executable, "-m", "pursuit_bench.cli.main", *SWEEP, "--episodes", "100000", "--out", str(out)]
    process = processes(command)
    wait_until(lambda: (out / "sweep.json").exists(), "the sweep's plan written")
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=300)  # stacks checkpoint first; slow on a loaded machine
    assert process.returncode == 143, stderr
    with_checkpoint = sum((out / "runs" / name / "checkpoint.pt").exists() for name in NAMES)
    assert f"{with_checkpoint} of 4 runs with a checkpoint" in stderr, stderr
    others = {0: "rerun the same command", 1: "the other one starts", 2: "the other 2 start", 3: "the other 3 start"}
    assert others.get(4 - with_checkpoint, "the other 4 start") in stderr and "the others" not in stderr, stderr
