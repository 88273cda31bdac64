"""The torch reference of the learners' loss, which the compiled update (``agents/fused.py``) is
held to in the tests: double-DQN targets and the importance-weighted Huber loss, by autograd.
Until 0.2 they were ``DQNLearner.loss`` and ``agents.dqn.double_dqn_targets``; no training used
them.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from pursuit_bench.agents.dqn import DQNLearner
from pursuit_bench.agents.network import DuelingQNetwork
from pursuit_bench.agents.replay import Batch


def double_dqn_targets(
    online_next: torch.Tensor,
    target: DuelingQNetwork,
    rewards: torch.Tensor,
    next_obs: torch.Tensor,
    terminated: torch.Tensor,
    gamma: float,
) -> torch.Tensor:
    """``y = r + γ (1 - terminated) Q_target(s', argmax_a Q_online(s', a))``, shapes (M, B);
    ``online_next`` is ``Q_online(s', ·)`` (M, B, A).

    Only termination cuts the bootstrap: a truncated transition (time limit) is stored with
    ``terminated = 0`` and bootstraps from its real next observation.
    """
    with torch.no_grad():
        best = online_next.argmax(dim=-1, keepdim=True)
        next_value = target(next_obs).gather(-1, best).squeeze(-1)
        return rewards + gamma * (1.0 - terminated) * next_value


def loss(learner: DQNLearner, batch: Batch) -> tuple[torch.Tensor, torch.Tensor]:
    """Per-member losses (M,) and TD errors (M, B): the Huber loss of ``Q(s, a) - y``
    weighted by the importance weights, averaged over the batch."""
    obs, next_obs = learner.encode(batch.obs), learner.encode(batch.next_obs)
    actions = torch.as_tensor(batch.actions, dtype=torch.int64)
    rewards = torch.as_tensor(batch.rewards, dtype=torch.float32)
    terminated = torch.as_tensor(batch.terminated, dtype=torch.float32)
    weights = torch.as_tensor(batch.weights, dtype=torch.float32)
    q = learner.online(obs).gather(-1, actions.unsqueeze(-1)).squeeze(-1)
    with torch.no_grad():
        online_next = learner.online(next_obs)
    y = double_dqn_targets(online_next, learner.target, rewards, next_obs, terminated, learner.config.gamma)
    per_sample = F.huber_loss(q, y, reduction="none", delta=learner.config.huber_delta)
    return (weights * per_sample).mean(dim=1), q - y
