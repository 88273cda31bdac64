"""``eval --tracks`` (issue 66): the evaluated episodes as movement's poses datasets, one netCDF
file per episode, read back by xarray, passing movement's own validator, the same positions and
modes as eval.csv; files movement cannot use refused in one line."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run_cli

from pursuit_bench.io import tracks

movement = pytest.importorskip("movement")
kinematics = pytest.importorskip("movement.kinematics")
#: netCDF4's wheel (pinned below 1.7.3 by movement) was compiled against an older numpy, which it
#: says on import; harmless (its arrays are read as numpy's), and not ours to fix.
pytestmark = pytest.mark.filterwarnings("ignore:numpy.ndarray size changed:RuntimeWarning")


def test_eval_tracks_writes_one_valid_dataset_per_episode_as_eval_csv_has_it(tmp_path: Path) -> None:
    out = tmp_path / "eval"
    code, output = run_cli(
        "eval", "--pretrained", "2p-low-shared", "--episodes", "6", "--num-envs", "3", "--no-record", "--csv",
        "--tracks", "--out", str(out),
    )  # fmt: skip
    assert code == 0, output
    files = sorted((out / "eval-tracks").glob("*.nc"))
    assert [f.name for f in files] == [f"episode-{k:04d}.nc" for k in range(1, 7)]
    rows = list(csv.DictReader((out / "eval.csv").open()))
    captured = 0
    for k, path in enumerate(files, start=1):
        dataset = tracks.read(path)  # movement's validator passes
        assert dict(dataset.sizes) == {"time": dataset.sizes["time"], "space": 2, "keypoints": 1, "individuals": 3}
        assert list(dataset["individuals"].values) == ["predator_0", "predator_1", "prey_0"]
        assert (dataset.attrs["fps"], dataset.attrs["source_software"], dataset.attrs["episode"]) == (
            10.0, "pursuit-bench", k
        )  # fmt: skip
        assert np.allclose(np.diff(dataset["time"].values), 0.1)
        mine = [r for r in rows if r["episode"] == str(k)]
        for name in ("predator_0", "prey_0"):
            xy = dataset["position"].sel(individuals=name, keypoints="centroid").values  # (time, space)
            expected = [(float(r["x_arena"]), float(r["y_arena"])) for r in mine if r["agent"] == name]
            assert np.array_equal(xy, np.array(expected))
        modes = dataset["mode"].sel(individuals="predator_1").values
        expected_modes = [
            {"chase": 1.0, "stalk": 0.0}.get(r["mode"], np.nan) for r in mine if r["agent"] == "predator_1"
        ]
        assert np.array_equal(modes, np.array(expected_modes), equal_nan=True)
        assert np.isnan(dataset["mode"].sel(individuals="prey_0").values).all()
        captured += dataset.attrs["ended"] == "captured"
        velocity = kinematics.compute_velocity(dataset["position"])  # movement's own functions run on it
        assert np.isfinite(velocity.values).all()
    result = json.loads((out / "eval.json").read_text())
    assert np.isclose(captured / 6, result["capture_rate"])


def test_files_movement_cannot_use_are_refused_in_one_line(tmp_path: Path) -> None:
    import xarray as xr

    (tmp_path / "notes.nc").write_text("not netCDF")
    xr.Dataset({"speed": (("time",), np.zeros(3))}, coords={"time": [0.0, 0.1, 0.2]}).to_netcdf(tmp_path / "x.nc")
    with pytest.raises(ValueError, match="not a netCDF dataset"):
        tracks.read(tmp_path / "notes.nc")
    with pytest.raises(ValueError, match=r"not a movement poses dataset \(no space, individuals, position\)"):
        tracks.read(tmp_path / "x.nc")
