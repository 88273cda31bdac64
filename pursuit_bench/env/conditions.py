"""The paper's experimental conditions and the options that define a task.

Source: Tsutsui, Takeda, Fujii (2023), section 3.2: number of predators (1, 2, 3), cost of a
step in chase mode (0.01 "low", 0.1 "high") and prey sharing ("shared", "individual"). With one
predator sharing makes no difference, so the paper has ten conditions and 22 predator panels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

RewardSharing = Literal["shared", "individual"]
WallRule = Literal["terminate", "contain"]
#: Physics backends of the world: pymunk (the reference) or its numpy twin.
Backend = Literal["pymunk", "numpy"]

#: Cost of one step in chase mode, by name (paper 3.2). Stalk mode costs nothing.
CHASE_COSTS: dict[str, float] = {"low": 0.01, "high": 0.1}
#: Episode limit in steps: 30 s at dt = 0.1 s (paper 3.1). Reaching it *truncates* the episode.
MAX_STEPS = 300
MAX_PREDATORS = 3
#: Most obstacles an arena may hold (docs/spec.md, obstacles).
MAX_OBSTACLES = 8
#: Obstacle radii allowed: from 0.1 (a full-speed step, 0.144, is then shorter than an agent's
#: and an obstacle's radii together, so no disk passes through one in a step) to 0.25.
OBSTACLE_RADII = (0.1, 0.25)
#: Default obstacle radius: three times an agent's.
OBSTACLE_RADIUS = 0.15
#: Free gap kept between two obstacles and between an obstacle and a wall: wider than an agent
#: (0.1), so every passage lets one through and no part of the arena is closed off.
OBSTACLE_GAP = 0.15
#: How crowded an arena may be: ``obstacles · (2 · obstacle_radius + OBSTACLE_GAP)²`` at most
#: this. Placement then always succeeds (measured: it first fails above 1.69; 8 obstacles of the
#: default radius give 1.62).
MAX_CROWDING = 1.65
#: The dynamics factors a task may shift, with their ranges: damping up to 4 (all velocity
#: lost in a step), accelerations up to 4 times the paper's.
DYNAMICS_FACTORS = (("damping_factor", 0.0, 4.0), ("predator_accel_factor", 0.0, 4.0), ("prey_accel_factor", 0.0, 4.0))


@dataclass(frozen=True)
class TaskConfig:
    """Everything that defines one pursuit task. Validated on construction."""

    n_predators: int = 1
    """Number of predators, 1 to 3 (paper 3.2). There is always exactly one prey."""
    chase_cost: float = CHASE_COSTS["low"]
    """Reward paid by a predator for each step it spends in chase mode (>= 0)."""
    reward_sharing: RewardSharing = "shared"
    """``"shared"``: every predator gets +1 when any predator captures the prey;
    ``"individual"``: only the predator(s) touching the prey get it."""
    max_steps: int = MAX_STEPS
    """Steps after which the episode is truncated (not terminated)."""
    wall_rule: WallRule = "terminate"
    """``"terminate"`` (paper): touching a wall costs -1 and ends the episode.
    ``"contain"``: the wall stops the disk, the -1 is paid on every step in contact and the
    episode goes on."""
    continuous: bool = False
    """Continuous actions: each agent's action is an acceleration in its line-of-sight frame, a
    2-vector of norm <= 1 (longer ones are scaled down to 1) times the agent's maximum (the
    prey's 3.0, a predator's chase level 3.6); a predator is in chase mode, and pays the chase
    cost, in a step whose acceleration exceeds the stalk level (1.8, a norm above 0.5). The
    discrete task is this one restricted to its 24 (predator) or 12 (prey) points."""
    obstacles: int = 0
    """Static circular obstacles per arena, 0 to 8, placed afresh at every reset (docs/spec.md,
    obstacles). 0 is the paper's empty arena, bit for bit. With obstacles every observation
    ends with 12 range readings, and ``state()`` with the obstacles."""
    obstacle_radius: float = OBSTACLE_RADIUS
    """Radius of every obstacle, 0.1 to 0.25 (the arena is 2 across, an agent's radius 0.05)."""
    damping_factor: float = 1.0
    """The world's damping (the fraction of velocity lost per step, 0.25) times this factor,
    from 0 to 4 (a robustness test, docs/robustness.md; 1: the paper's world, bit for bit)."""
    predator_accel_factor: float = 1.0
    """Every predator's acceleration (both modes) times this factor, >= 0 (1: unchanged)."""
    prey_accel_factor: float = 1.0
    """The prey's acceleration times this factor, >= 0 (1: unchanged)."""

    def __post_init__(self) -> None:
        if (
            isinstance(self.n_predators, bool)
            or not isinstance(self.n_predators, int)
            or not (1 <= self.n_predators <= MAX_PREDATORS)
        ):
            raise ValueError(f"n_predators={self.n_predators!r}: expected an integer from 1 to 3")
        cost = self.chase_cost
        if isinstance(cost, bool) or not isinstance(cost, (int, float)) or not math.isfinite(cost) or cost < 0:
            raise ValueError(f"chase_cost={cost!r}: expected a finite number >= 0")
        if self.reward_sharing not in ("shared", "individual"):
            raise ValueError(f"reward_sharing={self.reward_sharing!r}: expected 'shared' or 'individual'")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, int) or self.max_steps < 1:
            raise ValueError(f"max_steps={self.max_steps!r}: expected an integer >= 1")
        if self.wall_rule not in ("terminate", "contain"):
            raise ValueError(f"wall_rule={self.wall_rule!r}: expected 'terminate' or 'contain'")
        if not isinstance(self.continuous, bool):
            raise ValueError(f"continuous={self.continuous!r}: expected True or False")
        k = self.obstacles
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k <= MAX_OBSTACLES:
            raise ValueError(f"obstacles={k!r}: expected an integer from 0 to {MAX_OBSTACLES}")
        r = self.obstacle_radius
        low, high = OBSTACLE_RADII
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not low <= r <= high:
            raise ValueError(f"obstacle_radius={r!r}: expected a number from {low} to {high}")
        for name, low_, high_ in DYNAMICS_FACTORS:
            f = getattr(self, name)
            if isinstance(f, bool) or not isinstance(f, (int, float)) or not low_ <= f <= high_:
                raise ValueError(f"{name}={f!r}: expected a number from {low_} to {high_}")
        if k * (2 * r + OBSTACLE_GAP) ** 2 > MAX_CROWDING:
            raise ValueError(
                f"obstacles={k} of obstacle_radius={r}: no room for them with the gaps kept between "
                f"them; expected obstacles * (2 * obstacle_radius + {OBSTACLE_GAP})**2 <= {MAX_CROWDING}"
            )

    @property
    def n_agents(self) -> int:
        return self.n_predators + 1

    @property
    def agent_names(self) -> tuple[str, ...]:
        """``predator_0`` … then ``prey_0``: the order of the agent axis in every array."""
        return (*(f"predator_{i}" for i in range(self.n_predators)), "prey_0")


