"""``eval --csv`` (issue 67): the trained variant's trajectories as CSV, a row per agent and step,
units in the column names; checked against the recording's own traces and the env's rules."""

import csv
import json
from pathlib import Path

import numpy as np
from cli_helpers import run_cli

from pursuit_bench.trajectories.recording import EpisodeTrace
from pursuit_bench.trajectories.trajectory_csv import COLUMNS, TrajectoryCSV


def _trace() -> EpisodeTrace:
    positions = np.array([[[0.0, 0.0], [0.5, 0.5]], [[0.1, 0.0], [0.5, 0.6]], [[0.25, 0.0], [0.5, 0.65]]])
    return EpisodeTrace(
        positions=positions,
        modes=np.array([[0], [1]]),
        rewards=np.array([[-0.01, 0.0], [1.0, -1.0]]),
        wall=np.array([[False, False], [False, True]]),
        captured=np.array([[False], [True]]),
        truncated=False,
    )


def test_an_episode_s_rows_say_each_step_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    sink = TrajectoryCSV(path, ["predator_0", "prey_0"])
    sink.log_episode(2, _trace())
    sink.log_episode(1, _trace())
    sink.close()
    rows = list(csv.DictReader(path.open()))
    assert list(rows[0]) == list(COLUMNS) and len(rows) == 2 * 3 * 2
    assert [r["episode"] for r in rows[::6]] == ["1", "2"]  # in the order of their numbers
    start, first, last = rows[0], rows[2], rows[4]
    assert (start["step"], start["mode"], start["reward"], start["vx_arena_per_s"]) == ("0", "", "", "0.0")
    assert (first["agent"], first["role"], first["time_s"], first["mode"]) == ("predator_0", "predator", "0.1", "stalk")
    assert float(first["vx_arena_per_s"]) == 0.1 / 0.1 and float(first["reward"]) == -0.01
    assert (last["mode"], float(last["vx_arena_per_s"]), last["captured"]) == ("chase", 0.15 / 0.1, "1")
    prey = rows[5]
    assert (prey["role"], prey["mode"], prey["wall"], prey["captured"], float(prey["reward"])) == (
        "prey", "", "1", "1", -1.0
    )  # fmt: skip
    assert np.isclose(float(prey["vy_arena_per_s"]), 0.05 / 0.1)


def test_eval_csv_holds_every_trained_episode_as_eval_json_counts_it(tmp_path: Path) -> None:
    out = tmp_path / "eval"
    code, output = run_cli(
        "eval", "--pretrained", "2p-low-shared", "--episodes", "12", "--num-envs", "4", "--no-record", "--csv",
        "--out", str(out),
    )  # fmt: skip
    assert code == 0, output
    assert f"trajectories: {out / 'eval.csv'}" in output
    result = json.loads((out / "eval.json").read_text())
    rows = list(csv.DictReader((out / "eval.csv").open()))
    episodes: dict[int, list[dict[str, str]]] = {}
    for row in rows:
        episodes.setdefault(int(row["episode"]), []).append(row)
    assert sorted(episodes) == list(range(1, 13))
    lengths = [max(int(r["step"]) for r in e) for e in episodes.values()]
    assert np.isclose(np.mean(lengths), result["episode_length"])
    returns = {
        a: np.mean(
            [sum(float(r["reward"]) for r in e if r["agent"] == a and r["step"] != "0") for e in episodes.values()]
        )
        for a in ("predator_0", "predator_1", "prey_0")
    }
    assert all(np.isclose(returns[a], result["mean_return"][a]) for a in returns), (returns, result["mean_return"])
    captured = np.mean([any(r["captured"] == "1" for r in e if r["agent"] == "prey_0") for e in episodes.values()])
    assert np.isclose(captured, result["capture_rate"])
    speeds = [np.hypot(float(r["vx_arena_per_s"]), float(r["vy_arena_per_s"])) for r in rows]
    assert max(speeds) <= 1.44 + 1e-6  # no disk faster than a chasing predator's top speed (docs/spec.md)
    code, output = run_cli(
        "eval", "--pretrained", "2p-low-shared", "--episodes", "4", "--no-record", "--out", str(out)
    )  # fmt: skip
    assert code == 0 and not (out / "eval.csv").exists()  # an older file would not match
