"""Evidence for DQNLearner.decisive_q: every shipped condition evaluated by the paper's protocol
twice, acting by the compiled forward pass (falling back to torch's where a decision is close) and
by torch's network alone, and the largest difference between the two passes' Q-values seen,
relative to each row's decision scale (agents/dqn.py, DECISIVE_GAP).

    python benchmarks/decisive_check.py [--episodes 200]   # writes results/speed/decisive-check.json

Exits 1 if an evaluation differs or the difference comes within a quarter of the gap.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from pursuit_bench import pretrained
from pursuit_bench.agents.dqn import DECISIVE_GAP, DQNLearner, decision_scale
from pursuit_bench.agents.fused import q_and_value_kernel
from pursuit_bench.training.evaluate import evaluate_agents

OUT = Path(__file__).resolve().parents[1] / "results" / "speed" / "decisive-check.json"


def torch_only(worst: list[float]) -> Any:
    """A decisive_q that answers torch's Q-values and notes the compiled pass's largest difference."""

    def decisive_q(self: DQNLearner, obs: np.ndarray, member: int, parts: np.ndarray | None = None) -> np.ndarray:
        # torch's pass per part, as each part's rows were batched in calls of their own
        labels = np.zeros(len(obs), dtype=np.int64) if parts is None else np.asarray(parts)
        starts = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]]).tolist()
        ends = [*starts[1:], len(obs)]
        q = np.concatenate([self._torch_q(obs[a:b], member) for a, b in zip(starts, ends, strict=True)])
        stacked = np.ascontiguousarray(obs, dtype=np.float32)[None]
        compiled_q, compiled_v = q_and_value_kernel(
            self.optimizer.flat.numpy(), self._offsets, self.n_actions, stacked, self.config.wall_features, member
        )
        scale = decision_scale(compiled_q[0], compiled_v[0])
        worst[0] = max(worst[0], float((np.abs(compiled_q[0] - q) / scale[:, None]).max()))
        return q

    return decisive_q


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=200)
    args = parser.parse_args()
    rows = []
    fast_path = DQNLearner.decisive_q
    for condition in pretrained.available():
        fast = evaluate_agents(condition, pretrained.load(condition), episodes=args.episodes, seed=12345)
        worst = [0.0]
        DQNLearner.decisive_q = torch_only(worst)  # type: ignore[method-assign]
        try:
            slow = evaluate_agents(condition, pretrained.load(condition), episodes=args.episodes, seed=12345)
        finally:
            DQNLearner.decisive_q = fast_path  # type: ignore[method-assign]
        rows.append({"condition": condition, "identical": fast == slow, "largest_difference": worst[0]})
        print(f"{condition}: identical {fast == slow}, largest difference {worst[0]:.3g} of the scale")
    largest = max(r["largest_difference"] for r in rows)
    payload = {
        "command": f"python benchmarks/decisive_check.py --episodes {args.episodes}",
        "episodes_per_variant": args.episodes,
        "decisive_gap": DECISIVE_GAP,
        "largest_difference": largest,
        "conditions": rows,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(payload, indent=2) + "\n")
    ok = all(r["identical"] for r in rows) and largest < DECISIVE_GAP / 4
    print(f"{OUT}: largest difference {largest:.3g} against the gap {DECISIVE_GAP:g}: {'ok' if ok else 'NOT OK'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
