"""The residual predator (residual RL on the paper's rule): the hierarchical predator's mode
learner, unchanged, and a learned correction of the rule's direction that is zero by construction
until the corrections' own transitions show that one pays.

The predator's value of mode m with a correction of k steps of 30° is

    Q(s, m, k) = Q_mode(s, m) + C(s, m, k),    C(s, m, 0) ≡ 0,    C(s, m, k) = Â(s, m, k) − c·|k|,

- ``Q_mode`` is the hierarchical predator's dueling network, learned by the same compiled
  double-DQN update (:class:`~pursuit_bench.agents.dqn.DQNLearner`, two actions), from the same
  replay, on the transitions that moved in the rule's direction: a corrected transition enters
  its replay with importance weight 0 and priority ε, so it moves nothing there.
- ``Â`` is a network of its own (:class:`CorrectionNetwork`, outputs for the four non-zero
  corrections of each mode only, its last layer zero at the start) with its own Adam and its own
  replay of the corrected transitions alone, updated at the mode learner's replay ratio counted
  on those transitions: only they move it. It learns the one-step advantage
  of turning k · 30° and then going on as the mode learner's policy does,
  ``y = r + γ (1 − terminated) Q̄_mode(s', argmax Q_mode(s', ·)) − Q_mode(s, m)`` (Q̄: the mode
  learner's target network): the target the mode learner fits on the rule's transitions, less
  its fit. The mode's value and the correction's share one continuation, and the greedy
  correction is one step of policy improvement on the hierarchical predator (where the values
  are exact).
- ``c`` (:data:`CORRECTION_PRIOR`) is a fixed part of C, not a starting value: a correction is
  greedy where its learned advantage exceeds c per 30° turned.

Exploration: the mode as the hierarchical predator explores it (ε from the schedule, drawn from
the mode learner's own generators with the same calls), the correction with its own constant
ε_c (:data:`CORRECTION_EPSILON`): with probability ε_c one of the four other corrections.

docs/residual.md says why, and what the residual RL papers did.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numba
import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

import pursuit_bench.agents.names as names
from pursuit_bench.agents.adam import adam_step_kernel
from pursuit_bench.agents.config import AgentConfig
from pursuit_bench.agents.dqn import DECISIVE_GAP, DQNLearner, decision_scale
from pursuit_bench.agents.fused import dense_relu, network_inputs, q_and_value_kernel
from pursuit_bench.agents.kinds import HierarchicalPredator
from pursuit_bench.agents.network import TRUNK, StackedLinear, member_seeds
from pursuit_bench.env.task import N_DIRECTIONS
from pursuit_bench.rules.navigation import navigate

#: The corrections, in steps of 30° (index j of an action ``5 · mode + j``): no correction first.
CORRECTIONS = (0, -1, 1, -2, 2)
#: c: C(s, m, k) = Â(s, m, k) − c·|k|. A correction is taken greedily where its learned one-step
#: advantage exceeds 0.01 per 30°: the chase cost of the low-cost conditions, the smallest reward
#: difference the task makes in one step (docs/residual.md).
CORRECTION_PRIOR = 0.01
#: ε_c: the probability, at every exploring step, of one of the four other corrections (uniform).
#: Constant: the corrections keep being tried as long as the predator learns.
CORRECTION_EPSILON = 0.05

_STEPS = np.abs(np.array(CORRECTIONS, dtype=np.float32))
_PER_MODE = len(CORRECTIONS)


class CorrectionNetwork(nn.Module):
    """Â for M members: ``in → 64 → 64 → 2 · 4`` (ReLU), the four non-zero corrections of each
    mode; the last layer starts at zero (Â ≡ 0), the others as torch's Linear."""

    def __init__(self, n_inputs: int, *, members: int, seed: int | Sequence[int]) -> None:
        super().__init__()
        generators = [torch.Generator().manual_seed(s) for s in member_seeds(seed, members)]
        self.hidden1 = StackedLinear(n_inputs, TRUNK[0], generators)
        self.hidden2 = StackedLinear(TRUNK[0], TRUNK[1], generators)
        self.out = StackedLinear(TRUNK[1], 2 * (_PER_MODE - 1), generators)
        with torch.no_grad():
            self.out.weight.zero_()
            self.out.bias.zero_()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out(torch.relu(self.hidden2(torch.relu(self.hidden1(x)))))


