"""Obstacles: the paper's task unchanged without them, solid contacts on both backends, the
placement rule, range readings against a naive computation, avoidance, the checkers, the CLI."""

import json
import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from cli_helpers import load_script, run_cli
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st
from pettingzoo.test import parallel_api_test, parallel_seed_test
from test_recording import read_back

import pursuit_bench
from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.env import task
from pursuit_bench.env.conditions import OBSTACLE_GAP, TaskConfig, resolve_condition
from pursuit_bench.env.core import PursuitCore
from pursuit_bench.env.obstacles import RANGE_CAP, START_GAP
from pursuit_bench.env.vector import VectorPursuitEnv
from pursuit_bench.env.world import CONTACT_TOLERANCE, HALF_SIZE, RADIUS
from pursuit_bench.rules.navigation import SAFETY_DISTANCE, avoid, navigate, parallel_navigation
from pursuit_bench.rules.policies import AlwaysChase, FleeingPrey
from pursuit_bench.training.evaluate import run_episodes
from pursuit_bench.trajectories.recording import Recorder

make_paper_trajectories = load_script("tests/reference/paper_trajectories.py")

DATA = Path(__file__).parent / "data" / "paper-trajectories.json"


@pytest.mark.parametrize("case", json.loads(DATA.read_text())["cases"], ids=lambda c: "-".join(map(str, c["case"][:3])))
def test_without_obstacles_the_trajectories_are_those_before_obstacles_existed(case: dict) -> None:
    # digests written by the commit before obstacles (tests/reference/paper_trajectories.py, run on that checkout)
    assert make_paper_trajectories.digests(tuple(case["case"])) == case["sha256"]


def random_actions(rng: np.random.Generator, arenas: int, n_agents: int, spread: int = 12) -> np.ndarray:
    return np.stack([rng.integers(0, 2, (arenas, n_agents)), rng.integers(0, spread, (arenas, n_agents))], -1)


