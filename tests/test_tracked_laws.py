"""``law --tracks`` (issue 66): pursuit laws fitted to tracks in movement's format. Known answers
first: synthetic pursuers following each law at 30 Hz with tracking noise, resampled to 10 Hz,
must be fitted the law they follow; gaps split a track and are reported; what cannot be used is
refused in one line."""

import json
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run_cli

from pursuit_bench.laws import synthetic_attacks, tracked_laws

load_poses = pytest.importorskip("movement.io.load_poses")
pytestmark = pytest.mark.filterwarnings("ignore:numpy.ndarray size changed:RuntimeWarning")  # netCDF4's wheel

LAWS = {
    "pp": synthetic_attacks.TrueLaw("pp", k_gain=3.0),
    "pn": synthetic_attacks.TrueLaw("pn", n_gain=3.0, delay=0.1),
    "parallel": synthetic_attacks.TrueLaw("parallel"),
}


def tracked(true: synthetic_attacks.TrueLaw, seed: int, fps: float = 30.0, noise: float = 0.003) -> tuple:
    """One synthetic attack as a tracker would give it: (time, space, keypoints, individuals)
    positions of a "hawk" and a "pigeon", with Gaussian tracking noise on both."""
    pursuer, target = synthetic_attacks.attack(true, seed, dt=1 / fps, duration=4.0, noise=0.0)
    rng = np.random.default_rng(1000 + seed)
    both = np.stack([pursuer, target], axis=-1) + rng.normal(scale=noise, size=(len(pursuer), 2, 2))
    return both[:, :, None, :]


def dataset(position: np.ndarray, fps: float = 30.0, names: tuple[str, ...] = ("hawk", "pigeon")):
    return load_poses.from_numpy(
        position, individual_names=list(names), keypoint_names=["centroid"], fps=fps, source_software="synthetic"
    )


@pytest.mark.slow
@pytest.mark.parametrize("law", LAWS)
def test_a_synthetic_pursuer_is_fitted_the_law_it_follows(tmp_path: Path, law: str) -> None:
    """Three attacks a law: the law is chosen in most (parallel navigation and proportional
    navigation of N 3 are close at 10 Hz: one of three may go to pn, as in docs/pursuit-law.md's
    validation on the env's own sampling)."""
    chosen = []
    for seed in range(3):
        path = tmp_path / f"{law}-{seed}.nc"
        dataset(tracked(LAWS[law], seed)).to_netcdf(path)
        code, output = run_cli("law", "--tracks", str(path), "--pursuer", "hawk", "--target", "pigeon")
        assert code == 0, output
        assert "resampled from one sample every 0.0333333 s to the env's 0.1 s" in output
        result = json.loads((tmp_path / "law-tracks.json").read_text())
        assert result["resampled_to_s"] == 0.1 and result["pieces"] == 1
        chosen += result["attacks"]["chosen"]
    assert chosen.count(law) >= 2, chosen


def test_a_gap_splits_the_track_and_is_reported() -> None:
    position = tracked(LAWS["pp"], 0, fps=10.0)
    assert len(position) >= 30
    position[14:17] = np.nan  # the tracker lost both for 0.3 s
    result = tracked_laws.fit_tracks(dataset(position, fps=10.0), "hawk", "pigeon")
    assert result["resampled_to_s"] is None
    assert [(s["first"], s["last"]) for s in result["stretches"]] == [(0, 13), (17, len(position) - 1)]
    assert result["pieces"] == 2  # one attack each side of the gap: none spans it


def test_the_resampling_keeps_a_line_and_misses_a_time_beside_a_missing_sample() -> None:
    at = np.array([0.0, 0.04, 0.08, 0.12, 0.16, 0.20, 0.24])
    track = np.stack([at * 2.0, -at], axis=1)
    assert np.allclose(tracked_laws.resampled(track, at), [[0.0, 0.0], [0.2, -0.1], [0.4, -0.2]])
    track[3] = np.nan  # 0.12 s: the grid's 0.1 s lies between 0.08 and it
    out = tracked_laws.resampled(track, at)
    assert np.allclose(out[[0, 2]], [[0.0, 0.0], [0.4, -0.2]]) and np.isnan(out[1]).all()


def test_what_cannot_be_fitted_is_refused_in_one_line(tmp_path: Path) -> None:
    position = tracked(LAWS["pp"], 0)
    dataset(position).to_netcdf(tmp_path / "ok.nc")
    dataset(position[:, :, :, :1], names=("hawk",)).to_netcdf(tmp_path / "one.nc")
    lost = position.copy()
    lost[:, :, :, 1] = np.nan
    dataset(lost).to_netcdf(tmp_path / "lost.nc")
    (tmp_path / "notes.nc").write_text("not netCDF")
    cases = [
        ("one.nc", "hawk", "pigeon", "holds one individual"),
        ("lost.nc", "hawk", "pigeon", "pigeon's track is missing at every time"),
        ("ok.nc", "hawk", "sparrow", "no individual 'sparrow' in the dataset; it holds hawk, pigeon"),
        ("notes.nc", "hawk", "pigeon", "not a netCDF dataset"),
        ("missing.nc", "hawk", "pigeon", "no such file"),
    ]
    for name, pursuer, target, message in cases:
        code, output = run_cli("law", "--tracks", str(tmp_path / name), "--pursuer", pursuer, "--target", target)
        assert code == 2 and message in output and len(output.strip().splitlines()) == 1, (name, output)
    code, output = run_cli("law", "--tracks", str(tmp_path / "ok.nc"))
    assert code == 2 and "--tracks needs --pursuer NAME and --target NAME" in output
