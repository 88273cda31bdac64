"""Attacks with a known answer, for validating :mod:`pursuit_bench.study.guidance`: a pursuer
following one law in continuous time (1 ms Euler steps, written apart from the fitting code's
simulation), against a target weaving at random, sampled at 10 Hz with position noise.

The pursuer starts 2.0–2.8 from the target, heading 0.5–0.9 rad across the line of sight (so
every law has to turn it), at a speed of 1.2 ± 0.2 varying over time (the fit must use the
measured speed); the target turns sinusoidally at 0.5–0.8 units/s. A delayed law reads the
state at t − τ, the state at t = 0 before that exists. The attack ends when the pursuer is
within :data:`CATCH` of the target or at ``duration``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Distance at which an attack ends in a catch.
CATCH = 0.05
#: The fine time step of the continuous-time pursuer (seconds).
FINE = 0.001


@dataclass(frozen=True)
class TrueLaw:
    """The law a synthetic pursuer follows."""

    law: str
    """``"none"``, ``"pp"``, ``"pn"``, ``"mixed"`` or ``"parallel"``."""
    n_gain: float = 0.0
    """N (unitless)."""
    k_gain: float = 0.0
    """K (1/s)."""
    delay: float = 0.0
    """τ (seconds)."""


def attack(
    true: TrueLaw, seed: int, dt: float = 0.1, duration: float = 4.0, noise: float = 0.001
) -> tuple[np.ndarray, np.ndarray]:
    """One attack by ``true``: (pursuer, target) positions (T, 2) sampled every ``dt``, the
    pursuer's with Gaussian noise of ``noise`` per coordinate."""
    rng = np.random.default_rng(seed)
    steps = round(duration / FINE)
    every = round(dt / FINE)
    lag = round(true.delay / FINE)
    target_speed = rng.uniform(0.7, 1.0)
    amplitude, frequency, phase = rng.uniform(0.5, 1.0), rng.uniform(1.0, 2.0), rng.uniform(0, 2 * np.pi)
    bearing = rng.uniform(-np.pi, np.pi)
    target = np.array([0.0, 0.0]) + rng.uniform(2.2, 3.0) * np.array([np.cos(bearing), np.sin(bearing)])
    target_heading = rng.uniform(-np.pi, np.pi)
    position = np.zeros(2)
    heading = bearing + rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 0.9)
    speed_phase = rng.uniform(0, 2 * np.pi)
    pursuers, targets = [position.copy()], [target.copy()]
    lines: list[float] = []
    headings: list[float] = []
    target_velocities: list[np.ndarray] = []
    speeds: list[float] = []
    for step in range(steps):
        t = step * FINE
        offset = target - position
        if np.hypot(*offset) < CATCH:
            break
        turn = amplitude * frequency * np.cos(frequency * t + phase)
        velocity_t = target_speed * np.array([np.cos(target_heading), np.sin(target_heading)])
        speed = 1.2 + 0.2 * np.sin(0.7 * t + speed_phase)
        lines.append(np.arctan2(offset[1], offset[0]))
        target_velocities.append(velocity_t)
        speeds.append(speed)
        i = max(step - lag, 0)
        if true.law == "parallel":
            across = -target_velocities[i][0] * np.sin(lines[i]) + target_velocities[i][1] * np.cos(lines[i])
            heading = lines[i] + np.arcsin(np.clip(across / speeds[i], -1.0, 1.0))
        elif true.law != "none":
            rate = np.angle(np.exp(1j * (lines[i] - lines[i - 1]))) / FINE if i > 0 else 0.0
            deviation = np.angle(np.exp(1j * (lines[i] - (headings[i] if i < len(headings) else heading))))
            heading = heading + FINE * (true.n_gain * rate + true.k_gain * deviation)
        headings.append(heading)
        position = position + FINE * speed * np.array([np.cos(heading), np.sin(heading)])
        target = target + FINE * velocity_t
        target_heading += FINE * turn
        pursuers.append(position.copy())
        targets.append(target.copy())
    pursuer, target_path = np.array(pursuers)[::every], np.array(targets)[::every]
    return pursuer + rng.normal(scale=noise, size=pursuer.shape), target_path