@numba.njit(cache=True, error_model="numpy")
def _corrections_kernel(w1, b1, w2, b2, w3, b3, obs, wall):
    """Â (M, B, 8) of every member for observations (M, B, n_obs): :class:`CorrectionNetwork`'s
    forward pass, compiled (torch's to float rounding)."""
    members, rows, _ = obs.shape
    out = np.empty((members, rows, w3.shape[2]), dtype=np.float32)
    for m in range(members):
        hidden = dense_relu(dense_relu(network_inputs(obs[m], wall), w1[m], b1[m, 0]), w2[m], b2[m, 0])
        out[m] = np.dot(hidden, w3[m])
        for i in range(rows):
            for j in range(w3.shape[2]):
                out[m, i, j] += b3[m, 0, j]
    return out


class MemberAdam:
    """Adam for stacked parameters (member axis first), :class:`~pursuit_bench.agents.adam.FlatAdam`'s
    arithmetic member by member: each member steps only when it learns (``active``) and counts
    its own steps, so that its updates never depend on its companions'."""

    def __init__(self, params: list[nn.Parameter], lr: float, betas: tuple[float, float] = (0.9, 0.999)) -> None:
        self.params, self.lr, self.betas, self.eps = params, lr, betas, 1e-8
        self.exp_avg = [torch.zeros_like(p) for p in params]
        self.exp_avg_sq = [torch.zeros_like(p) for p in params]
        self.steps = np.zeros(params[0].shape[0], dtype=np.int64)

    @torch.no_grad()
    def step(self, active: np.ndarray) -> None:
        beta1, beta2 = self.betas
        f32 = np.float32
        for m in np.flatnonzero(active):
            self.steps[m] += 1
            t = int(self.steps[m])
            scalars = (f32(beta2), f32(1 - beta2), f32(self.lr / (1 - beta1**t)), f32(math.sqrt(1 - beta2**t)))
            for p, avg, avg_sq in zip(self.params, self.exp_avg, self.exp_avg_sq, strict=True):
                assert p.grad is not None
                adam_step_kernel(
                    p.data[m].view(-1).numpy(),
                    p.grad[m].reshape(-1).numpy(),
                    avg[m].view(-1).numpy(),
                    avg_sq[m].view(-1).numpy(),
                    f32(1 - beta1),
                    *scalars,
                    f32(self.eps),
                )


class CorrectionReplay:
    """Each member's corrected transitions, a uniform ring buffer per member (members store
    different numbers of them)."""

    def __init__(self, members: int, capacity: int, n_obs: int) -> None:
        self.capacity = capacity
        self.obs = np.zeros((members, capacity, n_obs), dtype=np.float32)
        self.next_obs = np.zeros((members, capacity, n_obs), dtype=np.float32)
        self.actions = np.zeros((members, capacity), dtype=np.int64)
        self.rewards = np.zeros((members, capacity), dtype=np.float32)
        self.terminated = np.zeros((members, capacity), dtype=np.float32)
        self.size = np.zeros(members, dtype=np.int64)
        self.position = np.zeros(members, dtype=np.int64)

    FIELDS = ("obs", "next_obs", "actions", "rewards", "terminated")

    def add(self, m: int, rows: tuple[np.ndarray, ...]) -> None:
        """Append member m's transitions (obs, actions, rewards, next_obs, terminated), (k, …)."""
        obs, actions, rewards, next_obs, terminated = rows
        slots = (self.position[m] + np.arange(len(actions))) % self.capacity
        self.obs[m, slots], self.actions[m, slots], self.rewards[m, slots] = obs, actions, rewards
        self.next_obs[m, slots], self.terminated[m, slots] = next_obs, terminated
        self.position[m] = (self.position[m] + len(actions)) % self.capacity
        self.size[m] = min(self.size[m] + len(actions), self.capacity)

    def take(self, members: list[int]) -> CorrectionReplay:
        new = CorrectionReplay(len(members), self.capacity, self.obs.shape[2])
        for name in (*self.FIELDS, "size", "position"):
            setattr(new, name, getattr(self, name)[members].copy())
        return new

    def member_state(self, m: int) -> dict[str, Any]:
        n = int(self.size[m])
        state: dict[str, Any] = {name: torch.from_numpy(getattr(self, name)[m, :n].copy()) for name in self.FIELDS}
        return {**state, "size": n, "position": int(self.position[m])}

    def load_member_state(self, m: int, state: dict[str, Any]) -> None:
        n = int(state["size"])
        if n > self.capacity or tuple(state["obs"].shape[1:]) != self.obs.shape[2:]:
            raise ValueError("correction replay state does not fit this replay (capacity or observation size differ)")
        for name in self.FIELDS:
            getattr(self, name)[m, :n] = np.asarray(state[name])
        self.size[m], self.position[m] = n, int(state["position"])


