"""Perturbed worlds and senses for robustness tests (docs/robustness.md): named, composable
options of evaluation, each with one definition, applied alike to every variant of the
paper's protocol (the trained predator and the baselines put in its place play the same
perturbed episodes on the same seeds).

- ``obs-noise=σ``: Gaussian noise of standard deviation σ (arena units) added to every
  position and velocity feature of every agent's observation (not to obstacle range readings);
- ``delay=k``: every agent observes the world as it was k steps before (at an episode's start,
  its first observation);
- ``act-noise=p``: with probability p an agent's chosen direction is replaced by one of its two
  neighbours (30° off), each as likely;
- ``damping=f``, ``predator-accel=f``, ``prey-accel=f``: the world's damping, the predators' and
  the prey's accelerations times f (task options, :class:`~pursuit_bench.env.conditions.TaskConfig`);
- ``obstacles=N``: N obstacles in the world of agents trained without them; their observations
  stay as trained (no range readings), the physics holds them back.

Senses and actions are a wrapper of the batched env (:class:`PerturbedEnv`); the world's
changes are task options. Each at its neutral value (0, or 1 for a factor) is exactly the
unperturbed evaluation.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from pursuit_bench.env import task
from pursuit_bench.env.conditions import MAX_OBSTACLES
from pursuit_bench.env.vector import VectorPursuitEnv


@dataclass(frozen=True)
class Perturbations:
    """The perturbations of one evaluation; every field at its neutral value is none."""

    obs_noise: float = 0.0
    """Standard deviation of the noise on positions and velocities (arena units), >= 0."""
    delay: int = 0
    """Steps by which every observation lags the world, >= 0."""
    act_noise: float = 0.0
    """Probability that a chosen direction is replaced by a neighbouring one, 0 to 1."""
    damping: float = 1.0
    """Factor on the world's damping (0 to 4)."""
    predator_accel: float = 1.0
    """Factor on the predators' accelerations (0 to 4)."""
    prey_accel: float = 1.0
    """Factor on the prey's acceleration (0 to 4)."""
    obstacles: int = 0
    """Obstacles hidden from agents trained without them (0 to 8)."""

    def __post_init__(self) -> None:
        for f in fields(self):
            name, value = cli_name(f.name), getattr(self, f.name)
            low, high = RANGES[f.name]
            integral = f.name in INTEGRAL
            if isinstance(value, bool) or not isinstance(value, int if integral else (int, float)):
                raise ValueError(f"{name}={value!r}: expected {'an integer' if integral else 'a number'}")
            if not low <= value <= high:
                raise ValueError(f"{name}={value!r}: expected a value from {low} to {high}")

    @classmethod
    def parse(cls, specs: Iterable[str]) -> Perturbations:
        """From ``NAME=VALUE`` strings (the CLI's ``--perturb``); ValueError naming the accepted
        names and values for a bad one, or a name given twice."""
        given: dict[str, Any] = {}
        names = {cli_name(f.name): f.name for f in fields(cls)}
        for spec in specs:
            name, sep, text = spec.partition("=")
            if not sep or name.strip() not in names:
                raise ValueError(f"--perturb {spec!r}: expected NAME=VALUE with NAME one of {', '.join(names)}")
            key = names[name.strip()]
            if key in given:
                raise ValueError(f"--perturb {name}: given twice")
            integral = key in INTEGRAL
            try:
                given[key] = int(text) if integral else float(text)
            except ValueError:
                kind = "an integer" if integral else "a number"
                raise ValueError(f"--perturb {spec!r}: {text!r} is not {kind}") from None
        try:
            return cls(**given)
        except ValueError as error:
            raise ValueError(f"--perturb {error}") from None

    @property
    def changed(self) -> dict[str, float]:
        """The perturbations away from their neutral values, by CLI name."""
        neutral = Perturbations()
        return {
            cli_name(f.name): getattr(self, f.name)
            for f in fields(self)
            if getattr(self, f.name) != getattr(neutral, f.name)
        }

    @property
    def tag(self) -> str:
        """A file-name tag for these perturbations, e.g. ``obs-noise0.05_delay2`` (``none``)."""
        return "_".join(f"{name}{value:g}" for name, value in self.changed.items()) or "none"

    def task_options(self) -> dict[str, Any]:
        """The world's changes as task options (only those away from neutral)."""
        options: dict[str, Any] = {}
        for key, option in (
            ("damping", "damping_factor"),
            ("predator_accel", "predator_accel_factor"),
            ("prey_accel", "prey_accel_factor"),
            ("obstacles", "obstacles"),
        ):
            if getattr(self, key) != getattr(Perturbations(), key):
                options[option] = getattr(self, key)
        return options

    @property
    def senses(self) -> bool:
        """Whether the senses or actions are perturbed (the env needs :class:`PerturbedEnv`)."""
        return bool(self.obs_noise or self.delay or self.act_noise or self.obstacles)


