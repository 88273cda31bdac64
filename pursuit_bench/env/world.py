"""The physical world: disks in square arenas with viscous damping and walls. Physics only.

Every array is batched over arenas: positions and velocities are ``(B, n_agents, 2)`` float64 in
each arena's own frame (the arena is ``[-1, 1]²``). Agents ``0 … n_agents-2`` are predators and the
last one is the prey: the world needs that much to know which pairs pass through each other.

Dynamics (docs/spec.md, the arena; authors' code): velocity first, then position, no lag between an action
and its effect::

    v' = (1 - DAMPING) · v + a · DT
    p' = p + v' · DT

Two backends share this contract and the interface ``reset(arenas, positions[, obstacles])`` /
``step(accelerations) -> Contacts``:

- :class:`PymunkWorld` (the reference): one pymunk ``Space`` holds every arena, spaced apart on a
  grid. We compute ``v'`` in numpy, write every velocity with ``pymunk.batch`` and let
  ``space.step`` move the bodies (``space.damping = 1``, no forces), so pymunk moves each body by
  exactly ``v' · DT``. pymunk owns the walls (thick static segments) and the contacts.
- :class:`NumpyWorld`: the same arithmetic in vectorized numpy, with contacts from distances.

Both put disks back at the walls with one small compiled kernel (:func:`touch_walls`).

Obstacles (``obstacles > 0``): static circles, placed by the task at each reset (``reset``'s
``obstacles``, (len(arenas), K, 3) rows of x, y, radius). Disks collide with them as solid,
frictionless, perfectly inelastic bodies: a disk that ends a step overlapping one is put back
touching it and loses the velocity that points into it (:func:`leave_obstacles`). In pymunk they
are static circle shapes whose contacts its solver resolves (the velocity); the kernel then does
the positions, as for the walls. The numpy backend does both in the kernel; the two agree to
rounding (tests/test_obstacles.py). Obstacles keep a gap wider than a disk from each other and
from the walls (the task's placement rule), so a disk touches at most one of them at a time and
never an obstacle and a wall together.

Contacts reported by ``step`` are those at the end of the step. Whatever the speed, no disk ends a
step outside its arena: a disk that touches or crosses a wall is put back touching it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numba
import numpy as np
import pymunk
import pymunk.batch

from pursuit_bench.env.conditions import Backend as Backend  # physics backends: named with the task's options
from pursuit_bench.env.conditions import WallRule

#: Time step in seconds (paper 3.1).
DT = 0.1
#: Fraction of velocity lost per step to viscous drag (authors' code, ``damping = 0.25``).
DAMPING = 0.25
#: Disk radius of every agent (paper 3.1: diameter 0.1).
RADIUS = 0.05
#: Mass of every agent (authors' code).
MASS = 1.0
#: Half side of the square arena: x and y in [-1, 1] (paper 3.1).
HALF_SIZE = 1.0
#: Thickness of the pymunk walls: more than the longest step (1.44 · 0.1), so no disk tunnels.
WALL_THICKNESS = 0.5
#: pymunk's allowed overlap for processed contacts (its default 0.1 is twice our radius).
COLLISION_SLOP = 1e-6
#: A disk within this distance of a wall touches it: one resting against a wall may sit a
#: rounding error inside (pymunk's solver leaves ~1e-12), and is still in contact.
CONTACT_TOLERANCE = 1e-9
#: pymunk broad phase: a spatial hash of this cell size with this many buckets per shape. For
#: thousands of equal small disks it is about twice as fast as chipmunk's default bounding-box
#: tree (measured at 256 and 1024 arenas); it changes which pairs are tested, never the contacts.
HASH_CELL = 0.75
HASH_BUCKETS_PER_SHAPE = 10

_POSITION_VELOCITY = pymunk.batch.BodyFields.POSITION | pymunk.batch.BodyFields.VELOCITY


@dataclass
class Contacts:
    """What touched what at the end of a step."""

    wall: np.ndarray
    """(B, n_agents) bool: the disk touches or crosses its arena's wall."""
    prey: np.ndarray
    """(B, n_predators) bool: the predator's disk overlaps the prey's."""
    obstacle: np.ndarray
    """(B, n_agents) bool: the disk touches an obstacle (always False without obstacles)."""


