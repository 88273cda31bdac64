"""The env through the ecosystem's own checkers, plus determinism and bad input."""

import hashlib
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import api_test, parallel_api_test, seed_test

import pursuit_bench
from pursuit_bench import CONDITIONS
from pursuit_bench.rules.policies import AlwaysStalk, FleeingPrey


def test_ten_conditions_by_name() -> None:
    assert len(CONDITIONS) == 10
    assert sum(c.n_predators for c in CONDITIONS.values()) == 22  # predator panels
    c = CONDITIONS["2p-high-individual"]
    assert (c.n_predators, c.chase_cost, c.reward_sharing) == (2, 0.1, "individual")
    assert CONDITIONS["1p-low"].chase_cost == 0.01


@pytest.mark.parametrize("condition", list(CONDITIONS))
def test_pettingzoo_api_tests(condition: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a PettingZoo API warning fails the test, except:
        # the spec (docs/spec.md) fixes the predators' action space as MultiDiscrete([2, 12]), which api_test flags
        warnings.filterwarnings("ignore", message="Action space for each agent probably should be")
        parallel_api_test(pursuit_bench.parallel_env(condition), num_cycles=400)
        api_test(pursuit_bench.aec_env(condition), num_cycles=400)
        seed_test(lambda: pursuit_bench.aec_env(condition), num_cycles=200)


def rollout_digest(condition: str, seed: int, steps: int) -> str:
    """sha256 of every observation and reward over ``steps`` steps (episodes reset as they end),
    with actions drawn from a generator seeded alongside."""
    env = pursuit_bench.parallel_env(condition)
    rng = np.random.default_rng(seed)
    digest = hashlib.sha256()
    obs, _ = env.reset(seed=seed)
    for _ in range(steps):
        if not env.agents:
            obs, _ = env.reset()
        actions = {a: (rng.integers(0, [2, 12]) if a != "prey_0" else int(rng.integers(12))) for a in env.agents}
        obs, rewards, *_ = env.step(actions)
        for a in env.possible_agents:
            digest.update(obs[a].tobytes())
            digest.update(np.float64(rewards[a]).tobytes())
    return digest.hexdigest()


def test_same_seed_same_1000_steps_in_two_envs_and_two_processes() -> None:
    here = rollout_digest("3p-high-shared", 7, 1000)
    assert here == rollout_digest("3p-high-shared", 7, 1000)
    # imported by its file's folder, not as ``tests.…``: sleap-io (movement's dependency) installs a
    # top-level package named ``tests`` that would be found first
    code = "from test_env_api import rollout_digest; print(rollout_digest('3p-high-shared', 7, 1000))"
    here_folder = Path(__file__).resolve().parent
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(here_folder), os.environ.get("PYTHONPATH", "")])}
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    assert other.stdout.strip() == here
    assert here != rollout_digest("3p-high-shared", 8, 1000)


def test_reseeding_the_same_env_repeats_its_episodes() -> None:
    env = pursuit_bench.parallel_env("3p-low-shared")
    first = [env.reset(seed=3)[0]["prey_0"]] + [env.reset()[0]["prey_0"] for _ in range(20)]
    again = [env.reset(seed=3)[0]["prey_0"]] + [env.reset()[0]["prey_0"] for _ in range(20)]
    np.testing.assert_array_equal(first, again)
    assert len({tuple(o[:2]) for o in first}) == 21  # and the starts do differ from episode to episode


def test_state_render_and_infos() -> None:
    env = pursuit_bench.parallel_env("2p-low-shared", render_mode="rgb_array")
    _obs, infos = env.reset(seed=3)
    state = env.state()
    assert state.shape == (12,) and env.state_space.contains(state)
    frame = env.render()
    assert frame is not None and frame.dtype == np.uint8 and frame.shape == (400, 400, 3)
    assert (frame[..., 0] > 200).any() and (frame[..., 2] > 200).any()  # red and blue disks drawn
    _, _, _, _, infos = env.step({"predator_0": [1, 0], "predator_1": [0, 0], "prey_0": 6})
    assert set(infos["predator_0"]) >= {"captured", "left_area", "mode", "distance_to_prey"}
    assert infos["predator_0"]["mode"] == 1 and infos["predator_1"]["mode"] == 0
    assert pursuit_bench.parallel_env("1p-low").render() is None


