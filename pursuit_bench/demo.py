"""A scripted demo: in each paper condition, always-chase vs always-stalk predators against the
fleeing prey. ``python -m pursuit_bench.demo``"""

from __future__ import annotations

import numpy as np

import pursuit_bench
from pursuit_bench.policies import AlwaysChase, AlwaysStalk, FleeingPrey


def mean_predator_return(condition: str, predator: AlwaysChase | AlwaysStalk, episodes: int, seed: int) -> float:
    env = pursuit_bench.parallel_env(condition)
    prey = FleeingPrey()
    totals = []
    for episode in range(episodes):
        obs, _ = env.reset(seed=seed + episode)
        total = 0.0
        while env.agents:
            actions = {a: (prey.act(obs[a]) if a == "prey_0" else predator.act(obs[a])) for a in env.agents}
            obs, rewards, *_ = env.step(actions)
            total += rewards["predator_0"]
        totals.append(total)
    return float(np.mean(totals))


def main(episodes: int = 50) -> None:
    print(f"mean return of predator_0 over {episodes} episodes against the scripted prey")
    print(f"{'condition':22s} {'always-chase':>13s} {'always-stalk':>13s}")
    for condition in pursuit_bench.CONDITIONS:
        chase = mean_predator_return(condition, AlwaysChase(), episodes, seed=0)
        stalk = mean_predator_return(condition, AlwaysStalk(), episodes, seed=0)
        print(f"{condition:22s} {chase:13.3f} {stalk:13.3f}")


if __name__ == "__main__":
    main()
