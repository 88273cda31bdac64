"""The world against the spec's (docs/spec.md) dynamics: closed form, terminal speeds, walls, contacts."""

import numpy as np
import pytest

from pursuit_bench.env.task import ACCEL_CHASE, ACCEL_PREY, ACCEL_STALK
from pursuit_bench.env.world import DAMPING, DT, RADIUS, checked_accelerations, make_world

BACKENDS = ["pymunk", "numpy"]


def closed_form(p0: np.ndarray, v0: np.ndarray, a: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
    """v_t = k^t v0 + a dt (1 - k^t) / (1 - k); p_t = p0 + dt Σ_{s=1..t} v_s, with k = 1 - damping."""
    k = 1 - DAMPING
    geo = k * (1 - k**t) / (1 - k)  # Σ_{s=1..t} k^s
    v = k**t * v0 + a * DT * (1 - k**t) / (1 - k)
    p = p0 + DT * (v0 * geo + a * DT / (1 - k) * (t - geo))
    return p, v


@pytest.mark.parametrize("backend", BACKENDS)
def test_free_disk_matches_closed_form_for_300_steps(backend: str) -> None:
    # a huge arena so the disks fly free for all 300 steps
    world = make_world(backend, 3, 2, half_size=100.0)
    p0 = np.array([[[0.1, -0.2], [3.0, 3.0]], [[-0.3, 0.4], [-3.0, 3.0]], [[0.0, 0.0], [3.0, -3.0]]])
    world.reset(np.arange(3), p0)
    rng = np.random.default_rng(1)
    a = rng.normal(size=(3, 2, 2)) * 2.0
    for t in range(1, 301):
        world.step(a)
        p, v = closed_form(p0, np.zeros_like(p0), a, t)
        np.testing.assert_allclose(world.positions, p, rtol=0, atol=1e-9)
        np.testing.assert_allclose(world.velocities, v, rtol=0, atol=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("accel", "speed"), [(ACCEL_PREY, 1.2), (ACCEL_CHASE, 1.44), (ACCEL_STALK, 0.72)])
def test_terminal_speeds(backend: str, accel: float, speed: float) -> None:
    world = make_world(backend, 1, 2, half_size=100.0)
    world.reset(np.array([0]), np.array([[[0.0, 0.0], [5.0, 5.0]]]))
    a = np.array([[[accel * 0.6, accel * 0.8], [0.0, 0.0]]])
    for _ in range(300):
        world.step(a)
    assert np.hypot(*world.velocities[0, 0]) == pytest.approx(speed, abs=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("wall_rule", ["terminate", "contain"])
@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.0, -1.0), (np.sqrt(0.5), np.sqrt(0.5))])
def test_disk_driven_at_a_wall_at_chase_speed_never_leaves(backend: str, wall_rule: str, direction: tuple) -> None:
    world = make_world(backend, 2, 2, wall_rule=wall_rule)  # two arenas: the second one stays put
    world.reset(np.arange(2), np.array([[[0.0, 0.0], [0.5, 0.5]], [[0.0, 0.0], [0.5, 0.5]]]))
    a = np.zeros((2, 2, 2))
    a[0, 0] = np.array(direction) * ACCEL_CHASE
    # start at terminal speed so the disk crosses the last stretch as fast as it ever can
    world.velocities[0, 0] = np.array(direction) * 1.44
    touched = []
    for _ in range(40):
        contacts = world.step(a)
        touched.append(contacts.wall[0, 0])
        assert (np.abs(world.positions) <= 1 - RADIUS + 1e-12).all()
        assert not contacts.wall[1].any()
    first = touched.index(True)
    assert 0 < first <= 0.95 / (0.144 * max(np.abs(direction))) + 1  # at most 0.144 per step to go
    if wall_rule == "contain":
        assert all(touched[first:])  # pressed against the wall: in contact on every later step
        normal = np.abs(direction) == 1.0
        assert (np.abs(world.velocities[0, 0][normal]) < 1e-6).all()  # the wall stops the disk