def overlaps(positions: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """(B, n_agents, K) how far each disk reaches into each obstacle (negative: apart)."""
    gaps = np.linalg.norm(positions[:, :, None] - obstacles[:, None, :, :2], axis=-1)
    return obstacles[:, None, :, 2] + RADIUS - gaps


@pytest.mark.parametrize("backend", ["pymunk", "numpy"])
@pytest.mark.parametrize("wall_rule", ["terminate", "contain"])
def test_no_agent_is_ever_inside_an_obstacle(backend: str, wall_rule: str) -> None:
    # mostly straight at their targets (directions 0-2), so that they run into obstacles often
    env = VectorPursuitEnv(16, "3p-high-shared", backend=backend, obstacles=8, wall_rule=wall_rule)  # type: ignore[arg-type]
    env.reset(seed=4)
    rng = np.random.default_rng(0)
    deepest, touching = -np.inf, 0
    for _ in range(3000):
        before = env.obstacles  # the episode's: an autoreset replaces them
        _, _, _, _, info = env.step(random_actions(rng, 16, 4, spread=3))
        reach = overlaps(info["positions"], before)
        deepest = max(deepest, reach.max())
        touching += int(info["touching_obstacle"].sum())
        assert (info["touching_obstacle"] == (reach >= -CONTACT_TOLERANCE).any(-1)).all()
    assert deepest <= 1e-9  # the stated tolerance
    assert touching > 1000  # the rollouts did push into obstacles


def test_both_backends_agree_with_obstacles() -> None:
    envs = [
        VectorPursuitEnv(16, "3p-high-shared", backend=b, obstacles=5, wall_rule="contain") for b in ("pymunk", "numpy")
    ]  # type: ignore[arg-type]
    for env in envs:
        env.reset(seed=3)
    rng = np.random.default_rng(0)
    worst = 0.0
    for _ in range(1500):
        actions = random_actions(rng, 16, 4, spread=3)
        (*_, a), (*_, b) = (env.step(actions) for env in envs)
        worst = max(worst, np.abs(a["positions"] - b["positions"]).max())
        assert (a["done"] == b["done"]).all()
    assert worst < 1e-9


def test_obstacles_are_placed_by_the_rule_and_starts_are_clear() -> None:
    config = resolve_condition("3p-high-shared", obstacles=8)  # the most of the default radius
    core = PursuitCore(config, 32)
    rngs = [np.random.default_rng(k) for k in range(32)]
    seen = []
    for _ in range(20):
        core.reset(np.arange(32), rngs)
        placed, starts = core.world.obstacles, core.world.positions
        seen.append(placed.copy())
        r = config.obstacle_radius
        assert placed.shape == (32, 8, 3) and (placed[..., 2] == r).all()
        assert (np.abs(placed[..., :2]) <= HALF_SIZE - r - OBSTACLE_GAP + 1e-12).all()
        apart = np.linalg.norm(placed[:, :, None, :2] - placed[:, None, :, :2], axis=-1)
        apart[:, np.arange(8), np.arange(8)] = np.inf
        assert (apart >= 2 * r + OBSTACLE_GAP - 1e-12).all()
        assert (overlaps(starts, placed) <= -START_GAP + 1e-12).all()
    assert len({a.tobytes() for a in np.concatenate(seen)}) == 32 * 20  # drawn afresh at each reset


def test_the_tightest_allowed_arenas_can_always_be_placed() -> None:
    for count, radius in [(8, 0.15), (6, 0.175), (5, 0.2), (4, 0.225), (3, 0.25)]:
        core = PursuitCore(resolve_condition("3p-low-shared", obstacles=count, obstacle_radius=radius), 64)
        rngs = [np.random.default_rng(k) for k in range(64)]
        for _ in range(10):
            core.reset(np.arange(64), rngs)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"obstacles": 9}, "obstacles=9: expected an integer from 0 to 8"),
        ({"obstacles": -1}, "obstacles=-1"),
        ({"obstacles": 2.0}, "obstacles=2.0"),
        ({"obstacles": 1, "obstacle_radius": 0.05}, "obstacle_radius=0.05: expected a number from 0.1 to 0.25"),
        ({"obstacles": 8, "obstacle_radius": 0.25}, "no room for them"),
    ],
)
def test_bad_obstacle_options_are_refused(options: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        TaskConfig(**options)


def naive_ranges(position: np.ndarray, los: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """The 12 readings of one agent by the textbook ray–circle and ray–plane formulas."""
    out = []
    for k in range(12):
        angle = np.arctan2(los[1], los[0]) - k * np.pi / 6
        u = np.array([np.cos(angle), np.sin(angle)])
        hits = [RANGE_CAP]
        for axis in (0, 1):
            for wall in (-(HALF_SIZE - RADIUS), HALF_SIZE - RADIUS):
                if abs(u[axis]) > 1e-12 and (wall - position[axis]) / u[axis] >= 0:
                    hits.append((wall - position[axis]) / u[axis])
        for x, y, r in obstacles:
            # |p + t u - c|^2 = (r + RADIUS)^2: t^2 + 2 t u.(p - c) + |p - c|^2 - (r + RADIUS)^2 = 0
            d = position - np.array([x, y])
            b, c = u @ d, d @ d - (r + RADIUS) ** 2
            if b >= 0:
                continue  # pointing away from the obstacle: never hits it
            if c <= 0:
                hits.append(0.0)
            elif b * b - c >= 0 and -b - np.sqrt(b * b - c) >= 0:
                hits.append(-b - np.sqrt(b * b - c))
        out.append(max(min(hits), 0.0))
    return np.array(out)


def test_range_readings_match_a_naive_ray_circle_computation() -> None:
    env = VectorPursuitEnv(8, "3p-high-shared", obstacles=6)
    obs, _ = env.reset(seed=11)
    rng = np.random.default_rng(1)
    n_obs = task.obs_size(4)
    checked = 0
    for _ in range(60):
        los = env.core._los.copy()
        positions, placed = env.core.world.positions.copy(), env.obstacles
        for b in range(8):
            for i in range(4):
                expected = naive_ranges(positions[b, i], los[b, i], placed[b])
                np.testing.assert_allclose(obs[b, i, n_obs:], expected, atol=1e-5)  # float32 observations
                checked += int((expected < RANGE_CAP).sum())
        obs, *_ = env.step(random_actions(rng, 8, 4, spread=3))
    assert checked > 5000


def test_observation_state_and_obstacles_attribute() -> None:
    env = pursuit_bench.parallel_env("2p-high-shared", obstacles=4, obstacle_radius=0.2)
    obs, _ = env.reset(seed=0)
    assert obs["predator_0"].shape == (16 + 12,) and env.observation_space("prey_0").shape == (28,)
    assert env.obstacles.shape == (4, 3) and (env.obstacles[:, 2] == 0.2).all()
    state = env.state()
    assert state.shape == (3 * 4 + 4 * 3,) and env.state_space.contains(state)
    np.testing.assert_allclose(state[12:].reshape(4, 3), env.obstacles, atol=1e-6)
    frame = pursuit_bench.parallel_env("1p-low", obstacles=3, render_mode="rgb_array")
    frame.reset(seed=0)
    grey = (frame.render() == (120, 120, 120)).all(-1).sum()
    area = 3 * np.pi * 0.15**2 * (400 / 2.1) ** 2
    assert 0.9 * area < grey < 1.1 * area  # the obstacles drawn at their size
    empty = pursuit_bench.parallel_env("1p-low")
    assert empty.reset(seed=0)[0]["predator_0"].shape == (10,) and empty.obstacles.shape == (0, 3)


def test_given_positions_need_the_obstacles_too() -> None:
    env = pursuit_bench.parallel_env("1p-low", obstacles=1)
    positions = [[-0.5, 0.0], [0.5, 0.0]]
    with pytest.raises(ValueError, match="obstacles: expected finite numbers of shape"):
        env.reset(options={"positions": positions})
    obs, _ = env.reset(options={"positions": positions, "obstacles": [[0.0, 0.0, 0.15]]})
    assert obs["predator_0"][10] == pytest.approx(1.0 - 0.5 - 0.2, abs=1e-6)  # straight at the prey: the obstacle


def test_pettingzoo_and_gymnasium_checkers_pass_with_obstacles() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message="Action space for each agent probably should be")
        parallel_api_test(pursuit_bench.parallel_env("3p-high-individual", obstacles=5), num_cycles=300)
        parallel_seed_test(lambda: pursuit_bench.parallel_env("2p-high-shared", obstacles=5), num_cycles=200)
    for agent in ("predator_0", "prey_0"):
        env = gymnasium.make("pursuit_bench/Pursuit-v0", agent=agent, condition="2p-high-shared", obstacles=5)
        check_env(env.unwrapped, skip_render_check=True)
        assert env.unwrapped.obstacles.shape == (5, 3)
    vec = gymnasium.make_vec("pursuit_bench/Pursuit-v0", num_envs=4, agent="prey_0", condition="1p-high", obstacles=3)
    obs, _ = vec.reset(seed=0)
    assert obs.shape == (4, 22) and vec.single_observation_space.contains(obs[0])
    obs, *_ = vec.step(vec.action_space.sample())
    assert vec.observation_space.contains(obs)
    vec.close()


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.floats(0.0, RANGE_CAP), min_size=12, max_size=12),
    st.integers(0, 11),
)
def test_avoidance_never_picks_a_blocked_direction_when_a_free_one_exists(ranges: list[float], chosen: int) -> None:
    picked = int(avoid(np.array(chosen), np.array(ranges)))
    free = [k for k, r in enumerate(ranges) if r >= SAFETY_DISTANCE]
    if not free:
        assert ranges[picked] == max(ranges)
        return
    assert picked in free
    turn = lambda k: min((k - chosen) % 12, (chosen - k) % 12)  # noqa: E731
    assert turn(picked) == min(turn(k) for k in free)  # the nearest free direction
    if ranges[chosen] >= SAFETY_DISTANCE:
        assert picked == chosen


