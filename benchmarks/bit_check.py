"""Does a build give today's results bit for bit? One JSON of SHA-256 digests of what the
package produces (issue 62): the batched env's outputs over random actions in twelve settings
(both backends; the wall rules; obstacles; continuous actions), the paper's protocol on every
condition's shipped agents (eval's panels, the prey check, every episode's return), ``score`` of
scripted and shipped contestants against the populations, and the learners after a short
training run of three conditions.

    python benchmarks/bit_check.py --out FILE.json [--episodes 200]
    python benchmarks/bit_check.py --compare A.json B.json

Run it on two builds (the older one from a git worktree, its own ``PYTHONPATH``) and compare:
every digest must match. Uses only APIs both builds have.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

SETTINGS: list[tuple[str, dict[str, Any]]] = [
    ("1p-high", {}),
    ("2p-low-shared", {}),
    ("3p-high-individual", {}),
    ("2p-high-shared", {"wall_rule": "contain"}),
    ("3p-low-shared", {"wall_rule": "contain"}),
    ("2p-high-individual", {"obstacles": 4}),
    ("1p-low", {"obstacles": 2, "wall_rule": "contain"}),
    ("3p-high-shared", {"continuous": True}),
]


def digest(*arrays: Any) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def env_outputs(condition: str, options: dict[str, Any], backend: str, steps: int = 1500) -> str:
    from pursuit_bench.env.vector import VectorPursuitEnv

    env = VectorPursuitEnv(24, condition, backend=backend, **options)  # type: ignore[arg-type]
    rng = np.random.default_rng(7)
    obs, _ = env.reset(seed=3)
    h = hashlib.sha256(obs.tobytes())
    for _ in range(steps):
        if env.config.continuous:
            actions = rng.uniform(-1, 1, (env.num_envs, env.n_agents, 2))
        else:
            actions = np.stack(
                [rng.integers(0, 2, (env.num_envs, env.n_agents)), rng.integers(0, 12, (env.num_envs, env.n_agents))],
                axis=-1,
            )
        obs, rewards, terminated, truncated, info = env.step(actions)
        for a in (obs, rewards, terminated, truncated, info["done"], info["positions"], info["captured"],
                  info["touching_prey"], info["left_area"], info["touching_obstacle"], info["final_obs"]):  # fmt: skip
            h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def evaluations(episodes: int) -> dict[str, str]:
    from pursuit_bench import pretrained
    from pursuit_bench.env.conditions import CONDITIONS
    from pursuit_bench.training.evaluate import evaluate_agents

    out = {}
    for condition in CONDITIONS:
        result = evaluate_agents(condition, pretrained.load(condition), episodes=episodes, seed=12345)
        out[condition] = hashlib.sha256(json.dumps(result, sort_keys=True).encode()).hexdigest()
    return out


def scores(episodes: int) -> dict[str, str]:
    from pursuit_bench.benchmark import score

    out = {}
    for spec, role, conditions in (
        ("always-chase", "predator", ["1p-high", "3p-low-individual"]),
        ("pretrained", "predator", ["2p-high-shared"]),
        ("FleeingPrey", "prey", ["2p-low-shared", "1p-low"]),
    ):
        result = score.score(score.resolve(spec, role), conditions, episodes=episodes, seed=12345)
        out[f"{spec}-{role}"] = hashlib.sha256(json.dumps(result, sort_keys=True).encode()).hexdigest()
    return out


def learners(episodes: int = 60) -> dict[str, str]:
    from pursuit_bench.agents.config import REPRODUCTION
    from pursuit_bench.training.train import TrainConfig, Trainer

    out = {}
    for condition in ("1p-high", "3p-high-shared", "2p-low-individual"):
        trainer = Trainer([TrainConfig(condition=condition, agent=REPRODUCTION, num_envs=8, seed=4, episodes=episodes)])
        trainer.run()
        h = hashlib.sha256()
        for run in trainer.runs:
            for name, agent in sorted(run.agents.items()):
                learner = getattr(agent, "learner", None)
                if learner is not None:
                    h.update(name.encode())
                    h.update(learner.optimizer.flat.numpy().tobytes())
        out[condition] = h.hexdigest()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--compare", nargs=2, type=Path)
    parser.add_argument("--only", default="env,eval,score,learn")
    args = parser.parse_args()
    if args.compare:
        a, b = (json.loads(p.read_text()) for p in args.compare)
        keys = sorted(set(a) | set(b))
        differ = [k for k in keys if a.get(k) != b.get(k)]
        print(f"{len(keys) - len(differ)} of {len(keys)} digests equal" + (f"; differ: {differ}" if differ else ""))
        sys.exit(1 if differ else 0)
    import torch

    torch.set_num_threads(1)
    parts = set(args.only.split(","))
    out: dict[str, str] = {}
    if "env" in parts:
        for condition, options in SETTINGS:
            for backend in ("pymunk", "numpy"):
                key = f"env|{condition}|{json.dumps(options, sort_keys=True)}|{backend}"
                out[key] = env_outputs(condition, options, backend)
    if "eval" in parts:
        out.update({f"eval|{k}": v for k, v in evaluations(args.episodes).items()})
    if "score" in parts:
        out.update({f"score|{k}": v for k, v in scores(max(2, args.episodes // 10)).items()})
    if "learn" in parts:
        out.update({f"learn|{k}": v for k, v in learners().items()})
    text = json.dumps(out, indent=2) + "\n"
    if args.out:
        args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
