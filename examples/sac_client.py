"""A real client of the continuous single-agent view: Stable-Baselines3's SAC trains a predator
against the scripted `FleeingPrey` and is compared with a random policy on the same seeds.

    python examples/sac_client.py [--condition 1p-low] [--steps 20000] [--episodes 100]

Prints the mean return (and capture rate) of the trained policy, deterministic, and of uniform
random actions, over the same evaluation seeds; the README quotes a run.
"""

from __future__ import annotations

import argparse
import time

import gymnasium
import numpy as np
import torch
from stable_baselines3 import SAC

import pursuit_bench  # noqa: F401  (registers the env)


def evaluate(env: gymnasium.Env, act, episodes: int) -> tuple[float, float]:
    returns, captures = [], []
    for episode in range(episodes):
        obs, _ = env.reset(seed=10_000 + episode)
        total, done, info = 0.0, False, {}
        while not done:
            obs, reward, terminated, truncated, info = env.step(act(obs))
            total += float(reward)
            done = terminated or truncated
        returns.append(total)
        captures.append(bool(info.get("captured")))
    return float(np.mean(returns)), float(np.mean(captures))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--condition", default="1p-low")
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    torch.set_num_threads(1)
    make = lambda: gymnasium.make(  # noqa: E731
        "pursuit_bench/Pursuit-v0", agent="predator_0", condition=args.condition, continuous=True
    )
    env = make()
    start = time.perf_counter()
    model = SAC("MlpPolicy", env, seed=args.seed, device="cpu", learning_starts=1000, verbose=0)
    model.learn(args.steps)
    minutes = (time.perf_counter() - start) / 60
    trained = evaluate(make(), lambda o: model.predict(o, deterministic=True)[0], args.episodes)
    rng = np.random.default_rng(args.seed)
    random = evaluate(make(), lambda o: rng.uniform(-1, 1, 2).astype(np.float32), args.episodes)
    print(f"{args.condition}, predator_0 against FleeingPrey, continuous actions, {args.steps} SAC steps")
    print(f"training took {minutes:.1f} min")
    print(f"SAC:    mean return {trained[0]:+.3f}, capture rate {trained[1]:.0%} ({args.episodes} episodes)")
    print(f"random: mean return {random[0]:+.3f}, capture rate {random[1]:.0%} (same seeds)")


if __name__ == "__main__":
    main()
