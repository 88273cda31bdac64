"""Parallel navigation against a prey at constant velocity, and the rule's pure-function form."""

import numba
import numpy as np
import pytest

from pursuit_bench.env import task
from pursuit_bench.env.world import DAMPING, DT, make_world
from pursuit_bench.rules.navigation import (
    _DIRS,
    _PHYSICS,
    APPROACH_DIRECTIONS,
    TIE_TOLERANCE,
    _python_mod,
    constant_bearing_angle,
    parallel_navigation,
    pure_pursuit,
)
from pursuit_bench.rules.policies import PurePursuitPredator

CASES = [  # predator start, prey start, prey velocity
    ((-0.5, -0.5), (0.3, 0.0), (0.0, 0.5)),
    ((-1.5, 0.0), (0.5, 0.0), (0.0, 0.8)),
    ((0.0, 0.0), (1.0, 1.0), (-0.6, 0.2)),
    ((-2.0, -2.0), (1.0, 0.5), (0.3, -0.7)),
]


def signed_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle from vector a to vector b."""
    return float(np.arctan2(a[0] * b[1] - a[1] * b[0], a @ b))


def pursue(rule, predator, prey, prey_velocity, steps=300):
    """A chase-mode predator steered by ``rule`` after a prey held at constant velocity (its
    acceleration cancels the drag exactly), in an arena too large to reach the walls. Returns
    the capture step and, per step, the absolute target direction φ, the constant-bearing angle β
    and the predator's heading relative to the LOS."""
    world = make_world("numpy", 1, 2, half_size=100.0)
    world.reset(np.array([0]), np.array([[predator, prey]], dtype=float))
    world.velocities[0, 1] = prey_velocity
    prey_acc = DAMPING * np.array(prey_velocity) / DT
    phi, beta, heading = [], [], []
    for t in range(1, steps + 1):
        obs, los = task.observe(world.positions, world.velocities)
        acc = np.zeros((1, 2, 2))
        acc[0, 0] = task.ACCEL_CHASE * task.rotate_by_direction(los[0, 0], np.asarray(rule(obs[0, 0])))
        acc[0, 1] = prey_acc
        contacts = world.step(acc)
        line = world.positions[0, 1] - world.positions[0, 0]
        vp, vt = world.velocities[0, 0], world.velocities[0, 1]
        phi.append(np.arctan2(line[1], line[0]))
        alpha = signed_angle(vt, -line)  # target velocity to the target→pursuer vector
        beta.append(constant_bearing_angle(np.hypot(*vt), np.hypot(*vp), alpha))
        heading.append(signed_angle(line, vp))
        if contacts.prey[0, 0]:
            return t, np.array(phi), np.array(beta), np.array(heading)
    raise AssertionError("no capture")


@pytest.mark.parametrize("case", CASES)
def test_always_chase_keeps_the_target_direction_and_captures_no_later_than_pure_pursuit(case) -> None:
    t_parallel, phi, beta, heading = pursue(lambda o: parallel_navigation(o, task.CHASE), *case)
    t_pure, phi_pure, *_ = pursue(pure_pursuit, *case)
    assert t_parallel <= t_pure
    approach = slice(0, -2)  # the last two steps pass within a diameter of the prey
    assert np.degrees(np.ptp(phi[approach])) < 5.0  # nearly constant absolute target direction
    assert np.degrees(np.ptp(phi_pure[:-2])) > 30.0  # pure pursuit lets it swing
    # the course agrees with constant bearing once the predator is moving (β defined): within
    # half the 30° spacing of the directions on every step, within 5° on average
    steady = slice(2, -2)
    error = np.degrees(np.abs(heading[steady] - beta[steady]))
    assert np.isfinite(error).all() and error.mean() < 5.0 and error.max() < 15.0