class World(Protocol):
    num_arenas: int
    n_agents: int
    positions: np.ndarray
    velocities: np.ndarray
    obstacles: np.ndarray
    """(B, K, 3): each arena's obstacles, rows of x, y, radius."""

    def reset(self, arenas: np.ndarray, positions: np.ndarray, obstacles: np.ndarray | None = None) -> None: ...

    def step(self, accelerations: np.ndarray) -> Contacts: ...

    def snapshot(self) -> dict[str, Any]: ...

    def restore(self, state: dict[str, Any]) -> None: ...


def integrate_velocity(velocities: np.ndarray, accelerations: np.ndarray) -> np.ndarray:
    """``v' = (1 - DAMPING) v + a DT``, the velocity half of the dynamics, in float64: velocities
    and accelerations (B, n, 2) (:func:`checked_accelerations`)."""
    out = np.empty((velocities.shape[0] * velocities.shape[1], 2))
    _integrate_kernel(velocities, checked_accelerations(velocities, accelerations), 1.0 - DAMPING, DT, out)
    return out.reshape(velocities.shape)


def checked_accelerations(velocities: np.ndarray, accelerations: np.ndarray) -> np.ndarray:
    """``accelerations`` as float64 of the velocities' shape (B, n, 2), or a ValueError: the
    compiled integration reads them element by element and would not broadcast them."""
    arr = np.asarray(accelerations, dtype=np.float64)
    if arr.shape != velocities.shape:
        raise ValueError(f"accelerations of shape {arr.shape}: expected {velocities.shape}, one per disk")
    return arr


@numba.njit(cache=True)
def _integrate_kernel(velocities, accelerations, keep, dt, out):
    """:func:`integrate_velocity` of (B, n, 2) arrays into ``out``'s rows (B·n, 2), which may be
    a strided view (pymunk's buffer)."""
    n = velocities.shape[1]
    for b in range(velocities.shape[0]):
        for i in range(n):
            for d in range(2):
                out[b * n + i, d] = keep * velocities[b, i, d] + accelerations[b, i, d] * dt


@numba.njit(cache=True)
def _touch_walls_kernel(positions, velocities, limit, tolerance, contain, wall, moved):
    for b in range(positions.shape[0]):
        moved[b] = False
        for i in range(positions.shape[1]):
            touching = False
            for d in range(2):
                x = positions[b, i, d]
                if abs(x) >= limit - tolerance:
                    touching = True
                if abs(x) > limit:
                    if contain and velocities[b, i, d] * x > 0:
                        velocities[b, i, d] = 0.0
                    positions[b, i, d] = limit if x > 0 else -limit
                    moved[b] = True
            wall[b, i] = touching


def touch_walls(
    positions: np.ndarray, velocities: np.ndarray, limit: float, wall_rule: WallRule
) -> tuple[np.ndarray, np.ndarray]:
    """Which disks touch or cross a wall (``|x|`` or ``|y| >= limit - CONTACT_TOLERANCE``),
    (B, n) bool, and which arenas had a disk put back, (B,) bool. Disks that cross are put back
    touching the wall, in place; under ``contain`` they also lose their outward velocity (a
    perfectly inelastic wall)."""
    wall = np.empty(positions.shape[:2], dtype=bool)
    moved = np.empty(positions.shape[0], dtype=bool)
    _touch_walls_kernel(positions, velocities, limit, CONTACT_TOLERANCE, wall_rule == "contain", wall, moved)
    return wall, moved


@numba.njit(cache=True)
def _leave_obstacles_kernel(positions, velocities, obstacles, tolerance, touching, moved):
    for b in range(positions.shape[0]):
        moved[b] = False
        for i in range(positions.shape[1]):
            touching[b, i] = False
            for k in range(obstacles.shape[1]):
                dx = positions[b, i, 0] - obstacles[b, k, 0]
                dy = positions[b, i, 1] - obstacles[b, k, 1]
                reach = obstacles[b, k, 2] + RADIUS
                d2 = dx * dx + dy * dy
                if d2 <= (reach + tolerance) ** 2:
                    touching[b, i] = True
                if d2 < reach * reach:
                    d = np.sqrt(d2)
                    nx, ny = (dx / d, dy / d) if d > 0 else (1.0, 0.0)
                    positions[b, i, 0] = obstacles[b, k, 0] + nx * reach
                    positions[b, i, 1] = obstacles[b, k, 1] + ny * reach
                    inward = velocities[b, i, 0] * nx + velocities[b, i, 1] * ny
                    if inward < 0:
                        velocities[b, i, 0] -= inward * nx
                        velocities[b, i, 1] -= inward * ny
                    moved[b] = True


