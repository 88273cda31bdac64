"""Write ``tests/data/paper-trajectories.json``: SHA-256 digests of the observations, rewards
and episode ends of random rollouts in the paper's empty arena, for ``tests/test_obstacles.py``
to check that ``obstacles=0`` still gives them bit for bit. Written from the commit before
obstacles existed (the package imported from that checkout):

    PYTHONPATH=OLD_CHECKOUT python tests/reference/paper_trajectories.py tests/data/paper-trajectories.json
"""

from __future__ import annotations

import hashlib
import json
import sys

import numpy as np

from pursuit_bench.env.vector import VectorPursuitEnv

#: (condition, backend, wall rule, arenas, steps, seed)
CASES = [
    ("1p-high", "pymunk", "terminate", 4, 300, 0),
    ("3p-low-individual", "pymunk", "contain", 4, 300, 1),
    ("2p-high-shared", "numpy", "terminate", 4, 300, 2),
]


def rollout(condition: str, backend: str, wall_rule: str, arenas: int, steps: int, seed: int) -> dict[str, np.ndarray]:
    """Observations, rewards and ends of ``steps`` steps of random actions drawn from ``seed``."""
    env = VectorPursuitEnv(arenas, condition, backend=backend, wall_rule=wall_rule)  # type: ignore[arg-type]
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    observations, rewards, ends = [obs], [], []
    for _ in range(steps):
        actions = np.stack(
            [rng.integers(0, 2, (arenas, env.n_agents)), rng.integers(0, 12, (arenas, env.n_agents))], -1
        )
        obs, reward, terminated, truncated, _ = env.step(actions)
        observations.append(obs)
        rewards.append(reward)
        ends.append(np.stack([terminated[:, 0], truncated[:, 0]], -1))
    return {"observations": np.array(observations), "rewards": np.array(rewards), "ends": np.array(ends)}


def digests(case: tuple) -> dict[str, str]:
    """The SHA-256 of each array of one case's rollout."""
    return {name: hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest() for name, a in rollout(*case).items()}


def main(path: str) -> None:
    import subprocess
    from pathlib import Path

    import pursuit_bench

    checkout = Path(pursuit_bench.__file__).parent
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=checkout, capture_output=True, text=True).stdout.strip()
    cases = [{"case": list(case), "sha256": digests(case)} for case in CASES]
    with open(path, "w") as f:
        json.dump({"commit": commit, "cases": cases}, f, indent=2)
        f.write("\n")


if __name__ == "__main__":
    main(sys.argv[1])
