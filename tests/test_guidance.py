"""Pursuit-law fits against known answers: pursuits made by each law, in discrete steps and in
continuous time sampled at 10 Hz, with noise; degenerate inputs refused."""

import json
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run_cli

from pursuit_bench import guidance
from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.evaluate import run_episodes
from pursuit_bench.policies import FleeingPrey, PurePursuitPredator

DT = 0.1


def manoeuvring_target(t: np.ndarray) -> np.ndarray:
    """A target weaving across the arena at about 0.7 units/s."""
    return np.stack([-0.2 + 0.5 * t, 0.6 * np.sin(1.3 * t)], axis=1)


def law_pursuit(n_gain: float, k_gain: float, delay: float, step: float, duration: float) -> np.ndarray:
    """A naive reference: the law ω = N λ̇ + K δ integrated by Euler steps of ``step`` seconds
    at a constant speed of 1.2 from (−1.2, −1.0), heading 1.5 rad, the delayed state read from the
    past (held at the start before it exists), until the pursuer is within 0.05 of the target.
    Returns (pursuer, target) at every step."""
    times = np.arange(0.0, duration + 1e-9, step)
    target = manoeuvring_target(times)
    lag = round(delay / step)
    position = np.array([-1.2, -1.0])
    heading = 1.5  # across the line of sight: the law has to turn the pursuer
    positions, headings, lines = [], [], []
    for t in range(len(times)):
        positions.append(position.copy())
        if np.linalg.norm(target[t] - position) < 0.05:  # caught: the pursuit ends
            break
        los = np.arctan2(*(target[t] - position)[::-1])
        lines.append(los)
        headings.append(heading)
        i = max(t - lag, 0)
        previous = lines[i - 1] if i > 0 else lines[0]
        los_rate = np.angle(np.exp(1j * (lines[i] - previous))) / step
        between = headings[i] - np.angle(np.exp(1j * (headings[i] - headings[i - 1]))) / 2 if i > 0 else headings[i]
        deviation = np.angle(np.exp(1j * (lines[i] - between)))
        heading = heading + step * (n_gain * los_rate + k_gain * deviation)
        position = position + step * 1.2 * np.array([np.cos(headings[-1]), np.sin(headings[-1])])
    return np.array(positions), target[: len(positions)]


def sampled(n_gain: float, k_gain: float, delay: float, fine: bool, seed: int) -> tuple[np.ndarray, np.ndarray]:
    step = 0.001 if fine else DT
    pursuer, target = law_pursuit(n_gain, k_gain, delay, step, 3.0)
    every = round(DT / step)
    pursuer, target = pursuer[::every], target[::every]
    noise = np.random.default_rng(seed).normal(scale=0.001, size=pursuer.shape)  # 0.05 % of the arena
    return pursuer + noise, target


CASES = [("pp", 0.0, 3.0, 0.0), ("pp", 0.0, 2.0, 0.2), ("pn", 3.0, 0.0, 0.0), ("pn", 4.0, 0.0, 0.1)]
CASES += [("mixed", 2.5, 2.0, 0.1)]


@pytest.mark.parametrize(("law", "n_gain", "k_gain", "delay"), CASES)
def test_gains_and_delays_of_discrete_pursuits_are_recovered(law: str, n_gain: float, k_gain: float, delay: float):
    pursuer, target = sampled(n_gain, k_gain, delay, fine=False, seed=1)
    fits = guidance.fit_all(pursuer, target, DT)
    result = fits[law]
    for name, true in (("N", n_gain), ("K", k_gain)):
        if name in result.gains:
            assert result.gains[name] == pytest.approx(true, rel=0.10), result
    assert result.delay == pytest.approx(delay)
    assert result.r2 > 0.99 and result.error < 0.01
    assert guidance.winner(fits) == law, {k: f.error for k, f in fits.items()}


@pytest.mark.parametrize(("law", "n_gain", "k_gain", "delay"), CASES)
def test_continuous_pursuits_sampled_at_10_hz_are_recovered(law: str, n_gain: float, k_gain: float, delay: float):
    pursuer, target = sampled(n_gain, k_gain, delay, fine=True, seed=2)
    fits = guidance.fit_all(pursuer, target, DT)
    result = fits[law]
    for name, true in (("N", n_gain), ("K", k_gain)):
        if name in result.gains:
            assert result.gains[name] == pytest.approx(true, rel=0.25), result
    assert abs(result.delay - delay) <= DT + 1e-9
    if law == "mixed":
        assert guidance.winner(fits) == "mixed", {k: f.error for k, f in fits.items()}
    else:  # the right single law wins; the mixed one, holding it, may fit the sampling a little better
        assert min(("pp", "pn"), key=lambda k: fits[k].error) == law, {k: f.error for k, f in fits.items()}