def test_given_start_positions() -> None:
    env = pursuit_bench.parallel_env("1p-low")
    obs, _ = env.reset(options={"positions": [[0.1, 0.2], [-0.3, 0.4]]})
    np.testing.assert_allclose(obs["predator_0"][:2], [0.1, 0.2], atol=1e-7)
    with pytest.raises(ValueError, match="positions"):
        env.reset(options={"positions": [[0.1, 0.2], [2.0, 0.0]]})


def test_truncation_at_max_steps_is_not_termination() -> None:
    env = pursuit_bench.parallel_env("1p-low", max_steps=5)
    env.reset(options={"positions": [[-0.4, 0.0], [0.4, 0.0]]})
    for _t in range(5):
        _, _, term, trunc, _ = env.step({"predator_0": [0, 6], "prey_0": 6})  # both back away
    assert trunc == {"predator_0": True, "prey_0": True} and not any(term.values())
    assert env.agents == []


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"condition": "4p-low"}, "condition='4p-low'"),
        ({"n_predators": 4}, "n_predators=4"),
        ({"chase_cost": -0.1}, "chase_cost=-0.1"),
        ({"chase_cost": float("nan")}, "chase_cost=nan"),
        ({"reward_sharing": "half"}, "reward_sharing='half'"),
        ({"wall_rule": "bounce"}, "wall_rule='bounce'"),
        ({"render_mode": "human"}, "render_mode='human'"),
        ({"condition": "1p-low", "n_predators": 2}, "already fixes"),
        ({"speed": 3}, "unknown option"),
    ],
)
def test_bad_options_are_value_errors(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        pursuit_bench.parallel_env(**kwargs)


@pytest.mark.parametrize(
    ("agent", "action", "match"),
    [
        ("predator_0", [2, 0], "predator_0"),
        ("predator_0", [0, 12], "predator_0"),
        ("predator_0", [0, -1], "predator_0"),
        ("predator_0", [1, 2, 3], "shape"),
        ("predator_0", 3, "shape"),
        ("predator_0", [float("nan"), 0], "predator_0"),
        ("prey_0", 12, "prey_0"),
        ("prey_0", float("nan"), "prey_0"),
        ("prey_0", [1, 2], "prey_0"),
        ("prey_0", "left", "prey_0"),
    ],
)
def test_bad_actions_name_the_agent(agent: str, action: object, match: str) -> None:
    env = pursuit_bench.parallel_env("2p-low-shared")
    env.reset(seed=0)
    actions: dict[str, object] = {"predator_0": [0, 0], "predator_1": [0, 0], "prey_0": 0}
    actions[agent] = action
    with pytest.raises(ValueError, match=match):
        env.step(actions)


def test_missing_or_unknown_agents_and_finished_episodes() -> None:
    env = pursuit_bench.parallel_env("1p-low", max_steps=1)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="missing action for prey_0"):
        env.step({"predator_0": [0, 0]})
    with pytest.raises(ValueError, match="predator_7"):
        env.step({"predator_0": [0, 0], "prey_0": 0, "predator_7": [0, 0]})
    env.step({"predator_0": [0, 0], "prey_0": 0})
    with pytest.raises(ValueError, match="reset"):
        env.step({"predator_0": [0, 0], "prey_0": 0})


@pytest.mark.parametrize("agent", ["predator_0", "prey_0"])
def test_single_agent_view_passes_check_env(agent: str) -> None:
    env = gymnasium.make("pursuit_bench/Pursuit-v0", agent=agent, condition="2p-high-shared")
    check_env(env.unwrapped)
    obs, _ = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    done = False
    while not done:
        obs, reward, terminated, truncated, _info = env.step(env.action_space.sample())
        done = terminated or truncated
    assert isinstance(reward, float)