def leave_obstacles(
    positions: np.ndarray, velocities: np.ndarray, obstacles: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Which disks touch an obstacle (centres within its radius + ``RADIUS`` +
    ``CONTACT_TOLERANCE``), (B, n) bool, and which arenas had a disk put back, (B,) bool. A disk
    overlapping an obstacle is put back touching it, along the line from the obstacle's centre,
    and loses the part of its velocity pointing into it; in place. Without obstacles (K = 0)
    nothing touches and nothing moves."""
    touching = np.empty(positions.shape[:2], dtype=bool)
    moved = np.empty(positions.shape[0], dtype=bool)
    _leave_obstacles_kernel(positions, velocities, obstacles, CONTACT_TOLERANCE, touching, moved)
    return touching, moved


#: A predator overlaps the prey when their centres are closer than two radii: that distance squared.
_CAPTURE_REACH_SQUARED = (2 * RADIUS) ** 2


@numba.njit(cache=True)
def _prey_overlap_row(positions, b, reach_squared, out):
    """``out[b, i]``: predator i of arena b overlaps the prey (``dx² + dy² < reach_squared``)."""
    n = positions.shape[1]
    for i in range(n - 1):
        dx = positions[b, i, 0] - positions[b, n - 1, 0]
        dy = positions[b, i, 1] - positions[b, n - 1, 1]
        out[b, i] = dx * dx + dy * dy < reach_squared


@numba.njit(cache=True)
def _prey_overlap_kernel(positions, reach_squared):
    out = np.empty((positions.shape[0], positions.shape[1] - 1), dtype=np.bool_)
    for b in range(positions.shape[0]):
        _prey_overlap_row(positions, b, reach_squared, out)
    return out


def _prey_overlap(positions: np.ndarray) -> np.ndarray:
    """(B, n - 1) bool: which predators overlap their arena's prey."""
    return _prey_overlap_kernel(positions, _CAPTURE_REACH_SQUARED)


@numba.njit(cache=True)
def _chipmunk_overlap_row(state, b, n, radius, out):
    """``out[b, i]``: predator i of arena b touches the prey as chipmunk's collision pipeline
    decides it on the bodies' absolute positions ``state`` (B·n, 4), the test it ran when the
    contact came from pymunk's callback: the two disks' bounding boxes intersect
    (``cpBBNewForCircle``, ``cpBBIntersects``) and the squared distance of the centres is below
    the squared sum of the radii (``CircleToCircle``), each in chipmunk's order of operations."""
    prey = b * n + n - 1
    px, py = state[prey, 0], state[prey, 1]
    reach = radius + radius
    for i in range(n - 1):
        qx, qy = state[b * n + i, 0], state[b * n + i, 1]
        boxes = qx - radius <= px + radius and px - radius <= qx + radius
        boxes = boxes and qy - radius <= py + radius and py - radius <= qy + radius
        dx, dy = px - qx, py - qy
        out[b, i] = boxes and dx * dx + dy * dy < reach * reach


@numba.njit(cache=True)
def _settle_kernel(state, offsets, relative, obstacles, limit, tolerance, contain, arenas, radius, reach_squared):
    """What :meth:`PymunkWorld.step` does after pymunk's step, in one pass: each arena's
    positions (``relative``: less its offset) and velocities from pymunk's body rows ``state``
    (B·n, 4), the obstacles and the walls (:func:`leave_obstacles`, then :func:`touch_walls`, in
    place), and the captures: decided as chipmunk decides a contact, on the positions pymunk's
    step ends with (:func:`_chipmunk_overlap_row`), and again on the final positions in an arena
    whose disks were put back. Returns positions, velocities, wall, prey and obstacle contacts,
    and whether any arena had a disk put back."""
    n = state.shape[0] // arenas
    captured = np.empty((arenas, n - 1), dtype=np.bool_)
    for b in range(arenas):
        _chipmunk_overlap_row(state, b, n, radius, captured)
    positions = np.empty((arenas, n, 2))
    velocities = np.empty((arenas, n, 2))
    for b in range(arenas):
        for i in range(n):
            for d in range(2):
                x = state[b * n + i, d]
                positions[b, i, d] = x - offsets[b * n + i, d] if relative else x
                velocities[b, i, d] = state[b * n + i, 2 + d]
    obstacle = np.empty((arenas, n), dtype=np.bool_)
    pushed = np.empty(arenas, dtype=np.bool_)
    _leave_obstacles_kernel(positions, velocities, obstacles, tolerance, obstacle, pushed)
    wall = np.empty((arenas, n), dtype=np.bool_)
    moved = np.empty(arenas, dtype=np.bool_)
    _touch_walls_kernel(positions, velocities, limit, tolerance, contain, wall, moved)
    prey = captured
    any_moved = False
    for b in range(arenas):
        if moved[b] or pushed[b]:
            any_moved = True
            _prey_overlap_row(positions, b, reach_squared, prey)
    return positions, velocities, wall, prey, obstacle, any_moved


class NumpyWorld:
    """The dynamics in vectorized numpy: the fast backend.

    Contacts are decided on distances: a disk touches the wall when ``|x| >= half_size - r`` (or
    ``|y|``), a predator overlaps the prey when their centres are closer than ``2 r``. Under
    ``contain`` a disk that crosses the wall is clamped to it and loses its outward velocity.
    """

    def __init__(
        self,
        num_arenas: int,
        n_agents: int,
        *,
        wall_rule: WallRule = "terminate",
        half_size: float = HALF_SIZE,
        obstacles: int = 0,
        blocks: list[int] | None = None,
    ) -> None:
        self.num_arenas = num_arenas
        self.n_agents = n_agents
        self.wall_rule = wall_rule
        self.limit = half_size - RADIUS
        check_blocks(blocks, num_arenas, static=False)  # no absolute coordinates: the sizes are all
        self.positions = np.zeros((num_arenas, n_agents, 2))
        self.velocities = np.zeros((num_arenas, n_agents, 2))
        self.obstacles = np.zeros((num_arenas, obstacles, 3))

    def reset(self, arenas: np.ndarray, positions: np.ndarray, obstacles: np.ndarray | None = None) -> None:
        self.positions[arenas] = positions
        self.velocities[arenas] = 0.0
        if obstacles is not None:
            self.obstacles[arenas] = obstacles

    def snapshot(self) -> dict[str, np.ndarray]:
        """Everything the next step depends on (for a checkpoint): see :meth:`restore`."""
        return {
            "positions": self.positions.copy(),
            "velocities": self.velocities.copy(),
            "obstacles": self.obstacles.copy(),
        }

    def restore(self, state: dict[str, Any]) -> None:
        """Put back a :meth:`snapshot`: the next step is the one that would have followed it."""
        self.positions = np.array(state["positions"], dtype=np.float64)
        self.velocities = np.array(state["velocities"], dtype=np.float64)
        self.obstacles = np.array(state["obstacles"], dtype=np.float64)

    def step(self, accelerations: np.ndarray) -> Contacts:
        v = integrate_velocity(self.velocities, accelerations)
        p = self.positions + v * DT
        obstacle, _ = leave_obstacles(p, v, self.obstacles)
        wall, _ = touch_walls(p, v, self.limit, self.wall_rule)
        self.positions, self.velocities = p, v
        return Contacts(wall=wall, prey=_prey_overlap(p), obstacle=obstacle)


class PymunkWorld:
    """The reference backend: every arena in one pymunk ``Space``.

    Arenas sit on a square grid, ``2 (half_size + WALL_THICKNESS)`` apart, so they never touch.
    Disks share one shape-filter group and so never collide with each other in pymunk: predators
    pass through each other, and a predator touching the prey is never pushed apart from it (a
    capture ends the episode). The capture is decided after pymunk's step, on the positions it
    ends with, by the test chipmunk's own contact pipeline makes (:func:`_chipmunk_overlap_row`;
    until issue 62, pymunk's pre-solve callback in Python reported it: the same contacts).
    Under ``contain`` pymunk's solver stops disks at the walls (perfectly inelastic,
    frictionless); under ``terminate`` there are no wall shapes (they were sensors, with no effect
    on the bodies, and took four fifths of pymunk's step). Whether a disk touches a wall is decided
    on its position (:func:`touch_walls`), which also catches every contact pymunk would report.
    Obstacles are circles on the space's static body, moved at each reset (``unsafe_set_offset``,
    then reindexed).
    """

    def __init__(
        self,
        num_arenas: int,
        n_agents: int,
        *,
        wall_rule: WallRule = "terminate",
        half_size: float = HALF_SIZE,
        obstacles: int = 0,
        blocks: list[int] | None = None,
    ) -> None:
        self.num_arenas = num_arenas
        self.n_agents = n_agents
        self.wall_rule = wall_rule
        self.limit = half_size - RADIUS
        static = wall_rule == "contain" or obstacles > 0
        sizes = check_blocks(blocks, num_arenas, static=static)

        space = pymunk.Space()
        space.damping = 1.0  # damping is applied in integrate_velocity, not by pymunk
        space.collision_slop = COLLISION_SLOP
        # No positional bias: the position check below puts disks back, so pymunk's own push-out
        # would correct the same overlap twice and bounce the disk off the wall.
        space.collision_bias = 1.0
        self.space = space
        # each block of arenas laid out as a world of its own would lay it out, the blocks one on
        # top of another: an arena's absolute coordinates, and so the bits of its physics, are those
        # it has in a world of its block alone; a block's walls and obstacles touch its own disks only
        spacing = 2 * (half_size + WALL_THICKNESS)
        grids = []
        for size in sizes:
            columns = int(np.ceil(np.sqrt(size)))
            grids += [[(i % columns) * spacing, (i // columns) * spacing] for i in range(size)]
        self.offsets = np.array(grids, dtype=np.float64)
        block = np.repeat(np.arange(len(sizes)), sizes)
        separate = static and len(sizes) > 1  # without walls or obstacles nothing could touch
        own = [pymunk.ShapeFilter(categories=1 << b, mask=1 << b) for b in range(len(sizes))] if separate else []
        disks = [pymunk.ShapeFilter(group=1, categories=f.categories, mask=f.mask) for f in own]
        self._static_filters = [own[b] for b in block] if own else []
        for arena, (ox, oy) in enumerate(self.offsets):
            if wall_rule == "contain":  # under "terminate" a wall has no effect: none is made
                self._add_walls(ox, oy, half_size, arena)
            for _ in range(n_agents):
                body = pymunk.Body(MASS, float("inf"))  # disks never rotate
                body.position = (ox, oy)
                if not static:  # nothing to touch: a body alone (pymunk moves it as it would a disk)
                    space.add(body)
                    continue
                disk = pymunk.Circle(body, RADIUS)
                disk.friction = 0.0
                disk.elasticity = 0.0
                # disks never collide with disks in pymunk (one group)
                disk.filter = disks[block[arena]] if disks else pymunk.ShapeFilter(group=1)
                space.add(body, disk)
        self.obstacles = np.zeros((num_arenas, obstacles, 3))
        if obstacles:
            # Contacts solved afresh each step: an arbiter kept from an earlier contact (pymunk's
            # default keeps them 3 steps) warm-starts the solver with that contact's impulse,
            # and the velocity then differs from a fresh solve (measured: 1e-4 within 12 steps).
            space.collision_persistence = 0
        self._obstacle_shapes: list[list[pymunk.Circle]] = []
        for arena, (ox, oy) in enumerate(self.offsets):
            shapes = [pymunk.Circle(space.static_body, 0.0, (ox, oy)) for _ in range(obstacles)]
            for shape in shapes:
                shape.friction = 0.0
                shape.elasticity = 0.0
                if self._static_filters:
                    shape.filter = self._static_filters[arena]
                space.add(shape)
            self._obstacle_shapes.append(shapes)
        if space.shapes:
            space.use_spatial_hash(HASH_CELL, HASH_BUCKETS_PER_SHAPE * len(space.shapes))

        self._offsets_per_body = np.repeat(self.offsets, n_agents, axis=0)
        self._offset = bool(self.offsets.any())  # a single arena sits at the origin
        # pymunk.batch visits the dynamic bodies in the order they were added, then the space's
        # static body (which holds the walls): one trailing row, kept at zero, stands for it.
        # Reads append into memory pymunk owns (and may grow); writes lend it two arrays of ours.
        self._bodies = num_arenas * n_agents
        self._read_buffer = pymunk.batch.Buffer()
        self._state = np.zeros((self._bodies + 1, 4))  # px, py, vx, vy per body
        self._state_buffer = pymunk.batch.Buffer()
        self._state_buffer.set_float_buf(self._state.reshape(-1))
        self._moved = False  # disks moved by us since pymunk last stepped: write their positions
        self._velocity = np.zeros((self._bodies + 1, 2))  # vx, vy per body
        self._velocity_buffer = pymunk.batch.Buffer()
        self._velocity_buffer.set_float_buf(self._velocity.reshape(-1))
        self.positions = np.zeros((num_arenas, n_agents, 2))
        self.velocities = np.zeros((num_arenas, n_agents, 2))

    def _add_walls(self, ox: float, oy: float, half_size: float, arena: int) -> None:
        t = WALL_THICKNESS / 2  # segment radius: the inner face is at ±half_size
        c = half_size + t
        corners = [(-c, -c), (c, -c), (c, c), (-c, c)]
        for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1], strict=True):
            wall = pymunk.Segment(self.space.static_body, (ox + ax, oy + ay), (ox + bx, oy + by), t)
            wall.friction = 0.0
            wall.elasticity = 0.0
            if self._static_filters:
                wall.filter = self._static_filters[arena]
            self.space.add(wall)

    def _bodies_state(self) -> np.ndarray:
        """(B·n, 4) every disk's absolute position and velocity as pymunk holds them (a view of
        pymunk's memory: valid until the next read)."""
        self._read_buffer.clear()
        pymunk.batch.get_space_bodies(self.space, _POSITION_VELOCITY, self._read_buffer)
        return np.frombuffer(self._read_buffer.float_buf(), dtype=np.float64).reshape(-1, 4)[: self._bodies]

    def reset(self, arenas: np.ndarray, positions: np.ndarray, obstacles: np.ndarray | None = None) -> None:
        self.positions[arenas] = positions
        self.velocities[arenas] = 0.0
        self._moved = True  # pymunk learns the new positions with the next step's velocities
        if obstacles is not None:
            self._place_obstacles(np.asarray(arenas), obstacles)

    def _place_obstacles(self, arenas: np.ndarray, obstacles: np.ndarray) -> None:
        self.obstacles[arenas] = obstacles
        for arena, rows in zip(arenas.tolist(), obstacles, strict=True):
            ox, oy = self.offsets[arena]
            for shape, (x, y, radius) in zip(self._obstacle_shapes[arena], rows, strict=True):
                shape.unsafe_set_offset((ox + x, oy + y))
                shape.unsafe_set_radius(radius)
                self.space.reindex_shape(shape)

    def snapshot(self) -> dict[str, Any]:
        """Everything of ours the next step depends on, and pymunk's bodies as pymunk holds them
        (absolute positions: relative ones plus the arena's offset need not give back the same
        bits). Not pymunk's contact caches: a contact under way at a restore may resolve in
        other last bits (:meth:`restore`)."""
        bodies = self._bodies_state()
        return {
            "positions": self.positions.copy(),
            "velocities": self.velocities.copy(),
            "obstacles": self.obstacles.copy(),
            "bodies": bodies.copy(),
            "moved": self._moved,
        }

    def restore(self, state: dict[str, Any]) -> None:
        """Put back a :meth:`snapshot`: pymunk's bodies exactly, our arrays, the obstacles."""
        if len(self._obstacle_shapes[0]):
            self._place_obstacles(np.arange(self.num_arenas), np.array(state["obstacles"], dtype=np.float64))
        self._state[:-1] = np.array(state["bodies"], dtype=np.float64)
        pymunk.batch.set_space_bodies(self.space, _POSITION_VELOCITY, self._state_buffer)
        self.positions = np.array(state["positions"], dtype=np.float64)
        self.velocities = np.array(state["velocities"], dtype=np.float64)
        self._moved = bool(state["moved"])

    def _write(self, accelerations: np.ndarray) -> None:
        """Give pymunk this step's velocities (:func:`integrate_velocity`, written straight into
        the buffer it reads), and the positions too if we moved disks (a reset, or putting them
        back at a wall) since it last stepped."""
        keep = 1.0 - DAMPING
        accelerations = checked_accelerations(self.velocities, accelerations)
        if self._moved:
            flat = self._state
            flat[:-1, :2] = self.positions.reshape(-1, 2) + self._offsets_per_body
            _integrate_kernel(self.velocities, accelerations, keep, DT, flat[:-1, 2:])
            pymunk.batch.set_space_bodies(self.space, _POSITION_VELOCITY, self._state_buffer)
            self._moved = False
        else:
            _integrate_kernel(self.velocities, accelerations, keep, DT, self._velocity[:-1])
            pymunk.batch.set_space_bodies(self.space, pymunk.batch.BodyFields.VELOCITY, self._velocity_buffer)

    def step(self, accelerations: np.ndarray) -> Contacts:
        self._write(accelerations)
        self.space.step(DT)
        # pymunk saw the arenas whose disks we put back at a wall or an obstacle before we did:
        # their captures are decided on the positions the step ends with
        self.positions, self.velocities, wall, prey, obstacle, moved = _settle_kernel(
            self._bodies_state(),
            self._offsets_per_body,
            self._offset,
            self.obstacles,
            self.limit,
            CONTACT_TOLERANCE,
            self.wall_rule == "contain",
            self.num_arenas,
            RADIUS,
            _CAPTURE_REACH_SQUARED,
        )
        self._moved = moved
        return Contacts(wall=wall, prey=prey, obstacle=obstacle)


#: The most blocks of arenas a pymunk world holds where there are walls or obstacles to keep
#: apart (one shape-filter category each; chipmunk's bitmasks have 32 bits).
MAX_BLOCKS = 32


def check_blocks(blocks: list[int] | None, num_arenas: int, *, static: bool) -> list[int]:
    """The block sizes (``[num_arenas]`` by default), checked: positive, summing to
    ``num_arenas``, at most :data:`MAX_BLOCKS` where blocks must not touch each other's
    walls or obstacles (``static``)."""
    sizes = [num_arenas] if blocks is None else [int(b) for b in blocks]
    if any(b < 1 for b in sizes) or sum(sizes) != num_arenas:
        raise ValueError(f"blocks={blocks!r}: expected positive sizes adding up to {num_arenas} arenas")
    if static and len(sizes) > MAX_BLOCKS:
        raise ValueError(f"blocks: {len(sizes)} blocks with walls or obstacles; at most {MAX_BLOCKS}")
    return sizes


def make_world(
    backend: Backend,
    num_arenas: int,
    n_agents: int,
    *,
    wall_rule: WallRule = "terminate",
    half_size: float = HALF_SIZE,
    obstacles: int = 0,
    blocks: list[int] | None = None,
) -> World:
    """Build a world of the named backend (``"pymunk"``, the reference, or ``"numpy"``) with
    room for ``obstacles`` obstacles per arena. ``blocks``: sizes of consecutive runs of arenas
    each placed as a world of that many arenas alone would place them, so that an arena's
    physics gives the bits it gives there (pymunk keeps absolute coordinates; the numpy
    backend's arenas have none, and it only checks the sizes)."""
    if backend == "pymunk":
        return PymunkWorld(
            num_arenas, n_agents, wall_rule=wall_rule, half_size=half_size, obstacles=obstacles, blocks=blocks
        )
    if backend == "numpy":
        return NumpyWorld(
            num_arenas, n_agents, wall_rule=wall_rule, half_size=half_size, obstacles=obstacles, blocks=blocks
        )
    raise ValueError(f"backend={backend!r}: expected 'pymunk' or 'numpy'")