@pytest.mark.parametrize("backend", BACKENDS)
def test_predators_pass_through_each_other(backend: str) -> None:
    world = make_world(backend, 1, 3)  # two predators and a prey
    p0 = np.array([[[-0.3, 0.0], [0.3, 0.0], [0.0, 0.8]]])
    world.reset(np.array([0]), p0)
    a = np.array([[[1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]]]) * ACCEL_CHASE
    for t in range(1, 8):
        contacts = world.step(a)
        p, _ = closed_form(p0, np.zeros_like(p0), a, t)
        np.testing.assert_allclose(world.positions, p, atol=1e-12)  # no collision response
        assert not contacts.prey.any() and not contacts.wall.any()
    assert world.positions[0, 0, 0] > world.positions[0, 1, 0]  # they crossed


@pytest.mark.parametrize("backend", BACKENDS)
def test_capture_is_an_overlap_at_the_end_of_a_step(backend: str) -> None:
    world = make_world(backend, 1, 3)
    # predator 0 moves towards the prey; predator 1 stays away
    p0 = np.array([[[0.0, 0.0], [-0.5, -0.5], [0.2, 0.0]]])
    world.reset(np.array([0]), p0)
    a = np.array([[[ACCEL_CHASE, 0.0], [0.0, 0.0], [0.0, 0.0]]])
    captured_at = None
    for t in range(1, 20):
        contacts = world.step(a)
        gap = np.hypot(*(world.positions[0, 0] - world.positions[0, 2]))
        assert contacts.prey[0, 0] == (gap < 2 * RADIUS)
        assert not contacts.prey[0, 1]
        if contacts.prey[0, 0]:
            captured_at = t
            p, _ = closed_form(p0, np.zeros_like(p0), a, t)
            np.testing.assert_allclose(world.positions, p, atol=1e-12)  # never pushed apart
            break
    assert captured_at is not None


def test_unknown_backend_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="backend='jax'"):
        make_world("jax", 1, 2)  # type: ignore[arg-type]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("wall_rule", ["terminate", "contain"])
def test_capture_is_decided_after_a_disk_is_put_back(backend: str, wall_rule: str) -> None:
    """The prey would end past the wall (0.955) and is put back at 0.95: only then does it
    overlap the predator (0.1 - 0.003 apart), so the step ends in a capture."""
    world = make_world(backend, 1, 2, wall_rule=wall_rule)
    world.reset(np.array([0]), np.array([[[0.0, 0.853], [0.0, 0.94]]]))
    world.velocities[0, 1] = (0.0, 0.2)  # v' = 0.15, p' = 0.955 without the wall
    contacts = world.step(np.zeros((1, 2, 2)))
    assert world.positions[0, 1, 1] == pytest.approx(1 - RADIUS)
    assert contacts.wall[0, 1] and contacts.prey[0, 0]


@pytest.mark.parametrize("backend", ["pymunk", "numpy"])
def test_accelerations_of_another_shape_are_refused_not_broadcast(backend: str) -> None:
    """The compiled integration reads one acceleration per disk: a shape that numpy would have
    broadcast is a ValueError, and float32 accelerations are taken as float64."""
    world = make_world(backend, 3, 2)
    world.reset(np.arange(3), np.zeros((3, 2, 2)))
    with pytest.raises(ValueError, match=r"accelerations of shape \(1, 2, 2\): expected \(3, 2, 2\)"):
        world.step(np.ones((1, 2, 2)))
    accelerations = np.random.default_rng(0).normal(size=(3, 2, 2)).astype(np.float32)
    assert checked_accelerations(world.velocities, accelerations).dtype == np.float64
    world.step(accelerations)
    np.testing.assert_array_equal(world.velocities, accelerations.astype(np.float64) * DT)


