"""Training throughput: K runs trained one after another versus stacked in one process, and
Stable-Baselines3's DQN on the single-agent view, in one process and one run.

    python benchmarks/bench_train.py [--runs 5] [--steps 100] [--repeats 3]

First the compute bound: the FLOPs of one member-update (batch 64) over a matrix-product rate
measured on this CPU in the same run, and a member-update's time alone and at 24 members as a
ratio to it. Then, for each of 1p-high and 3p-high-shared and each of two schedules (``quick``:
one update per transition on 8 arenas, the earlier sessions' maths; ``reproduction``: one
update per env step of 32 arenas): transitions/s (arena-steps of one run, every agent
learning) and member-updates/s (one gradient step of one agent's network) of one run alone
(one after another, K runs take K times as long) and of K seeds stacked. Then SB3's DQN on
``gymnasium.make("pursuit_bench/Pursuit-v0", agent="prey_0")`` with the same batch size and
network sizes, one update per transition. One torch thread, as on a busy 2-core machine;
medians of ``--repeats`` timed runs, after the replays have filled past ``learning_starts``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium
import numpy as np
import torch

import pursuit_bench  # noqa: F401  (registers the Gymnasium env)
from pursuit_bench.agents.config import PRESET_ARENAS, QUICK, REPRODUCTION
from pursuit_bench.agents.dqn import WALL_FEATURES, DQNLearner
from pursuit_bench.agents.network import HEAD, TRUNK
from pursuit_bench.env.task import obs_size
from pursuit_bench.training.train import TrainConfig, Trainer

AGENT = QUICK.replace(learning_starts=500)


def trainer_rates(configs: list[TrainConfig], steps: int, repeats: int) -> tuple[float, float, float]:
    """Median (transitions/s, member-updates/s, seconds per member-update) of a stack."""
    rates = []
    for _ in range(repeats):
        trainer = Trainer(configs)
        while trainer.groups[0].learner.steps < configs[0].agent.learning_starts:
            trainer.step()  # fill the replays first: we time learning, not warm-up
        updates_before = sum(g.learner.updates * g.learner.members for g in trainer.groups)
        start = time.perf_counter()
        for _ in range(steps):
            trainer.step()
        elapsed = time.perf_counter() - start
        member_updates = sum(g.learner.updates * g.learner.members for g in trainer.groups) - updates_before
        transitions = steps * sum(c.num_envs for c in configs)
        rates.append((transitions / elapsed, member_updates / elapsed))
    transitions = statistics.median(r[0] for r in rates)
    updates = statistics.median(r[1] for r in rates)
    return transitions, updates, 1.0 / updates if updates > 0 else float("nan")


def member_update_flops(n_obs: int, n_actions: int, batch: int) -> float:
    """Floating-point operations of one member-update: the dueling network's matrix products
    (2 per multiply-add) for the online pass on s, the online and target passes on s' and the
    backward pass (twice the forward's products), the loss and Adam ignored."""
    trunk = n_obs * TRUNK[0] + TRUNK[0] * TRUNK[1]
    heads = TRUNK[1] * HEAD + HEAD + TRUNK[1] * HEAD + HEAD * n_actions
    forward = 2.0 * batch * (trunk + heads)
    return 3 * forward + 2 * forward


def matmul_rate(repeats: int) -> float:
    """FLOP/s of this CPU on one thread, from 256×256 matrix products (median of repeats)."""
    a, b = torch.randn(256, 256), torch.randn(256, 256)
    rates = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(200):
            torch.mm(a, b)
        rates.append(200 * 2 * 256**3 / (time.perf_counter() - start))
    return statistics.median(rates)


def member_update_seconds(members: int, n_obs: int, repeats: int) -> float:
    """Median seconds per member-update of a learner with ``members`` members (prey-sized
    network, batch of AGENT), its replay filled."""
    learner = DQNLearner(n_obs, 12, AGENT, members=members, seed=0)
    rng = np.random.default_rng(0)
    for _ in range(20):
        obs = rng.normal(size=(members, 100, n_obs)).astype(np.float32)
        learner.store(
            obs, rng.integers(0, 12, (members, 100)), rng.normal(size=(members, 100)), obs, np.zeros((members, 100))
        )
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(50):
            learner.update()
        times.append((time.perf_counter() - start) / (50 * members))
    return statistics.median(times)


def sb3_rates(steps: int, repeats: int) -> tuple[float, float] | None:
    """SB3 DQN's (transitions/s, updates/s), or None without stable-baselines3."""
    try:
        from stable_baselines3 import DQN
    except ImportError:
        return None
    rates = []
    for repeat in range(repeats):
        env = gymnasium.make("pursuit_bench/Pursuit-v0", agent="prey_0", condition="1p-high")
        model = DQN(
            "MlpPolicy",
            env,
            learning_rate=AGENT.learning_rate,
            buffer_size=AGENT.buffer_size,
            learning_starts=AGENT.learning_starts,
            batch_size=AGENT.batch_size,
            gamma=AGENT.gamma,
            train_freq=1,
            gradient_steps=1,
            policy_kwargs={"net_arch": [64, 64]},
            seed=repeat,
            device="cpu",
        )
        model.learn(total_timesteps=AGENT.learning_starts + 10)
        start = time.perf_counter()
        model.learn(total_timesteps=steps, reset_num_timesteps=False)
        rate = steps / (time.perf_counter() - start)
        rates.append(rate)
    rate = statistics.median(rates)
    return rate, rate  # one update per transition


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="K: seeds stacked")
    parser.add_argument("--num-envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=100, help="env steps timed per repeat")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    torch.set_num_threads(1)
    rate = matmul_rate(args.repeats)
    n_obs = obs_size(2)
    bound = member_update_flops(n_obs + WALL_FEATURES, 12, AGENT.batch_size) / rate
    print(
        f"matrix products: {rate / 1e9:.1f} GFLOP/s on one thread; one member-update (batch "
        f"{AGENT.batch_size}) is {member_update_flops(n_obs, 12, AGENT.batch_size) / 1e6:.2f} MFLOP: "
        f"bound {bound * 1e3:.3f} ms"
    )
    for members in (1, 24):
        seconds = member_update_seconds(members, n_obs, args.repeats)
        print(f"member-update at {members:2d} members: {seconds * 1e3:.3f} ms = {seconds / bound:.1f}x the bound")
    print(f"{'':36s} {'transitions/s':>14s} {'member-updates/s':>17s} {'ms/member-update':>17s} {'x bound':>8s}")
    schedules = (
        ("quick", AGENT, args.num_envs),  # one update per transition: the maths of earlier sessions
        ("reproduction", REPRODUCTION.replace(learning_starts=500), PRESET_ARENAS["reproduction"]),
    )
    for schedule, agent, arenas in schedules:
        for condition in ("1p-high", "3p-high-shared"):
            configs = [
                TrainConfig(condition=condition, agent=agent, num_envs=arenas, seed=s, episodes=10**9)
                for s in range(args.runs)
            ]
            alone = trainer_rates(configs[:1], args.steps, args.repeats)
            stacked = trainer_rates(configs, max(1, args.steps // 2), args.repeats)
            for label, (t, u, sec) in (
                (f"{condition}, {schedule}, one run", alone),
                (f"{condition}, {schedule}, {args.runs} stacked", stacked),
            ):
                per_update = f"{sec * 1e3:17.3f} {sec / bound:8.1f}" if u > 0 else f"{'–':>17s} {'–':>8s}"
                print(f"{label:36s} {t:14,.0f} {u:17,.0f} {per_update}")
            print(f"  stacked / one after another: {stacked[0] / alone[0]:.2f}x transitions/s")
    sb3 = sb3_rates(args.steps * 4, args.repeats)
    if sb3 is None:
        print("SB3 DQN: not installed (pip install stable-baselines3)")
        return
    label = "SB3 DQN, single-agent view"
    print(f"{label:36s} {sb3[0]:14,.0f} {sb3[1]:17,.0f} {1e3 / sb3[1]:17.3f} {1 / sb3[1] / bound:8.1f}")


if __name__ == "__main__":
    main()