class ResidualLearner(DQNLearner):
    """The residual predator's learner for M members: as a :class:`DQNLearner` it is the
    hierarchical predator's (two actions: the modes; the same network, seeds, update, replay and
    exploration draws), and it adds the corrections (:class:`CorrectionNetwork`, its Adam, its
    replay and generators). Its Q-values, choices and stored actions have 10 actions,
    ``5 · mode + j`` with k = ``CORRECTIONS[j]``."""

    def __init__(
        self,
        n_obs: int,
        config: AgentConfig,
        *,
        members: int = 1,
        seed: int | Sequence[int] = 0,
        prior: float = CORRECTION_PRIOR,
        correction_epsilon: float = CORRECTION_EPSILON,
    ) -> None:
        super().__init__(n_obs, 2, config, members=members, seed=seed)
        if not 0.0 <= correction_epsilon <= 1.0 or prior < 0:
            raise ValueError(
                f"prior={prior!r}, correction_epsilon={correction_epsilon!r}: expected c >= 0, ε in [0, 1]"
            )
        self.prior, self.correction_epsilon = prior, correction_epsilon
        seeds = member_seeds(seed, members)
        # the corrections' streams: derived from each member's seed, apart from the mode learner's
        streams = [np.random.SeedSequence([s, 1]).generate_state(1)[0] for s in seeds]
        n_inputs = self.online.trunk1.weight.shape[1]
        self.corrections = CorrectionNetwork(n_inputs, members=members, seed=[int(s) for s in streams])
        self.correction_adam = MemberAdam(list(self.corrections.parameters()), lr=config.learning_rate)
        self.correction_replay = CorrectionReplay(members, config.buffer_size, n_obs)
        self.correction_rngs = [np.random.default_rng([int(s), 2]) for s in streams]
        self.owed_corrections = np.zeros(members)  # updates of the corrections owed, per member

    # --- values -------------------------------------------------------------------------------

    def correction_values(self, obs: np.ndarray, *, compiled: bool = False) -> np.ndarray:
        """C (M, B, 2, 5) for observations (M, B, n_obs): 0 for k = 0, Â − c·|k| otherwise; Â by
        torch's forward pass, or by the compiled one (``compiled``: what the training loop acts with)."""
        if compiled:
            w1, b1, w2, b2, w3, b3 = (p.detach().numpy() for p in self.corrections.parameters())
            obs = np.ascontiguousarray(obs, dtype=np.float32)
            learned = _corrections_kernel(w1, b1, w2, b2, w3, b3, obs, self.config.wall_features)
        else:
            with torch.no_grad():
                learned = self.corrections(self.encode(obs)).numpy()
        table = np.zeros((*learned.shape[:-1], 2, _PER_MODE), dtype=np.float32)
        table[..., 1:] = learned.reshape(*learned.shape[:-1], 2, _PER_MODE - 1)
        return table - np.float32(self.prior) * _STEPS

    def _with_corrections(self, mode_q: np.ndarray, obs: np.ndarray, *, compiled: bool = False) -> np.ndarray:
        q = mode_q[..., :, None] + self.correction_values(obs, compiled=compiled)
        return q.reshape(*mode_q.shape[:-1], 2 * _PER_MODE)

    def evaluate(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Q-values (M, B, 10) and V(s) (M, B): torch's passes of both networks."""
        mode_q, value = super().evaluate(obs)
        return self._with_corrections(mode_q, np.asarray(obs)), value

    def act_values(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`evaluate` by the compiled forward passes (torch's to float rounding)."""
        mode_q, value = super().act_values(obs)
        return self._with_corrections(mode_q, np.asarray(obs), compiled=True), value

    def decisive_q(self, obs: np.ndarray, member: int, parts: np.ndarray | None = None) -> np.ndarray:
        """Member ``member``'s Q-values (B, 10), the mode values from the compiled pass, and
        torch's for the whole batch where some row's two best actions lie within
        :data:`DECISIVE_GAP` (C is torch's in both). ``parts`` (B,) labels runs of rows as
        batches of their own (torch's passes are made per run: see the base class)."""
        if parts is not None and len(parts) and np.any(parts[1:] != parts[:-1]):
            starts = np.flatnonzero(np.r_[True, parts[1:] != parts[:-1]]).tolist()
            ends = [*starts[1:], len(obs)]
            return np.concatenate([self.decisive_q(obs[a:b], member) for a, b in zip(starts, ends, strict=True)])
        if not 0 <= member < self.members:
            raise ValueError(f"member={member!r}: expected one of 0 … {self.members - 1}")
        obs = np.asarray(obs, dtype=np.float32)
        if obs.ndim != 2 or obs.shape[1] != self.n_obs:
            raise ValueError(f"obs of shape {obs.shape}: expected (B, {self.n_obs})")
        stacked = np.ascontiguousarray(obs)[None]
        mode_q, value = q_and_value_kernel(
            self.optimizer.flat.numpy(), self._offsets, 2, stacked, self.config.wall_features, member
        )
        everyone = np.zeros((self.members, *obs.shape), dtype=np.float32)
        everyone[member] = obs
        correction = self.correction_values(everyone)[member]
        q = (mode_q[0][..., None] + correction).reshape(len(obs), 2 * _PER_MODE)
        top = np.sort(q, axis=-1)[:, -2:]
        if np.any(top[:, 1] - top[:, 0] <= DECISIVE_GAP * decision_scale(mode_q[0], value[0])):
            return self.evaluate(everyone)[0][member]
        return q

    # --- acting -------------------------------------------------------------------------------

    def act_members(self, obs: np.ndarray, *, explore: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The training loop's acting step, (actions, Q-values, V(s)): the mode learner's compiled
        call acts over 2 actions only, so the residual predator acts by :meth:`act_values` (both
        networks) and its own :meth:`choose` (the correction's exploration)."""
        q, value = self.act_values(obs)
        return self.choose(q, explore=explore), q, value

    def choose(self, q_values: np.ndarray, *, explore: bool, epsilon: float | None = None) -> np.ndarray:
        """Actions (M, B) ``5 · mode + j``: the mode greedy over its best correction, or with
        ε-greedy exploration exactly as the hierarchical predator's (the same draws from the same
        generators); then the greedy correction of that mode, or with probability ε_c (when
        ``explore``) one of the four others, drawn from the corrections' generators."""
        table = np.asarray(q_values).reshape(*q_values.shape[:-1], 2, _PER_MODE)
        modes = table.max(axis=-1).argmax(axis=-1)
        if explore:  # the mode learner's own ε-greedy draws (2 actions), as the hierarchical predator's
            uniforms, randoms, eps = self._exploration(modes.shape[1], explore, epsilon)
            modes = np.where(uniforms < eps, randoms, modes)
        j = np.take_along_axis(table, modes[..., None, None], axis=-2)[..., 0, :].argmax(axis=-1)
        if explore:
            for m, rng in enumerate(self.correction_rngs):
                tried = rng.random(j.shape[1:]) < self.correction_epsilon
                other = rng.integers(0, _PER_MODE - 1, size=j.shape[1:])
                j[m] = np.where(tried, other + (other >= j[m]), j[m])
        return modes * _PER_MODE + j

    # --- learning -----------------------------------------------------------------------------

    def store(
        self, obs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray, terminated: np.ndarray
    ) -> None:
        """Every transition into the mode learner's replay (actions ``5 · mode + j``: its update
        reads the mode and leaves the corrected ones out); the corrected ones into each member's
        correction replay too, each owing the replay ratio's updates of the corrections once that
        replay holds a batch."""
        super().store(obs, actions, rewards, next_obs, terminated)
        corrected = np.asarray(actions) % _PER_MODE != 0
        replay = self.correction_replay
        for m in np.flatnonzero(corrected.any(axis=1)):
            rows = corrected[m]
            replay.add(
                int(m), (obs[m, rows], actions[m, rows], rewards[m, rows], next_obs[m, rows], terminated[m, rows])
            )
            if replay.size[m] >= self.config.batch_size:
                self.owed_corrections[m] += rows.sum() * self.config.replay_ratio

    def train(self) -> np.ndarray | None:
        """The mode learner's updates owed (:meth:`DQNLearner.train`), then the corrections'."""
        losses = super().train()
        self.learn_corrections()
        return losses

    def update(self) -> np.ndarray:
        """One step of the mode learner on its prioritized batch (the corrected transitions in
        it weighted 0, their priorities set to ε); its losses (M,)."""
        batch = self.replay.sample(self.config.batch_size, self.beta, self.generators())
        modes, j = np.divmod(batch.actions, _PER_MODE)
        corrected = j != 0
        batch.actions, batch.weights = modes, np.where(corrected, np.float32(0.0), batch.weights)
        losses = self.learn(batch)
        if corrected.any() and self.replay.prioritized:
            rows = np.arange(self.members)[:, None]
            td = self.replay.priorities[rows, batch.indices] - self.replay.priority_epsilon
            self.replay.update_priorities(batch.indices, np.where(corrected, 0.0, td))
        return losses

    def correction_targets(
        self, obs: np.ndarray, modes: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray, terminated: np.ndarray
    ) -> np.ndarray:
        """The one-step advantages (M, B) Â learns from: ``r + γ (1 − terminated) Q̄(s', argmax
        Q(s', ·)) − Q(s, m)`` with the mode learner's online (Q) and target (Q̄) networks: the
        double-DQN target the mode learner fits with its online network on the rule's transitions,
        less that fit, so that the mode learner's own lag (its target network's drift) cancels."""
        wall, offsets, online_flat = self.config.wall_features, self._offsets, self.optimizer.flat.numpy()
        online_next = q_and_value_kernel(online_flat, offsets, 2, next_obs, wall)[0]
        target_next = q_and_value_kernel(self._target_flat.numpy(), offsets, 2, next_obs, wall)[0]
        online_now = q_and_value_kernel(online_flat, offsets, 2, obs, wall)[0]
        best = online_next.argmax(axis=-1)[..., None]
        bootstrap = np.take_along_axis(target_next, best, axis=-1)[..., 0]
        now = np.take_along_axis(online_now, modes[..., None], axis=-1)[..., 0]
        return rewards + np.float32(self.config.gamma) * (1.0 - terminated) * bootstrap - now

    def learn_corrections(self) -> None:
        """The corrections' updates owed, member by member: the replay ratio's updates per
        corrected transition (as the mode learner's per transition), once its correction replay
        holds a batch."""
        while True:
            active = self.owed_corrections >= 1.0
            if not active.any():
                return
            self.owed_corrections[active] -= 1.0
            self.correction_step(active)

    def correction_step(self, active: np.ndarray) -> np.ndarray:
        """One step of Â for the ``active`` members (the others don't move, not even by Adam's
        momentum), each on a uniform batch of its corrected transitions; the members' losses
        (M,), 0 for those that did not learn."""
        replay, size = self.correction_replay, self.config.batch_size
        indices = np.zeros((self.members, size), dtype=np.int64)
        for m in np.flatnonzero(active):
            indices[m] = self.correction_rngs[m].integers(0, replay.size[m], size=size)
        rows = np.arange(self.members)[:, None]
        obs, next_obs = replay.obs[rows, indices], replay.next_obs[rows, indices]
        modes, j = np.divmod(replay.actions[rows, indices], _PER_MODE)
        rewards, terminated = replay.rewards[rows, indices], replay.terminated[rows, indices]
        y = torch.as_tensor(self.correction_targets(obs, modes, rewards, next_obs, terminated), dtype=torch.float32)
        column = torch.as_tensor(modes * (_PER_MODE - 1) + j - 1)
        predicted = self.corrections(self.encode(obs)).gather(-1, column[..., None])[..., 0]
        per_sample = F.huber_loss(predicted, y, reduction="none", delta=self.config.huber_delta)
        losses = per_sample.mean(dim=1) * torch.as_tensor(active, dtype=torch.float32)
        for p in self.corrections.parameters():
            p.grad = None
        losses.sum().backward()
        self.correction_adam.step(active)
        return losses.detach().numpy()

    # --- stacks and checkpoints ---------------------------------------------------------------

    def take(self, members: Sequence[int]) -> ResidualLearner:
        keep = list(members)
        modes = DQNLearner.take(self, keep)
        new = ResidualLearner.__new__(ResidualLearner)
        new.__dict__.update(modes.__dict__)
        new.prior, new.correction_epsilon = self.prior, self.correction_epsilon
        n_inputs = self.corrections.hidden1.weight.shape[1]
        new.corrections = CorrectionNetwork(n_inputs, members=len(keep), seed=[0] * len(keep))
        with torch.no_grad():
            for mine, theirs in zip(self.corrections.parameters(), new.corrections.parameters(), strict=True):
                theirs.copy_(mine[keep])
        new.correction_adam = MemberAdam(list(new.corrections.parameters()), lr=self.correction_adam.lr)
        for source, destination in zip(
            self.correction_adam.exp_avg + self.correction_adam.exp_avg_sq,
            new.correction_adam.exp_avg + new.correction_adam.exp_avg_sq,
            strict=True,
        ):
            destination.copy_(source[keep])
        new.correction_adam.steps = self.correction_adam.steps[keep].copy()
        new.correction_replay = self.correction_replay.take(keep)
        new.correction_rngs = [self.correction_rngs[m] for m in keep]
        new.owed_corrections = self.owed_corrections[keep].copy()
        return new

    def member_weights(self, m: int) -> dict[str, torch.Tensor]:
        """Member m's mode network and, under ``correction.``, its correction network."""
        weights = super().member_weights(m)
        weights.update({f"correction.{k}": v[m].clone() for k, v in self.corrections.state_dict().items()})
        return weights

    def load_member_weights(self, m: int, weights: dict[str, torch.Tensor]) -> None:
        modes = {k: v for k, v in weights.items() if not k.startswith("correction.")}
        corrections = {k.removeprefix("correction."): v for k, v in weights.items() if k.startswith("correction.")}
        ours = {k: tuple(v.shape[1:]) for k, v in self.corrections.state_dict().items()}
        if ours != {k: tuple(v.shape) for k, v in corrections.items()}:
            theirs = {k: tuple(v.shape) for k, v in corrections.items()}
            raise ValueError(f"correction weights of shapes {theirs}: expected {ours}")
        super().load_member_weights(m, modes)
        with torch.no_grad():
            for name, tensor in self.corrections.state_dict().items():
                tensor[m] = corrections[name]

    def member_state(self, m: int) -> dict[str, Any]:
        adam = self.correction_adam
        corrections = {
            "weights": {k: v[m].clone() for k, v in self.corrections.state_dict().items()},
            "adam_steps": int(adam.steps[m]),
            "adam_exp_avg": [avg[m].clone() for avg in adam.exp_avg],
            "adam_exp_avg_sq": [avg_sq[m].clone() for avg_sq in adam.exp_avg_sq],
            "replay": self.correction_replay.member_state(m),
            "rng": self.correction_rngs[m].bit_generator.state,
            "owed": float(self.owed_corrections[m]),
            "prior": self.prior,
            "epsilon": self.correction_epsilon,
        }
        return {**super().member_state(m), "corrections": corrections}

    def load_member_state(self, m: int, state: dict[str, Any]) -> None:
        if "corrections" not in state:
            raise ValueError(
                "not a residual predator's state: it holds no corrections (an older version's checkpoint?)"
            )
        super().load_member_state(m, state)
        saved = state["corrections"]
        adam = self.correction_adam
        with torch.no_grad():
            for name, tensor in self.corrections.state_dict().items():
                tensor[m] = saved["weights"][name]
            for exp_avg, exp_avg_sq, avg, avg_sq in zip(
                adam.exp_avg, adam.exp_avg_sq, saved["adam_exp_avg"], saved["adam_exp_avg_sq"], strict=True
            ):
                exp_avg[m], exp_avg_sq[m] = avg, avg_sq
        adam.steps[m] = int(saved["adam_steps"])
        self.correction_replay.load_member_state(m, saved["replay"])
        self.correction_rngs[m].bit_generator.state = saved["rng"]
        self.owed_corrections[m] = float(saved["owed"])
        self.prior, self.correction_epsilon = float(saved["prior"]), float(saved["epsilon"])


class ResidualPredator(HierarchicalPredator):
    """Residual RL on the rule (Johannink et al. 2019; Silver et al. 2018): the mode, as the
    hierarchical predator picks it, and a correction k of the direction the lower layer picks
    (with obstacles, after avoidance): it moves in ``(navigate(obs, mode) + k) mod 12``. Its
    learner is a :class:`ResidualLearner`: until a correction's own transitions show that it
    pays, it moves exactly as the hierarchical predator."""

    kind = names.RESIDUAL
    n_actions = 2 * _PER_MODE

    def __init__(self, name: str, learner: DQNLearner, member: int = 0, *, avoidance: bool = False) -> None:
        if not isinstance(learner, ResidualLearner):
            raise ValueError(f"residual needs a ResidualLearner (modes, corrections), got a {type(learner).__name__}")
        self.name, self.learner, self.member, self.avoidance = name, learner, member, avoidance

    @classmethod
    def new_learner(
        cls, n_obs: int, config: AgentConfig, *, members: int = 1, seed: int | Sequence[int] = 0
    ) -> ResidualLearner:
        return ResidualLearner(n_obs, config, members=members, seed=seed)

    @staticmethod
    def split(choices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(modes, corrections k)`` of actions ``5 · mode + j``."""
        modes, j = np.divmod(np.asarray(choices), _PER_MODE)
        return modes, np.asarray(CORRECTIONS)[j]

    @staticmethod
    def action(modes: np.ndarray | int, corrections: np.ndarray | int) -> np.ndarray:
        """The actions ``5 · mode + j`` for modes and corrections k (inverse of :meth:`split`)."""
        index = {k: j for j, k in enumerate(CORRECTIONS)}
        j = np.vectorize(index.__getitem__)(np.asarray(corrections))
        return np.asarray(modes) * _PER_MODE + j

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        modes, corrections = self.split(choices)
        rule = navigate(obs, modes, avoidance=self.avoidance)
        return np.stack([modes, (rule + corrections) % N_DIRECTIONS], axis=-1)

    @staticmethod
    def mode_q(q: np.ndarray) -> np.ndarray:
        """Each mode's best Q-value over its corrections (…, 2)."""
        q = np.asarray(q)
        return q.reshape(*q.shape[:-1], 2, _PER_MODE).max(axis=-1)