def test_the_lower_layer_is_parallel_navigation_without_avoidance() -> None:
    env = VectorPursuitEnv(16, "2p-high-shared", obstacles=5)
    obs, _ = env.reset(seed=2)
    predators = obs[:, :2].reshape(-1, obs.shape[-1])
    plain = navigate(predators, 1)
    np.testing.assert_array_equal(plain, parallel_navigation(predators, 1))
    steered = navigate(predators, 1, avoidance=True)
    np.testing.assert_array_equal(steered, avoid(plain, predators[:, -12:]))


def test_scripted_agents_steer_around_obstacles() -> None:
    def play(avoidance: bool) -> tuple[float, float]:
        actors = {
            "predator_0": ScriptedAgent("predator_0", AlwaysChase(avoidance=avoidance)),
            "prey_0": ScriptedAgent("prey_0", FleeingPrey(obstacles=True)),
        }
        played = run_episodes("1p-high", actors, 300, seed=1, num_envs=32, task_options={"obstacles": 5})
        return float(played.contact_steps[:, 0].mean()), float(played.captured.mean())

    (plain, caught_plain), (avoiding, caught_avoiding) = play(False), play(True)
    assert avoiding < 0.5 * plain  # measured 0.29 against 1.40 steps in contact per episode
    assert caught_avoiding > 0.9 and caught_plain > 0.9


