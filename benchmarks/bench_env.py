"""Env speed side by side with the peers, in one process and one run.

Single envs (PettingZoo parallel API, actions sampled from each env's own spaces, resets when an
episode ends): ours on both backends and MPE2's ``simple_tag``. Batched envs (random actions
drawn every step, autoreset): ours on both backends at several sizes, VMAS ``simple_tag`` on the
CPU and JaxMARL ``MPE_simple_tag_v3`` under ``jit(vmap(step))`` on the CPU. The single-agent
Gymnasium view N at once: ``gymnasium.make_vec`` (ours, over the batched core) against
Gymnasium's own ``SyncVectorEnv`` over N envs. Ours with 5 obstacles beside ours without, single
and batched at 256 arenas (the target: within 1.5× of the speed without). Every peer is set
to 3 predators (adversaries), 1 prey (good agent) and no obstacles; peers that are not
installed are skipped (``bash scripts/bench.sh`` installs them). Each figure is the median of
``--repeats`` timed runs after a warm-up.

    python benchmarks/bench_env.py [--repeats 5] [--sizes 64 256 1024 4096]
"""

from __future__ import annotations

import argparse
import statistics
import time
import warnings
from collections.abc import Callable
from typing import Any

import gymnasium
import numpy as np

import pursuit_bench
from pursuit_bench.env.vector import VectorPursuitEnv

CONDITION = "3p-high-shared"
OBSTACLES = 5


def median_rate(run: Callable[[], None], work: int, repeats: int) -> float:
    """Median of ``work`` units per second over ``repeats`` calls of ``run`` (after a warm-up)."""
    run()
    rates = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        rates.append(work / (time.perf_counter() - start))
    return statistics.median(rates)


def single_env(env: Any, steps: int, repeats: int) -> float:
    def run() -> None:
        env.reset(seed=0)
        for _ in range(steps):
            if not env.agents:
                env.reset()
            env.step({a: env.action_space(a).sample() for a in env.agents})

    return median_rate(run, steps, repeats)


def ours_batched(backend: str, num_envs: int, steps: int, repeats: int, obstacles: int = 0) -> float:
    env = VectorPursuitEnv(num_envs, CONDITION, backend=backend, obstacles=obstacles)  # type: ignore[arg-type]
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = (num_envs, env.n_agents)

    def run() -> None:
        for _ in range(steps):
            env.step(np.stack([rng.integers(0, 2, shape), rng.integers(0, 12, shape)], axis=-1))

    return median_rate(run, steps * num_envs, repeats)


def gymnasium_vector(mode: str, num_envs: int, steps: int, repeats: int) -> float:
    """Env steps per second (arena-steps) of the single-agent view, N at once: ours
    (``gymnasium.make_vec``, the batched core) or Gymnasium's ``SyncVectorEnv`` over N envs,
    both same-step autoreset, sampled actions."""
    from gymnasium.vector import AutoresetMode, SyncVectorEnv

    kwargs = {"agent": "predator_0", "condition": CONDITION}
    if mode == "ours":
        env = gymnasium.make_vec("pursuit_bench/Pursuit-v0", num_envs=num_envs, **kwargs)
    else:
        makers = [lambda: gymnasium.make("pursuit_bench/Pursuit-v0", **kwargs) for _ in range(num_envs)]
        env = SyncVectorEnv(makers, autoreset_mode=AutoresetMode.SAME_STEP)
    env.reset(seed=0)
    env.action_space.seed(0)

    def run() -> None:
        for _ in range(steps):
            env.step(env.action_space.sample())

    return median_rate(run, steps * num_envs, repeats)


def mpe2_single(steps: int, repeats: int) -> float | None:
    try:
        from mpe2 import simple_tag_v3
    except ImportError:
        return None
    return single_env(simple_tag_v3.parallel_env(num_good=1, num_adversaries=3, num_obstacles=0), steps, repeats)


def vmas_batched(num_envs: int, steps: int, repeats: int) -> float | None:
    try:
        import vmas
    except ImportError:
        return None
    env = vmas.make_env(
        "simple_tag",
        num_envs=num_envs,
        device="cpu",
        continuous_actions=False,
        seed=0,
        num_good_agents=1,
        num_adversaries=3,
        num_landmarks=0,
    )
    env.reset()

    def run() -> None:
        for _ in range(steps):
            env.step([env.get_random_action(agent) for agent in env.agents])

    return median_rate(run, steps * num_envs, repeats)


