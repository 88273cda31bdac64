"""``train --tensorboard DIR`` (issue 67): the scalars of metrics.jsonl as TensorBoard event files,
read back with TensorBoard's own reader; a resumed run shows each episode once."""

import json
from pathlib import Path

import pytest
from cli_helpers import run_cli

from pursuit_bench.training.tensorboard_log import TensorBoardLog
from pursuit_bench.training.train import EpisodeRecord

event_accumulator = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")


def scalars(folder: Path) -> dict[str, dict[int, float]]:
    """Every scalar TensorBoard shows for a log dir: tag -> step -> value."""
    reader = event_accumulator.EventAccumulator(str(folder), size_guidance={event_accumulator.SCALARS: 0})
    reader.Reload()
    shown = {tag: [(e.step, e.value) for e in reader.Scalars(tag)] for tag in reader.Tags()["scalars"]}
    for tag, events in shown.items():  # each step once
        assert len({step for step, _ in events}) == len(events), (tag, events)
    return {tag: dict(events) for tag, events in shown.items()}


def test_train_writes_the_metrics_rows_as_scalars_at_their_episodes(tmp_path: Path) -> None:
    out, board = tmp_path / "run", tmp_path / "tb"
    code, output = run_cli(
        "train", "--condition", "2p-low-shared", "--episodes", "6", "--out", str(out), "--no-record",
        "--tensorboard", str(board), "--learning-starts", "20", "--batch-size", "8",
    )  # fmt: skip
    assert code == 0, output
    assert f"tensorboard --logdir {board}" in output
    rows = [json.loads(line) for line in (out / "metrics.jsonl").read_text().splitlines()]
    shown = scalars(board / "run")
    columns = {k for row in rows for k in row} - {"episode"}
    assert set(shown) == columns and {"return/predator_0", "chase_fraction/predator_1", "length"} <= columns
    assert any(k.startswith("loss/") for k in columns) and "epsilon" in columns
    for row in rows:
        for key in columns & row.keys():
            assert shown[key][row["episode"]] == pytest.approx(float(row[key]), rel=1e-6, abs=1e-7), key
    assert sorted(shown["length"]) == [row["episode"] for row in rows] == list(range(1, 7))


def test_a_resumed_run_replaces_the_episodes_after_its_checkpoint(tmp_path: Path) -> None:
    """A process stopped after its checkpoint at episode 3 had written episodes 4 and 5; the
    resumed one writes 4 to 6 again: TensorBoard shows the new 4 and 5, each episode once."""

    def record(episode: int, length: int) -> EpisodeRecord:
        return EpisodeRecord(episode, length, False, {"prey_0": 0.5}, {"predator_0": 0.25})

    first = TensorBoardLog(tmp_path / "tb", episodes_done=0)
    for episode in range(1, 6):
        first.write(record(episode, 10 * episode))
    first.close()
    resumed = TensorBoardLog(tmp_path / "tb", episodes_done=3)
    for episode in range(4, 7):
        resumed.write(record(episode, 100 * episode))
    resumed.close()
    assert scalars(tmp_path / "tb")["length"] == {1: 10, 2: 20, 3: 30, 4: 400, 5: 500, 6: 600}