def test_rule_on_hand_cases() -> None:
    # predator at rest, prey at rest straight ahead: straight at it (k = 0, zero change of φ)
    obs = np.zeros(10)
    obs[6] = 0.5  # prey 0.5 ahead along the LOS
    assert parallel_navigation(obs, task.CHASE) == 0
    # prey crossing to the left (positive v): lead it, turning left (k = 11, 10 or 9)
    obs[9] = 0.8
    assert parallel_navigation(obs, task.CHASE) in (9, 10, 11)
    obs[9] = -0.8  # crossing to the right: k in 1..3
    assert parallel_navigation(obs, task.STALK) in (1, 2, 3)
    # batched over any leading axes, always on the approaching side
    rng = np.random.default_rng(0)
    many = rng.normal(size=(5, 7, 10))
    ks = parallel_navigation(many, rng.integers(0, 2, size=(5, 7)))
    assert ks.shape == (5, 7) and np.isin(ks, APPROACH_DIRECTIONS).all()
    assert (pure_pursuit(many) == 0).all()
    np.testing.assert_array_equal(PurePursuitPredator(task.STALK).act(many[0, 0]), [task.STALK, 0])


def test_constant_bearing_formula() -> None:
    assert constant_bearing_angle(1.0, 2.0, np.pi / 2) == pytest.approx(np.pi / 6)
    assert constant_bearing_angle(0.0, 1.0, 1.0) == 0.0
    assert np.isnan(constant_bearing_angle(2.0, 1.0, np.pi / 2))  # too slow to intercept
    with pytest.raises(ValueError, match="pursuer_speed"):
        constant_bearing_angle(1.0, 0.0, 0.3)


def _rule_in_numpy(observations: np.ndarray, modes: np.ndarray) -> np.ndarray:
    """The rule written out in numpy: every direction's change of φ and distance."""
    accel = np.where(modes == 1, task.ACCEL_CHASE, task.ACCEL_STALK)[..., None, None]
    angles = -task.DIRECTION_STEP * APPROACH_DIRECTIONS
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
    o = observations.astype(np.float64)
    prey_rel = o[..., None, 6:8]
    line = prey_rel + o[..., None, 8:10] * DT - ((1.0 - DAMPING) * o[..., None, 2:4] + accel * DT * dirs) * DT
    phi = np.arctan2(prey_rel[..., 1], prey_rel[..., 0])
    with np.errstate(invalid="ignore"):
        change = np.abs((np.arctan2(line[..., 1], line[..., 0]) - phi + np.pi) % (2 * np.pi) - np.pi)
        tied = change <= np.min(np.where(np.isnan(change), np.inf, change), axis=-1, keepdims=True) + 1e-12
        distance = np.where(tied, np.hypot(line[..., 0], line[..., 1]), np.inf)
    first_smallest = np.array(
        [next((k for k, d in enumerate(row) if d == min(row)), 0) for row in distance.reshape(-1, 7)]
    )
    return APPROACH_DIRECTIONS[first_smallest].reshape(observations.shape[:-1])


def test_the_compiled_rule_is_the_rules_numpy_form() -> None:
    """:func:`parallel_navigation` (compiled, row by row, angles only for the candidates) against
    the rule written out in numpy over random observations, float32 and float64, one mode for all
    or one per row."""
    rng = np.random.default_rng(0)
    obs = rng.normal(size=(4, 500, 16))
    modes = rng.integers(0, 2, size=(4, 500))
    for observations in (obs, obs.astype(np.float32)):
        np.testing.assert_array_equal(parallel_navigation(observations, modes), _rule_in_numpy(observations, modes))
        one_mode = parallel_navigation(observations[0, :5], 1)
        np.testing.assert_array_equal(one_mode, parallel_navigation(observations[0, :5], np.ones(5, dtype=int)))
        assert [parallel_navigation(observations[0, i], 1) for i in range(5)] == one_mode.tolist()