def jaxmarl_batched(num_envs: int, steps: int, repeats: int) -> float | None:
    try:
        import jax
        import jaxmarl
    except ImportError:
        return None
    env = jaxmarl.make("MPE_simple_tag_v3", num_good_agents=1, num_adversaries=3, num_obs=0)
    n_actions = env.action_space(env.agents[0]).n

    @jax.jit
    def step(key: Any, state: Any) -> tuple[Any, Any]:
        key, act_key, step_key = jax.random.split(key, 3)
        act_keys = jax.random.split(act_key, env.num_agents)
        actions = {
            a: jax.random.randint(k, (num_envs,), 0, n_actions) for a, k in zip(env.agents, act_keys, strict=True)
        }
        _, state, _, _, _ = jax.vmap(env.step)(jax.random.split(step_key, num_envs), state, actions)
        return key, state

    key = jax.random.PRNGKey(0)
    _, state = jax.vmap(env.reset)(jax.random.split(key, num_envs))
    carry = [key, state]

    def run() -> None:
        for _ in range(steps):
            carry[0], carry[1] = step(carry[0], carry[1])
        jax.block_until_ready(carry[1])

    return median_rate(run, steps * num_envs, repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--single-steps", type=int, default=3000)
    parser.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024, 4096])
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    rows: list[tuple[str, int, float | None]] = []

    def report(name: str, size: int, rate: float | None) -> None:
        rows.append((name, size, rate))
        shown = "not installed" if rate is None else f"{rate:>12,.0f}"
        print(f"{name:42s} {size:>5d} {shown}", flush=True)

    print(f"{'env':42s} {'envs':>5s} {'steps/s':>12s}")
    report(
        "pursuit-bench single (pymunk)",
        1,
        single_env(pursuit_bench.parallel_env(CONDITION), args.single_steps, args.repeats),
    )
    report(
        "pursuit-bench single (numpy)",
        1,
        single_env(pursuit_bench.parallel_env(CONDITION, backend="numpy"), args.single_steps, args.repeats),
    )
    report("MPE2 simple_tag", 1, mpe2_single(args.single_steps // 3, args.repeats))
    for size in args.sizes:
        steps = max(20, 100_000 // size)  # long enough for a stable median at every size
        report("pursuit-bench batched (pymunk)", size, ours_batched("pymunk", size, steps, args.repeats))
        report("pursuit-bench batched (numpy)", size, ours_batched("numpy", size, steps, args.repeats))
        report("VMAS simple_tag (cpu)", size, vmas_batched(size, steps, args.repeats))
        report("JaxMARL MPE_simple_tag_v3 (cpu, jit+vmap)", size, jaxmarl_batched(size, steps, args.repeats))

    single = args.single_steps
    for obstacles in (0, OBSTACLES):
        env = pursuit_bench.parallel_env(CONDITION, obstacles=obstacles)
        report(f"pursuit-bench single, {obstacles} obstacles", 1, single_env(env, single, args.repeats))
        rate = ours_batched("pymunk", 256, 400, args.repeats, obstacles)
        report(f"pursuit-bench batched (pymunk), {obstacles} obstacles", 256, rate)

    for size in (16, 256):
        steps = max(10, 20_000 // size)
        report("Gymnasium make_vec, ours (batched core)", size, gymnasium_vector("ours", size, steps, args.repeats))
        report("Gymnasium SyncVectorEnv over single envs", size, gymnasium_vector("sync", size, steps, args.repeats))

    def best(name: str, size: int | None = None) -> float | None:
        rates = [r for n, s, r in rows if n == name and r is not None and (size is None or s == size)]
        return max(rates) if rates else None

    print()
    for label, ours, peer in [
        ("single env (pymunk) vs MPE2", best("pursuit-bench single (pymunk)"), best("MPE2 simple_tag")),
        ("single env (numpy) vs MPE2", best("pursuit-bench single (numpy)"), best("MPE2 simple_tag")),
        (
            "batched pymunk vs VMAS, each at its best size",
            best("pursuit-bench batched (pymunk)"),
            best("VMAS simple_tag (cpu)"),
        ),
        (
            "Gymnasium vector env vs SyncVectorEnv at 256 envs",
            best("Gymnasium make_vec, ours (batched core)", 256),
            best("Gymnasium SyncVectorEnv over single envs", 256),
        ),
        (
            f"single env, no obstacles vs {OBSTACLES} (target <= 1.5)",
            best("pursuit-bench single, 0 obstacles"),
            best(f"pursuit-bench single, {OBSTACLES} obstacles"),
        ),
        (
            f"batched at 256, no obstacles vs {OBSTACLES} (target <= 1.5)",
            best("pursuit-bench batched (pymunk), 0 obstacles"),
            best(f"pursuit-bench batched (pymunk), {OBSTACLES} obstacles"),
        ),
        (
            "numpy backend vs JaxMARL at 1024 envs",
            best("pursuit-bench batched (numpy)", 1024),
            best("JaxMARL MPE_simple_tag_v3 (cpu, jit+vmap)", 1024),
        ),
    ]:
        if ours is not None and peer is not None:
            print(f"ratio {label}: {ours / peer:.1f}x")


if __name__ == "__main__":
    main()
