"""The task rules against naive references: directions, observations, rewards, episode end."""

import math

import numpy as np
import pytest

from pursuit_bench.env import task
from pursuit_bench.env.conditions import TaskConfig
from pursuit_bench.env.world import Contacts


def naive_observation(p: np.ndarray, v: np.ndarray, i: int) -> list[float]:
    """the spec's (docs/spec.md) observation for agent i, written with loops and trigonometry."""
    n = len(p)
    prey = n - 1
    if i < prey:
        target = prey
        others = [prey] + [j for j in range(prey) if j != i]
    else:
        dists = [math.dist(p[j], p[prey]) for j in range(prey)]
        others = sorted(range(prey), key=lambda j: (dists[j], j))
        target = others[0]
    theta = math.atan2(p[target][1] - p[i][1], p[target][0] - p[i][0])

    def frame(x: float, y: float) -> list[float]:
        return [x * math.cos(theta) + y * math.sin(theta), -x * math.sin(theta) + y * math.cos(theta)]

    obs = [*p[i], *frame(*v[i])]
    for j in others:
        obs += [*p[j], *frame(p[j][0] - p[i][0], p[j][1] - p[i][1]), *frame(*v[j])]
    return obs


@pytest.mark.parametrize("n_agents", [2, 3, 4])
def test_observations_match_naive_reference(n_agents: int) -> None:
    rng = np.random.default_rng(n_agents)
    p = rng.uniform(-0.9, 0.9, size=(50, n_agents, 2))
    v = rng.uniform(-1.4, 1.4, size=(50, n_agents, 2))
    obs = task.observations(p, v)
    assert obs.shape == (50, n_agents, 6 * n_agents - 2) and obs.dtype == np.float32
    for b in range(50):
        for i in range(n_agents):
            np.testing.assert_allclose(obs[b, i], naive_observation(p[b], v[b], i), atol=1e-6)


def test_direction_indices_are_relative_to_the_line_of_sight() -> None:
    p = np.array([[[0.0, 0.0], [0.0, 0.5]]])  # predator at origin, prey straight up
    los = task.line_of_sight(p)
    np.testing.assert_allclose(los, [[[0, 1], [0, -1]]], atol=1e-12)
    for k, expected in [(0, (0, 1)), (3, (1, 0)), (6, (0, -1)), (9, (-1, 0)), (1, (0.5, math.sqrt(3) / 2))]:
        d = task.rotate_by_direction(los[0, 0], np.array(k))  # -k·30° from the LOS
        np.testing.assert_allclose(d, expected, atol=1e-12)
    acc = task.accelerations(los, np.array([[task.CHASE]]), np.array([[0, 0]]))
    np.testing.assert_allclose(acc, [[[0, task.ACCEL_CHASE], [0, -task.ACCEL_PREY]]], atol=1e-12)
    acc = task.accelerations(los, np.array([[task.STALK]]), np.array([[6, 6]]))
    np.testing.assert_allclose(acc, [[[0, -task.ACCEL_STALK], [0, task.ACCEL_PREY]]], atol=1e-12)


def test_prey_looks_at_its_nearest_predator() -> None:
    p = np.array([[[0.5, 0.0], [-0.2, 0.0], [0.0, 0.0]]])
    np.testing.assert_allclose(task.line_of_sight(p)[0, 2], [-1, 0], atol=1e-12)


def contacts(wall: list[list[bool]], prey: list[list[bool]]) -> Contacts:
    return Contacts(wall=np.array(wall), prey=np.array(prey), obstacle=np.zeros_like(wall, dtype=bool))


NO_CHASE = np.array([[0, 0]])


@pytest.mark.parametrize(
    ("sharing", "wall", "prey", "modes", "expected", "terminated"),
    [
        # capture by predator 0, shared: +1 to both predators, -1 to the prey
        ("shared", [[0, 0, 0]], [[1, 0]], NO_CHASE, [1, 1, -1], True),
        # capture by predator 0, individual: only predator 0 gets +1
        ("individual", [[0, 0, 0]], [[1, 0]], NO_CHASE, [1, 0, -1], True),
        # both touch the prey, individual: both get +1
        ("individual", [[0, 0, 0]], [[1, 1]], NO_CHASE, [1, 1, -1], True),
        # predator 1 leaves the area: -1 to it only
        ("shared", [[0, 1, 0]], [[0, 0]], NO_CHASE, [0, -1, 0], True),
        # the prey leaves the area: -1 to it
        ("individual", [[0, 0, 1]], [[0, 0]], NO_CHASE, [0, 0, -1], True),
        # chase costs 0.1 a step, stalk nothing; no event, no end
        ("shared", [[0, 0, 0]], [[0, 0]], np.array([[1, 0]]), [-0.1, 0, 0], False),
        # predator 1 leaves on the step of a shared capture, in chase mode: 1 - 1 - 0.1
        ("shared", [[0, 1, 0]], [[1, 0]], np.array([[0, 1]]), [1, -0.1, -1], True),
        # the prey captured on the step it leaves: -2
        ("shared", [[0, 0, 1]], [[0, 1]], NO_CHASE, [1, 1, -2], True),
    ],
)
def test_reward_table(sharing, wall, prey, modes, expected, terminated) -> None:
    config = TaskConfig(n_predators=2, chase_cost=0.1, reward_sharing=sharing)
    out = task.outcome(config, contacts(wall, prey), modes)
    np.testing.assert_allclose(out.rewards[0], expected, atol=1e-12)
    assert out.terminated[0] == terminated


def test_contain_pays_for_walls_without_ending() -> None:
    config = TaskConfig(n_predators=1, chase_cost=0.01, wall_rule="contain")
    out = task.outcome(config, contacts([[1, 1]], [[0]]), np.array([[1]]))
    np.testing.assert_allclose(out.rewards[0], [-1.01, -1])
    assert not out.terminated[0]


def test_start_positions_never_overlap() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        p = task.sample_start(rng, 4)
        assert (np.abs(p) <= 0.5).all()
        gaps = [np.hypot(*(p[i] - p[j])) for i in range(4) for j in range(i)]
        assert min(gaps) >= 0.1
