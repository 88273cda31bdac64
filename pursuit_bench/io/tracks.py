"""Trajectories in the format animal-tracking tools use: ``movement``'s poses datasets (xarray:
``position`` over ``time``, ``space``, ``keypoints`` and ``individuals``; netCDF on disk), the
neuroinformatics community's toolbox that reads DeepLabCut, SLEAP and other trackers' files.

An episode is one dataset, and one file: movement's datasets have exactly those four dimensions
and its functions (kinematics, filters) assume them, so episodes are not stacked along a fifth.
Each agent is an individual named by its role (``predator_0`` …, ``prey_0``) with one keypoint,
``centroid`` (a disk's centre); time in seconds at the env's 10 Hz (``fps`` 10); ``mode`` is a
data variable of its own (time, individuals): 1 chase, 0 stalk, NaN for the prey and at the
start, where no step has been taken. Needs the ``animals`` extra (movement)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

#: What the files say made them (movement's ``source_software``).
SOURCE = "pursuit-bench"
KEYPOINT = "centroid"


def episode_dataset(
    positions: np.ndarray, modes: np.ndarray, names: list[str], fps: float, attrs: Mapping[str, Any] | None = None
) -> Any:
    """A movement poses dataset of one episode: ``positions`` (T + 1, n, 2) from the start state,
    ``modes`` (T, n − 1) the predators' mode in each step, ``names`` the agents (prey last)."""
    from movement.io import load_poses

    n = len(names)
    position = np.asarray(positions, dtype=float).transpose(0, 2, 1)[:, :, None, :]  # (time, space, 1, n)
    dataset = load_poses.from_numpy(
        position,
        confidence_array=np.ones((len(positions), 1, n)),  # simulated: every position is known
        individual_names=list(names),
        keypoint_names=[KEYPOINT],
        fps=fps,
        source_software=SOURCE,
    )
    mode = np.full((len(positions), n), np.nan)
    mode[1:, : n - 1] = np.asarray(modes, dtype=float)
    dataset["mode"] = (("time", "individuals"), mode)
    dataset["mode"].attrs["meaning"] = "1 chase, 0 stalk, in the step that ended at this time; NaN for the prey"
    dataset.attrs.update({k: v for k, v in (attrs or {}).items() if v is not None})
    return dataset


def write(dataset: Any, path: Path) -> None:
    """``dataset`` as netCDF at ``path`` (movement's own format: ``xarray.open_dataset`` reads it)."""
    dataset.to_netcdf(path)


def read(path: Path) -> Any:
    """A movement poses dataset from ``path``, checked by movement's own validator
    (``ValidPosesInputs``); ValueError in one line for a file it cannot use."""
    import xarray as xr
    from movement.validators.datasets import ValidPosesInputs

    try:
        dataset = xr.load_dataset(path)
    except (OSError, ValueError) as error:  # xarray's message runs over lines: its first says it
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise ValueError(f"not a netCDF dataset ({first.removeprefix(str(path)).strip(': ')})") from None
    missing = [d for d in ("time", "space", "individuals") if d not in dataset.dims] + (
        [] if "position" in dataset else ["position"]
    )
    if missing:
        raise ValueError(f"not a movement poses dataset (no {', '.join(missing)})")
    try:
        ValidPosesInputs(
            position_array=dataset["position"].transpose("time", "space", "keypoints", "individuals").values,
            confidence_array=dataset["confidence"].values if "confidence" in dataset else None,
            individual_names=[str(i) for i in dataset["individuals"].values],
            keypoint_names=[str(k) for k in dataset["keypoints"].values],
            fps=dataset.attrs.get("fps"),
            source_software=dataset.attrs.get("source_software"),
        )
    except (TypeError, ValueError) as error:
        raise ValueError(f"movement's validator refuses it ({' '.join(str(error).split())})") from None
    return dataset