#: The fields that count steps or obstacles: integers.
INTEGRAL = ("delay", "obstacles")
#: Each field's accepted range.
RANGES: dict[str, tuple[float, float]] = {
    "obs_noise": (0.0, 1.0),
    "delay": (0, 50),
    "act_noise": (0.0, 1.0),
    "damping": (0.0, 4.0),
    "predator_accel": (0.0, 4.0),
    "prey_accel": (0.0, 4.0),
    "obstacles": (0, MAX_OBSTACLES),
}


def cli_name(field: str) -> str:
    """``obs_noise`` -> ``obs-noise``."""
    return field.replace("_", "-")


class PerturbedEnv:
    """A :class:`VectorPursuitEnv` whose agents sense and act through the perturbations:
    observations delayed, then noised, then cut to the size the agents trained with (hidden
    obstacles: no range readings); chosen directions jittered before the world takes them.
    Noise comes from its own generators, seeded by the evaluation's seed, so every variant of
    the protocol starts from the same draws. Continuous actions are not supported."""

    def __init__(self, env: VectorPursuitEnv, perturbations: Perturbations, seed: int) -> None:
        if env.config.continuous:
            raise ValueError("perturbations: the discrete task only (continuous=True given)")
        self.env = env
        self.perturbations = perturbations
        self.num_envs, self.n_agents, self.agents = env.num_envs, env.n_agents, env.agents
        self.config, self.core = env.config, env.core
        #: The observation the agents see: without range readings when the obstacles are hidden.
        self.obs_size = task.obs_size(env.n_agents) if perturbations.obstacles else env.obs_size
        self._noisy = task.obs_size(env.n_agents)  # positions and velocities come first
        self._obs_rng = np.random.default_rng([seed, 1])
        self._act_rng = np.random.default_rng([seed, 2])
        self._history: np.ndarray | None = None  # (delay + 1, B, n, F), a ring: the newest at _newest
        self._newest = 0

    def reset(self, seed: int | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        obs, info = self.env.reset(seed=seed)
        self._history = np.repeat(obs[None], self.perturbations.delay + 1, axis=0)
        self._newest = 0
        return self._sensed(), info

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        p = self.perturbations
        if p.act_noise:
            actions = np.array(actions, copy=True)
            jitter = self._act_rng.random(actions.shape[:2]) < p.act_noise
            side = np.where(self._act_rng.random(actions.shape[:2]) < 0.5, -1, 1)
            actions[..., 1] = np.where(jitter, (actions[..., 1] + side) % task.N_DIRECTIONS, actions[..., 1])
        obs, rewards, terminated, truncated, info = self.env.step(actions)
        assert self._history is not None, "reset() first"
        self._newest = (self._newest + 1) % len(self._history)
        self._history[self._newest] = obs
        started = info["done"]
        self._history[:, started] = obs[started]  # a new episode remembers nothing older
        return self._sensed(), rewards, terminated, truncated, info

    def _sensed(self) -> np.ndarray:
        assert self._history is not None
        oldest = (self._newest + 1) % len(self._history)
        obs = self._history[oldest][..., : self.obs_size].copy()
        if self.perturbations.obs_noise:
            noise = self._obs_rng.normal(0.0, self.perturbations.obs_noise, obs[..., : self._noisy].shape)
            obs[..., : self._noisy] += noise.astype(obs.dtype)
        return obs