@pytest.mark.parametrize("wall_rule", ["terminate", "contain"])
@pytest.mark.parametrize("n_agents", [2, 4])
def test_captures_are_the_contacts_pymunk_reports(wall_rule: str, n_agents: int) -> None:
    """The world decides a capture after pymunk's step (issue 62); the reference is pymunk's own
    contact pipeline: a pre-solve callback on every predator–prey pair of the same bodies, in arenas
    where no disk was put back at a wall (there the capture is decided again, on the final positions)."""
    import pymunk

    arenas = 120
    world = make_world("pymunk", arenas, n_agents, wall_rule=wall_rule)
    assert world.__class__.__name__ == "PymunkWorld"
    space = world.space  # type: ignore[attr-defined]
    disks = [s for s in space.shapes if isinstance(s, pymunk.Circle) and s.body.body_type == pymunk.Body.DYNAMIC]
    if not disks:  # with nothing to touch the world's disks are bodies alone: the reference gives them shapes
        for body in space.bodies:
            disks.append(pymunk.Circle(body, RADIUS))
            disks[-1].filter = pymunk.ShapeFilter(group=1)
            space.add(disks[-1])
    assert len(disks) == arenas * n_agents
    reported = np.zeros((arenas, n_agents - 1), dtype=bool)
    for k, disk in enumerate(disks):
        arena, agent = divmod(k, n_agents)
        if agent == n_agents - 1:
            disk.collision_type, disk.filter = 2, pymunk.ShapeFilter()  # the prey collides with the predators
            continue
        disk.collision_type = 100 + k

        def pre_solve(arbiter: pymunk.Arbiter, space: pymunk.Space, data: tuple[int, int]) -> None:
            reported[data] = True
            arbiter.process_collision = False  # reported, never solved: the bodies move as without it

        space.on_collision(100 + k, 2, pre_solve=pre_solve, data=(arena, agent))
    rng = np.random.default_rng(5)
    compared = captures = 0
    for step in range(600):
        if step % 20 == 0:  # predator 0 starts near the prey: many contacts, many near misses
            positions = rng.uniform(-0.5, 0.5, (arenas, n_agents, 2))
            positions[:, 0] = positions[:, -1] + rng.normal(0.0, 0.06, (arenas, 2))
            world.reset(np.arange(arenas), np.clip(positions, -0.9, 0.9))
        reported[:] = False
        contacts = world.step(rng.uniform(-4.0, 4.0, (arenas, n_agents, 2)))
        untouched = ~contacts.wall.any(axis=1)
        np.testing.assert_array_equal(contacts.prey[untouched], reported[untouched])
        compared += int(untouched.sum())
        captures += int(reported[untouched].sum())
    assert compared > 30_000 and captures > 3_000


@pytest.mark.parametrize(("wall_rule", "obstacles"), [("terminate", 0), ("contain", 0), ("terminate", 3)])
def test_an_arena_in_a_block_moves_as_in_a_world_of_its_block_alone(wall_rule: str, obstacles: int) -> None:
    """Blocks of arenas lie one on another, each laid out as its own world would lay it out: the
    same absolute coordinates, so the same bits, and no block touches another's walls or
    obstacles (a block's obstacles in another block's way would change where its disks go)."""
    sizes = [5, 12, 7]
    together = make_world("pymunk", sum(sizes), 3, wall_rule=wall_rule, obstacles=obstacles, blocks=sizes)
    alone = [make_world("pymunk", size, 3, wall_rule=wall_rule, obstacles=obstacles) for size in sizes]
    rng = np.random.default_rng(2)
    moved = 0.0
    for step in range(400):
        if step % 100 == 0:
            positions = rng.uniform(-0.9, 0.9, (sum(sizes), 3, 2))
            around = None
            if obstacles:  # blocks' obstacles at different places: overlapping blocks would collide
                around = np.concatenate(
                    [rng.uniform(-0.8, 0.8, (sum(sizes), obstacles, 2)), np.full((sum(sizes), obstacles, 1), 0.12)],
                    axis=-1,
                )
            together.reset(np.arange(sum(sizes)), positions, around)
            for k, world in enumerate(alone):
                rows = slice(sum(sizes[:k]), sum(sizes[: k + 1]))
                world.reset(np.arange(sizes[k]), positions[rows], None if around is None else around[rows])
        pushes = rng.uniform(-4.0, 4.0, (sum(sizes), 3, 2))
        contacts = together.step(pushes)
        at = 0
        for size, world in zip(sizes, alone, strict=True):
            theirs = world.step(pushes[at : at + size])
            np.testing.assert_array_equal(together.positions[at : at + size], world.positions)
            np.testing.assert_array_equal(together.velocities[at : at + size], world.velocities)
            np.testing.assert_array_equal(contacts.obstacle[at : at + size], theirs.obstacle)
            at += size
        moved += float(np.abs(together.velocities).sum())
    assert moved > 0


def test_blocks_that_do_not_add_up_are_refused() -> None:
    with pytest.raises(ValueError, match="adding up to 10"):
        make_world("pymunk", 10, 2, blocks=[4, 5])
    with pytest.raises(ValueError, match="at most 32"):
        make_world("pymunk", 33, 2, wall_rule="contain", blocks=[1] * 33)