def test_simulate_reproduces_the_reference_exactly_without_noise() -> None:
    pursuer, target = law_pursuit(3.0, 1.0, 0.2, DT, 3.0)
    simulated = guidance.simulate("mixed", {"N": 3.0, "K": 1.0}, 0.2, pursuer, target, DT)
    np.testing.assert_allclose(simulated, pursuer, atol=1e-9)


def test_the_pure_pursuit_predator_is_best_described_by_proportional_pursuit() -> None:
    positions: list[np.ndarray] = []
    run_episodes(
        "1p-high",
        {
            "predator_0": ScriptedAgent("predator_0", PurePursuitPredator()),
            "prey_0": ScriptedAgent("prey_0", FleeingPrey()),
        },
        1,
        seed=4,
        num_envs=1,
        on_step=lambda obs, actions, done: positions.append(obs[0, :, 0:2].copy()),
    )
    track = np.array(positions)  # (T, agents, 2): each agent's own position as it observes it
    assert len(track) >= 10
    fits = guidance.fit_all(track[:, 0], track[:, 1], DT)
    assert guidance.winner(fits) == "pp", {k: (f.error, f.gains) for k, f in fits.items()}
    assert fits["pp"].r2 > 0.9


def test_a_straight_line_target_gets_an_answer() -> None:
    times = np.arange(0, 2.0, DT)
    target = np.stack([0.5 * times, np.full_like(times, 0.5)], axis=1)
    pursuer = np.stack([0.9 * times - 0.5, 0.5 * times - 0.5], axis=1)
    for result in guidance.fit_all(pursuer, target, DT).values():
        assert np.isfinite(result.error) and np.isfinite(result.r2)
        assert all(np.isfinite(v) for v in result.gains.values())


def test_degenerate_input_is_refused_with_a_reason() -> None:
    good = np.cumsum(np.ones((10, 2)) * 0.1, axis=0)
    with pytest.raises(ValueError, match="at least 5"):
        guidance.fit(good[:4], good[:4], DT, "pp")
    with pytest.raises(ValueError, match="does not move"):
        guidance.fit(np.zeros((10, 2)), good, DT, "pp")
    broken = good.copy()
    broken[3, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        guidance.fit(broken, good, DT, "pn")
    with pytest.raises(ValueError, match="law='xx'"):
        guidance.fit(good, good + 1, DT, "xx")
    with pytest.raises(ValueError, match="multiple of dt"):
        guidance.simulate("pp", {"K": 1.0}, 0.15, good, good + 1, DT)
    with pytest.raises(ValueError, match="expected two"):
        guidance.fit(good, good[:, :1], DT, "pp")


def test_the_law_command_on_a_run_and_on_a_sweep(tmp_path: Path) -> None:
    sweep = tmp_path / "s"
    code, output = run_cli(
        "sweep", "--conditions", "1p-low", "--seeds", "2", "--episodes", "6", "--eval-episodes", "4",
        "--workers", "1", "--no-record", "--out", str(sweep),
    )  # fmt: skip
    assert code == 0, output
    run = sweep / "runs" / "1p-low-hierarchical-seed0"
    code, output = run_cli("law", str(run), "--episodes", "4")
    assert code == 0, output
    result = json.loads((run / "law.json").read_text())
    assert set(result["kinds"]) == {"hierarchical", "always_chase", "always_stalk", "pure_pursuit"}
    fits = result["kinds"]["hierarchical"]["predator_0"]
    assert fits["pursuits"] == len(fits["laws"]["pp"]["gains"]["K"]) and set(fits["wins"]) == {"pp", "pn", "mixed"}
    assert (run / "law.png").stat().st_size > 10_000
    code, output = run_cli("law", str(sweep), "--episodes", "3")
    assert code == 0 and "1p-low hierarchical: best law" in output, output
    summary = json.loads((sweep / "law.json").read_text())["summary"]
    assert set(summary["1p-low"]["hierarchical"]["laws"]) == {"pp", "pn", "mixed"}
    code, output = run_cli("law", str(tmp_path / "nothing"))
    assert code == 2 and "no such run folder" in output