@numba.njit
def _rule_as_written(obs, modes, dirs, approach, chase, accel_stalk, accel_chase, damping, dt):
    """The compiled rule as it was before it chose candidates (every direction's angle and
    distance, the angle wrapped by ``%``): what the candidates must not change, bit for bit."""
    out = np.empty(obs.shape[0], dtype=np.int64)
    for r in range(obs.shape[0]):
        accel = accel_chase if modes[r] == chase else accel_stalk
        px, py = np.float64(obs[r, 6]), np.float64(obs[r, 7])
        nx = px + np.float64(obs[r, 8]) * dt
        ny = py + np.float64(obs[r, 9]) * dt
        vx, vy = np.float64(obs[r, 2]), np.float64(obs[r, 3])
        phi = np.arctan2(py, px)
        best_change, choice, best_distance = np.inf, 0, np.inf
        change = np.empty(len(approach))
        distance = np.empty(len(approach))
        for k in range(len(approach)):
            lx = nx - ((1.0 - damping) * vx + accel * dt * dirs[k, 0]) * dt
            ly = ny - ((1.0 - damping) * vy + accel * dt * dirs[k, 1]) * dt
            change[k] = abs((np.arctan2(ly, lx) - phi + np.pi) % (2 * np.pi) - np.pi)
            distance[k] = np.hypot(lx, ly)
            best_change = min(best_change, change[k])
        for k in range(len(approach)):
            if change[k] <= best_change + TIE_TOLERANCE and distance[k] < best_distance:
                best_distance, choice = distance[k], k
        out[r] = approach[choice]
    return out


def test_the_rule_keeps_every_direction_it_needs_on_hard_cases() -> None:
    """Against the rule as written before it chose candidates, where choosing them could go wrong:
    exact and near ties (symmetric layouts, the prey dead ahead or behind), vectors of zero
    length, tiny and huge scales, infinities and NaN; float64 and float32."""
    rng = np.random.default_rng(1)
    rows = []
    for scale in (1e-300, 1e-200, 1e-8, 1.0, 1e8, 1e200, 1e300):
        rows.append(rng.normal(size=(200, 16)) * scale)
    symmetric = np.zeros((200, 16))
    symmetric[:, 6] = rng.choice([-1.0, 1.0], 200) * rng.uniform(1e-6, 2, 200)  # the prey on the line of sight
    symmetric[:100, 2] = rng.uniform(-1, 1, 100)  # own velocity along it: still symmetric
    rows += [symmetric, symmetric * 1e-7]
    near = symmetric.copy()
    near[:, 7] = rng.choice([-1, 1], 200) * 10.0 ** rng.uniform(-16, -8, 200)  # just off the line
    rows.append(near)
    odd = rng.normal(size=(60, 16))
    odd[:10] = 0.0
    odd[10:20, 6:8] = 0.0
    odd[20:30, 8] = np.nan
    odd[30:40, 6] = np.inf
    odd[40:50, 2] = -np.inf
    odd[50:60, 6:10] = odd[50:60, 6:10] * 1e160
    rows.append(odd)
    obs = np.concatenate(rows)
    with np.errstate(over="ignore"):  # the huge rows become infinities in float32: cases too
        single = obs.astype(np.float32)
    for observations in (obs, single):
        for mode in (0, 1):
            modes = np.full(len(observations), mode)
            expected = _rule_as_written(observations, modes, _DIRS, APPROACH_DIRECTIONS, *_PHYSICS)
            np.testing.assert_array_equal(parallel_navigation(observations, modes), expected)


def test_the_rules_remainder_is_pythons() -> None:
    """``_python_mod`` (the rule's angle wrap, without ``fmod`` where the angles lie) gives the
    bits of Python's ``%``, signed zeros, the range's ends, infinities and NaN included."""
    period = 2 * np.pi
    edges = [0.0, -0.0, period, -period, 2 * period, -2 * period, 3 * np.pi, np.pi, -np.pi, 1e-300, -1e-300]
    edges += [np.nextafter(x, d) for x in (period, -period, 2 * period, 0.0) for d in (-np.inf, np.inf)]
    edges += [1e20, -1e20, np.inf, -np.inf, np.nan]
    values = np.concatenate([np.random.default_rng(0).uniform(-4 * np.pi, 6 * np.pi, 20_000), edges])
    for x in values.tolist():
        ours, pythons = _python_mod(x, period), x % period
        assert np.float64(ours).tobytes() == np.float64(pythons).tobytes() or (np.isnan(ours) and np.isnan(pythons)), x
