"""The leaderboard's Stable-Baselines3 row: a PPO predator trained through the Gymnasium view
(``pursuit_bench/Pursuit-v0``, one predator learning against the view's scripted prey) in each
1-predator condition, and the agent module that plays it (``predator(condition=…)``: the model
trained in the condition it is asked to play).

    python studies/leaderboard/ppo_leaderboard.py            # trains runs/ppo-leaderboard/<condition>.zip
    pursuit-bench score studies.leaderboard.ppo_leaderboard:predator --role predator --conditions 1p-high,1p-low …

The models are generated files (not in git); the budget is TIMESTEPS per condition, seed 0,
SB3's PPO defaults but n_steps and batch_size (as docs/tutorials/sb3.md).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

FOLDER = Path("runs/ppo-leaderboard")
CONDITIONS = ("1p-high", "1p-low")
TIMESTEPS = 50_000


class Predator:
    """A trained PPO model behind ``act`` / ``act_batch`` (deterministic actions)."""

    def __init__(self, path: Path) -> None:
        from stable_baselines3 import PPO

        self.model = PPO.load(path, device="cpu")

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        actions, _ = self.model.predict(np.asarray(observations, dtype=np.float32), deterministic=True)
        return np.asarray(actions)

    def act(self, observation: np.ndarray) -> Any:
        return self.act_batch(np.asarray(observation)[None])[0]


def predator(condition: str) -> Predator:
    """The model trained in ``condition`` (the score command passes the condition it plays)."""
    path = FOLDER / f"{condition}.zip"
    if not path.is_file():
        raise FileNotFoundError(
            f"{path}: no model for {condition}; train it first (python studies/leaderboard/ppo_leaderboard.py)"
        )
    return Predator(path)


def main() -> None:
    import gymnasium
    import torch
    from stable_baselines3 import PPO

    import pursuit_bench

    torch.set_num_threads(1)
    gymnasium.register_envs(pursuit_bench)
    FOLDER.mkdir(parents=True, exist_ok=True)
    for condition in CONDITIONS:
        start = time.monotonic()
        env = gymnasium.make("pursuit_bench/Pursuit-v0", agent="predator_0", condition=condition)
        model = PPO("MlpPolicy", env, n_steps=1024, batch_size=128, seed=0, verbose=0, device="cpu")
        model.learn(total_timesteps=TIMESTEPS)
        model.save(FOLDER / condition)
        print(f"{condition}: {TIMESTEPS} steps in {time.monotonic() - start:.0f} s -> {FOLDER / condition}.zip")


if __name__ == "__main__":
    main()