def test_a_recording_shows_the_obstacles(tmp_path: Path) -> None:
    path = tmp_path / "eval.rrd"
    names = ["predator_0", "prey_0"]
    actors = {
        "predator_0": ScriptedAgent("predator_0", AlwaysChase()),
        "prey_0": ScriptedAgent("prey_0", FleeingPrey(obstacles=True)),
    }
    with Recorder(path, names, {"condition": "1p-high"}) as recorder:
        run_episodes("1p-high", actors, 3, seed=0, num_envs=1, recorder=recorder, task_options={"obstacles": 4})
    rows = [r for r in read_back(path)["/arena/obstacles"] if r[0] != "static"]
    assert [(episode, step) for episode, step, _ in rows] == [(1, 0), (2, 0), (3, 0)]
    positions = [v for _, _, values in rows for k, v in values.items() if k.endswith("positions")]
    assert all(len(p) == 4 for p in positions) and positions[0] != positions[1]


def test_train_and_eval_with_obstacles(tmp_path: Path) -> None:
    out = tmp_path / "run"
    tiny = ["--episodes", "12", "--num-envs", "4", "--learning-starts", "32", "--batch-size", "16", "--no-record"]
    code, output = run_cli("train", "--condition", "2p-high-shared", "--obstacles", "5", "--out", str(out), *tiny)
    assert code == 0, output
    saved = json.loads((out / "config.json").read_text())["train"]
    assert (saved["obstacles"], saved["obstacle_radius"], saved["avoidance"]) == (5, 0.15, True)
    code, output = run_cli("eval", str(out), "--episodes", "8", "--num-envs", "4", "--no-record")
    assert code == 0, output
    result = json.loads((out / "eval.json").read_text())
    assert result["task_options"] == {"obstacles": 5, "obstacle_radius": 0.15}
    assert set(result["obstacle_collisions"]) == {"predator_0", "predator_1", "prey_0"}
    code, output = run_cli("train", "--condition", "1p-low", "--obstacles", "9", "--out", str(tmp_path / "x"))
    assert code == 2 and "--obstacles" in output and "Traceback" not in output


def test_the_experiment_table_in_the_docs_is_what_the_committed_results_say() -> None:
    obstacle_study = load_script("studies/obstacles/obstacle_study.py")

    table = obstacle_study.markdown(obstacle_study.rows())
    assert table in (Path(__file__).parents[1] / "docs" / "obstacles.md").read_text()
