"""Attacks with a known answer, for validating :mod:`pursuit_bench.laws.guidance`: a pursuer
following one law in continuous time (1 ms Euler steps, written apart from the fitting code's
simulation), against a target weaving at random, sampled at 10 Hz with position noise.

The pursuer starts 2.2–3.0 from the target, heading 0.5–0.9 rad across the line of sight (so
every law has to turn it), at a speed of 1.2 ± 0.2 varying over time (the fit must use the
measured speed); the target moves at 0.7–1.0 units/s, turning sinusoidally. A delayed law reads
the state at t − τ, the state at t = 0 before that exists. The attack ends when the pursuer is
within :data:`CATCH` of the target or at ``duration``.

**A pursuer outside every fitted law** (the misspecification control, docs/pursuit-law.md):
with :attr:`TrueLaw.directions` > 0 the law's heading is only a *command*, flown as our
predators fly theirs (:mod:`pursuit_bench.env.world`, :mod:`pursuit_bench.rules.navigation`):
rounded to the nearest of ``directions`` directions spaced evenly around the line of sight
(12: 30° apart), held for :attr:`TrueLaw.hold` seconds (one env step), and followed by the
velocity with a first-order lag of time constant :attr:`TrueLaw.velocity_lag` (the env's
damping, a quarter of the velocity lost per 0.1 s step, is a lag of 0.1 / ln(4/3) ≈ 0.35 s).
None of the fitted laws holds quantised, held, lagged steering. Every draw of the generator is
the same with or without it, so a seed gives the same target and start either way.
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
    directions: int = 0
    """0: the law's heading is flown; > 0: it is a command rounded to the nearest of this many
    directions spaced evenly around the line of sight (see the module's text)."""
    hold: float = 0.0
    """With ``directions``: how long each rounded command is held (seconds; 0: re-rounded at
    every fine step)."""
    velocity_lag: float = 0.0
    """With ``directions``: the time constant of the velocity's first-order lag towards the
    commanded velocity (seconds; 0: no lag)."""

    def __post_init__(self) -> None:
        if self.law not in ("none", "pp", "pn", "mixed", "parallel"):
            raise ValueError(f"law={self.law!r}: expected none, pp, pn, mixed or parallel")
        if self.directions < 0 or self.hold < 0 or self.velocity_lag < 0 or self.delay < 0:
            raise ValueError(f"{self}: expected directions, hold, velocity_lag and delay >= 0")
        if not self.directions and (self.hold or self.velocity_lag):
            raise ValueError(f"{self}: hold and velocity_lag need directions > 0")

    @property
    def misspecified(self) -> bool:
        """Whether the pursuer flies outside every fitted law (quantised, held, lagged)."""
        return self.directions > 0


def attack(
    true: TrueLaw, seed: int, dt: float = 0.1, duration: float = 4.0, noise: float = 0.001
) -> tuple[np.ndarray, np.ndarray]:
    """One attack by ``true``: (pursuer, target) positions (T, 2) sampled every ``dt``, the
    pursuer's with Gaussian noise of ``noise`` per coordinate (see the module's text)."""
    rng = np.random.default_rng(seed)
    steps = round(duration / FINE)
    every = round(dt / FINE)
    lag = round(true.delay / FINE)
    hold = max(round(true.hold / FINE), 1)
    target_speed = rng.uniform(0.7, 1.0)
    amplitude, frequency, phase = rng.uniform(0.5, 1.0), rng.uniform(1.0, 2.0), rng.uniform(0, 2 * np.pi)
    bearing = rng.uniform(-np.pi, np.pi)
    target = np.array([0.0, 0.0]) + rng.uniform(2.2, 3.0) * np.array([np.cos(bearing), np.sin(bearing)])
    target_heading = rng.uniform(-np.pi, np.pi)
    position = np.zeros(2)
    heading = bearing + rng.choice([-1.0, 1.0]) * rng.uniform(0.5, 0.9)
    speed_phase = rng.uniform(0, 2 * np.pi)
    velocity = 1.2 * np.array([np.cos(heading), np.sin(heading)])
    command = velocity / 1.2
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
        if not true.misspecified:
            position = position + FINE * speed * np.array([np.cos(heading), np.sin(heading)])
        else:
            if step % hold == 0:  # the command: the law's heading rounded around the line of sight
                spacing = 2 * np.pi / true.directions
                rounded = lines[-1] + spacing * np.round(np.angle(np.exp(1j * (heading - lines[-1]))) / spacing)
                command = np.array([np.cos(rounded), np.sin(rounded)])
            relax = min(FINE / true.velocity_lag, 1.0) if true.velocity_lag > 0 else 1.0
            velocity = velocity + relax * (speed * command - velocity)
            position = position + FINE * velocity
        target = target + FINE * velocity_t
        target_heading += FINE * turn
        pursuers.append(position.copy())
        targets.append(target.copy())
    pursuer, target_path = np.array(pursuers)[::every], np.array(targets)[::every]
    return pursuer + rng.normal(scale=noise, size=pursuer.shape), target_path