def test_single_agent_view_uses_given_opponents() -> None:
    env = gymnasium.make(
        "pursuit_bench/Pursuit-v0", agent="prey_0", condition="1p-high", opponents={"predator_0": AlwaysStalk()}
    )
    env.reset(seed=0)
    *_, _info = env.step(0)
    assert isinstance(env.unwrapped.opponents["predator_0"], AlwaysStalk)
    with pytest.raises(ValueError, match="agent='wolf'"):
        gymnasium.make("pursuit_bench/Pursuit-v0", agent="wolf")
    with pytest.raises(ValueError, match="opponents"):
        gymnasium.make("pursuit_bench/Pursuit-v0", agent="prey_0", opponents={"prey_0": FleeingPrey()})


def test_every_name_the_readme_gives_works_as_written_after_importing_the_package() -> None:
    """Each dotted ``pursuit_bench.…`` name in the README and in docs/use.md (the env from Python)
    is reached, in a fresh interpreter, by attributes alone after ``import pursuit_bench`` (the
    layers import their modules on first use), as a user types it."""
    root = Path(__file__).resolve().parent.parent
    readme = (root / "README.md").read_text() + (root / "docs" / "use.md").read_text()
    names = sorted(set(re.findall(r"pursuit_bench(?:\.[A-Za-z_][A-Za-z_0-9]*)+", readme)))
    assert {"pursuit_bench.training.evaluate.evaluate_agents", "pursuit_bench.rules.navigation"} <= set(names)
    code = (
        "import functools, sys, pursuit_bench\n"
        "for name in sys.argv[1:]:\n"
        "    functools.reduce(getattr, name.split('.')[1:], pursuit_bench)\n"
        "assert 'seed' in next(iter(pursuit_bench.pretrained.info('1p-high').values()))\n"
    )
    done = subprocess.run([sys.executable, "-c", code, *names], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_pettingzoo_s_versioned_module() -> None:
    from pursuit_bench import pursuit_v0

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", message="Action space for each agent probably should be")
        api_test(pursuit_v0.env(condition="2p-high-shared"), num_cycles=100)
        api_test(pursuit_v0.raw_env(condition="1p-high"), num_cycles=100)
        parallel_api_test(pursuit_v0.parallel_env(condition="3p-low-individual"), num_cycles=100)
    assert isinstance(pursuit_v0.raw_env("1p-low"), pursuit_v0.parallel_to_aec_wrapper)
    assert pursuit_v0.env is pursuit_bench.aec_env and pursuit_v0.parallel_env is pursuit_bench.parallel_env


@pytest.mark.slow
def test_importing_the_package_pins_mkls_code_path_unless_set() -> None:
    code = "import os, pursuit_bench, torch; torch.ones(3, 3) @ torch.ones(3, 3); print(os.environ['MKL_CBWR'])"
    env = {k: v for k, v in os.environ.items() if k != "MKL_CBWR"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0 and done.stdout.split() == ["AVX2"], done.stderr
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={**env, "MKL_CBWR": "AUTO"})
    assert done.returncode == 0 and done.stdout.split() == ["AUTO"], done.stderr


@pytest.mark.slow
def test_importing_the_package_pins_openblas_kernels_unless_set() -> None:
    # Every OpenBLAS the training loads (numpy's, and SciPy's that the compiled update calls) must run its
    # Haswell kernels whatever the CPU: without the pin, OpenBLAS picks by CPU (SkylakeX, Zen, …) and
    # training's bytes follow. threadpoolctl reads each loaded OpenBLAS's own report of its kernels.
    code = (
        "import os, pursuit_bench, numpy, scipy.linalg\n"
        "from pursuit_bench.agents import fused\n"
        "from threadpoolctl import threadpool_info\n"
        "kinds = sorted({i['architecture'] for i in threadpool_info() if i['internal_api'] == 'openblas'})\n"
        "print(os.environ['OPENBLAS_CORETYPE'], *kinds)"
    )
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["Haswell", "Haswell"], done.stdout
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env={**env, "OPENBLAS_CORETYPE": "Sandybridge"}
    )
    assert done.returncode == 0 and done.stdout.split() == ["Sandybridge", "Sandybridge"], done.stdout + done.stderr
