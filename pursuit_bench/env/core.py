"""One task in B arenas: the world, the task rules and the step counters, batched.

The PettingZoo env is this core at ``B = 1``; the batched env is the same core at any ``B``.
Everything here is arrays shaped ``(B, n_agents, …)``; no dicts of agent names.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pursuit_bench.env import task
from pursuit_bench.env.conditions import TaskConfig
from pursuit_bench.env.obstacles import place_obstacles
from pursuit_bench.env.world import DAMPING, DT, Backend, Contacts, make_world

#: Start layouts an arena draws from its generator at a time (see ``PursuitCore._draw_starts``).
STARTS_AHEAD = 16


@dataclass
class StepResult:
    """What one step of B arenas produced (all arrays have the arena axis first)."""

    observations: np.ndarray
    """(B, n_agents, 6n-2) float32."""
    rewards: np.ndarray
    """(B, n_agents) float64."""
    terminated: np.ndarray
    """(B,) bool."""
    captured: np.ndarray
    """(B,) bool: some predator overlaps the prey."""
    truncated: np.ndarray
    """(B,) bool: the step limit was reached without termination."""
    contacts: Contacts
    modes: np.ndarray
    """(B, n_predators) the modes used this step."""
    distance_to_prey: np.ndarray
    """(B, n_agents) each predator's distance to the prey, the prey's to its nearest predator."""


class PursuitCore:
    """B arenas of one task. ``reset`` some arenas, ``step`` all of them."""

    def __init__(
        self, config: TaskConfig, num_arenas: int = 1, *, backend: Backend = "pymunk", blocks: list[int] | None = None
    ) -> None:
        if isinstance(num_arenas, bool) or not isinstance(num_arenas, int) or num_arenas < 1:
            raise ValueError(f"num_envs={num_arenas!r}: expected an integer >= 1")
        self.config = config
        self.num_arenas = num_arenas
        self.world = make_world(
            backend, num_arenas, config.n_agents, wall_rule=config.wall_rule, obstacles=config.obstacles, blocks=blocks
        )
        self.steps = np.zeros(num_arenas, dtype=np.int64)
        # the dynamics factors (robustness tests), fixed by the config: None where unchanged
        scale = np.full(config.n_agents, config.predator_accel_factor)
        scale[-1] = config.prey_accel_factor
        self._accel_scale = scale[None, :, None] if np.any(scale != 1.0) else None
        self._extra_damping = (config.damping_factor - 1.0) * DAMPING if config.damping_factor != 1.0 else None
        self._los = np.zeros((num_arenas, config.n_agents, 2))  # LOS at the current positions
        # start layouts (and their obstacles) drawn ahead, per arena, with the generator they came from
        self._starts: dict[int, tuple[np.random.Generator, list[tuple[np.ndarray, np.ndarray]]]] = {}

    @property
    def obstacles(self) -> np.ndarray | None:
        """(B, K, 3) every arena's obstacles (x, y, radius), or None in a task without them."""
        return self.world.obstacles if self.config.obstacles else None

    def reset(
        self,
        arenas: np.ndarray,
        rngs: list[np.random.Generator],
        positions: np.ndarray | None = None,
        obstacles: np.ndarray | None = None,
    ) -> np.ndarray:
        """Start the given arenas afresh: positions (and obstacles) drawn each from its own
        generator, or given (``positions`` (len(arenas), n_agents, 2), checked by
        :func:`task.check_positions`; ``obstacles`` (len(arenas), K, 3) with them, taken as
        they are). Returns the observations of those arenas (len(arenas), n_agents, n_obs)."""
        if positions is None:
            starts, placed = self._draw_starts(arenas, rngs)
        else:
            starts = task.check_positions(positions, (len(arenas), self.config.n_agents, 2))
            placed = self._given_obstacles(obstacles, len(arenas)) if self.config.obstacles else None
        self.world.reset(arenas, starts, placed)
        self.steps[arenas] = 0
        obs, self._los[arenas] = task.observe(starts, np.zeros_like(starts), placed)
        return obs

    def _given_obstacles(self, obstacles: np.ndarray | None, count: int) -> np.ndarray:
        shape = (count, self.config.obstacles, 3)
        arr = np.asarray(obstacles, dtype=np.float64) if obstacles is not None else None
        if arr is None or arr.shape != shape or not np.isfinite(arr).all():
            raise ValueError(f"obstacles: expected finite numbers of shape {shape} with the positions")
        return arr

    def _draw_starts(self, arenas: np.ndarray, rngs: list[np.random.Generator]) -> tuple[np.ndarray, np.ndarray | None]:
        """The next start layout (and obstacles, in a task with them) of each arena. Each arena
        draws ``STARTS_AHEAD`` layouts at a time from its own generator (one call instead of one
        per episode), their obstacles after them, and uses them in order; a new generator (a
        reseed) discards what the old one drew."""
        config = self.config
        starts = np.empty((len(arenas), config.n_agents, 2))
        placed = np.empty((len(arenas), config.obstacles, 3))
        for k, (arena, rng) in enumerate(zip(arenas.tolist(), rngs, strict=True)):
            owner, ahead = self._starts.get(arena, (None, []))
            if owner is not rng or not ahead:
                ahead = self._draw_ahead(rng)
                self._starts[arena] = (rng, ahead)
            starts[k], placed[k] = ahead.pop()
        return starts, (placed if config.obstacles else None)

    def _draw_ahead(self, rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
        """``STARTS_AHEAD`` start layouts and their obstacles drawn from ``rng``, last first."""
        config = self.config
        layouts = task.start_layouts(rng, config.n_agents, STARTS_AHEAD)
        if config.obstacles:
            around = place_obstacles(rng, layouts, config.obstacles, config.obstacle_radius)
        else:
            around = np.empty((len(layouts), 0, 3))
        return list(zip(layouts, around, strict=True))[::-1]

    def first_start(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """The start layout (n_agents, 2) and obstacles (K, 3) an arena given the fresh generator
        ``rng`` starts its next episode from (``reset`` draws them so): what an evaluation with
        common random numbers draws once per episode for every arena that plays it."""
        return self._draw_ahead(rng)[-1]

    def state_dict(self) -> dict[str, Any]:
        """The arenas as they are mid-episode (for a checkpoint): the world, the step counts,
        the lines of sight and each arena's start layouts drawn ahead."""
        return {
            "world": self.world.snapshot(),
            "steps": self.steps.copy(),
            "los": self._los.copy(),
            "starts": {
                arena: [[layout, placed] for layout, placed in ahead] for arena, (_, ahead) in self._starts.items()
            },
        }

    def load_state_dict(self, state: dict[str, Any], rngs: list[np.random.Generator]) -> None:
        """Put back :meth:`state_dict`; ``rngs``: each arena's generator, which drew its layouts."""
        self.world.restore(state["world"])
        self.steps = np.array(state["steps"], dtype=np.int64)
        self._los = np.array(state["los"], dtype=np.float64)
        self._starts = {
            int(arena): (rngs[int(arena)], [(np.asarray(layout), np.asarray(placed)) for layout, placed in ahead])
            for arena, ahead in state["starts"].items()
        }

    def state(self) -> np.ndarray:
        """(B, 4 n_agents [+ 3 K]) float32 global state: ``[x, y, vx, vy]`` per agent, world
        frame, then ``[x, y, radius]`` per obstacle in a task with obstacles."""
        w = self.world
        parts = [np.concatenate([w.positions, w.velocities], axis=-1).reshape(self.num_arenas, -1)]
        if self.config.obstacles:
            parts.append(w.obstacles.reshape(self.num_arenas, -1))
        return np.concatenate(parts, axis=-1).astype(np.float32)

    def step(self, modes: np.ndarray, directions: np.ndarray) -> StepResult:
        """Advance every arena by one step; ``modes`` (B, n_predators), ``directions`` (B, n_agents)."""
        return self._advance(task.accelerations(self._los, modes, directions), modes)  # LOS of the last observation

    def step_continuous(self, actions: np.ndarray) -> StepResult:
        """Advance every arena by one step of continuous actions (B, n_agents, 2), each in its
        agent's line-of-sight frame (``task.continuous_accelerations``)."""
        acc, modes = task.continuous_accelerations(self._los, actions, self.config.n_predators)
        return self._advance(acc, modes)

    def _shifted(self, acc: np.ndarray) -> np.ndarray:
        """The accelerations the world applies under the task's dynamics factors: each agent's
        scaled by its factor, and the damping shifted by an acceleration against the velocity
        (``(1 - f D) v + a DT == (1 - D) v + (a - (f - 1) D v / DT) DT``). Unchanged, the same
        array, when every factor is 1."""
        if self._accel_scale is not None:
            acc = acc * self._accel_scale
        if self._extra_damping is not None:
            acc = acc - self._extra_damping * self.world.velocities / DT
        return acc

    def _advance(self, acc: np.ndarray, modes: np.ndarray) -> StepResult:
        contacts = self.world.step(self._shifted(acc))
        self.steps += 1
        world = self.world
        done = task.finish_step(
            self.config, contacts, modes, self.steps, world.positions, world.velocities, self.obstacles
        )
        self._los = done.los
        return StepResult(
            observations=done.observations,
            rewards=done.outcome.rewards,
            terminated=done.outcome.terminated,
            captured=done.outcome.captured,
            truncated=done.truncated,
            contacts=contacts,
            modes=modes,
            distance_to_prey=done.distance_to_prey,
        )