def _paper_conditions() -> dict[str, TaskConfig]:
    conditions: dict[str, TaskConfig] = {}
    for n in range(1, MAX_PREDATORS + 1):
        for cost_name, cost in CHASE_COSTS.items():
            sharings: tuple[RewardSharing, ...] = ("shared",) if n == 1 else ("shared", "individual")
            for sharing in sharings:
                name = f"{n}p-{cost_name}" if n == 1 else f"{n}p-{cost_name}-{sharing}"
                conditions[name] = TaskConfig(n_predators=n, chase_cost=cost, reward_sharing=sharing)
    return conditions


#: The paper's ten conditions by name: ``"1p-low"``, ``"1p-high"``, ``"2p-low-shared"``, …,
#: ``"3p-high-individual"``.
CONDITIONS: dict[str, TaskConfig] = _paper_conditions()


def resolve_condition(condition: str | None = None, **options: object) -> TaskConfig:
    """Build a :class:`TaskConfig` from a condition name and/or explicit options.

    A condition fixes ``n_predators``, ``chase_cost`` and ``reward_sharing``; giving one of those
    as well is an error (ambiguous). ``max_steps``, ``wall_rule``, ``continuous``, ``obstacles``,
    ``obstacle_radius`` and the dynamics factors may be set with either.
    """
    known = {"n_predators", "chase_cost", "reward_sharing", "max_steps", "wall_rule", "continuous"}
    known |= {"obstacles", "obstacle_radius", *(name for name, _, _ in DYNAMICS_FACTORS)}
    unknown = set(options) - known
    if unknown:
        raise ValueError(f"unknown option(s) {sorted(unknown)}: expected some of {sorted(known)}")
    given = {k: v for k, v in options.items() if v is not None}
    if condition is None:
        return TaskConfig(**given)  # type: ignore[arg-type]
    if condition not in CONDITIONS:
        raise ValueError(f"condition={condition!r}: expected one of {', '.join(CONDITIONS)}")
    clash = sorted({"n_predators", "chase_cost", "reward_sharing"} & set(given))
    if clash:
        raise ValueError(f"condition={condition!r} already fixes {clash}; pass either the condition or the options")
    base = CONDITIONS[condition]
    return TaskConfig(
        n_predators=base.n_predators,
        chase_cost=base.chase_cost,
        reward_sharing=base.reward_sharing,
        **given,  # type: ignore[arg-type]
    )
