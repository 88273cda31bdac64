"""Double DQN (van Hasselt et al. 2016) with a dueling network and prioritized replay, for M
independent members updated as one batched computation.

Each member has its own parameters (a slice of the stacked network), its own replay and, in
effect, its own Adam: Adam's update is elementwise, and the batched loss is the *sum* of the
members' losses, so member m's gradient and moments depend on member m's data alone. One
learner with M members therefore makes exactly the updates of M learners with one member each
(``tests/test_dqn.py`` checks it).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch

from pursuit_bench.agents.adam import FlatAdam, flatten_parameters, parameter_offsets
from pursuit_bench.agents.config import AgentConfig
from pursuit_bench.agents.fused import (
    act_kernel,
    choose_kernel,
    exploration_kernel,
    one_thread_for_scipys_blas,
    q_and_value_kernel,
    replay_update_kernel,
    undecided_kernel,
    update_kernel,
)
from pursuit_bench.agents.generators import CompiledGenerators
from pursuit_bench.agents.network import DuelingQNetwork, member_seeds
from pursuit_bench.agents.replay import Batch, ReplayStack

#: Inputs added to the observation by ``AgentConfig.wall_features``.
WALL_FEATURES = 2
#: Two Q-values closer than this (relative to the row's :func:`decision_scale`) are left to
#: torch's forward pass to order (:meth:`DQNLearner.decisive_q`). The compiled pass differs from
#: torch's by at most 3.1e-7 of that scale so measured (every Q-value the shipped agents of all
#: ten conditions computed in an evaluation of 200 episodes a variant, ``benchmarks/decisive_check.py``;
#: ``tests/test_fused.py`` keeps measuring it): a measured bound, not a proven one.
DECISIVE_GAP = 4e-6


def decision_scale(q: np.ndarray, value: np.ndarray) -> np.ndarray:
    """How large the numbers are that each row's Q-values (B, A) were summed from, for
    :data:`DECISIVE_GAP`: 1 + |V(s)| + the largest |A(s, a) - mean A| (= |Q - V|), so that a Q
    near zero made of a large value and a large advantage is not trusted to a small gap."""
    return 1.0 + np.abs(value) + np.abs(q - value[:, None]).max(axis=-1)


def wall_features(obs: torch.Tensor) -> torch.Tensor:
    """``obs`` (…, n_obs) with the agent's own position in its line-of-sight frame appended:
    ``(u, v)``, u along the LOS (towards the first other agent: a predator's prey, the prey's
    nearest predator), v to its left; the LOS is +x for coincident disks (docs/departures.md)."""
    own, target = obs[..., 0:2], obs[..., 4:6]
    delta = target - own
    norm = torch.linalg.vector_norm(delta, dim=-1, keepdim=True)
    los = torch.where(norm > 0, delta / norm.clamp_min(1e-12), torch.tensor([1.0, 0.0]))
    u = (own * los).sum(dim=-1, keepdim=True)
    v = own[..., 1:2] * los[..., 0:1] - own[..., 0:1] * los[..., 1:2]
    return torch.cat([obs, u, v], dim=-1)


class DQNLearner:
    """M independent double-DQN learners. Arrays passed in and out have the member axis first.

    ``seed`` is one seed per member (or one from which they are derived): member m's network
    initialisation, exploration and replay sampling draw from its own seed only, so a member
    learns the same whether it is alone or stacked beside others, wherever it sits. The
    counters (transitions stored, updates, target copies) are shared: members move in lockstep.
    """

    def __init__(
        self, n_obs: int, n_actions: int, config: AgentConfig, *, members: int = 1, seed: int | Sequence[int] = 0
    ) -> None:
        if isinstance(n_actions, bool) or not isinstance(n_actions, (int, np.integer)) or n_actions < 1:
            raise ValueError(f"n_actions={n_actions!r}: expected an integer >= 1")
        one_thread_for_scipys_blas()
        self.config, self.members, self.n_obs, self.n_actions = config, members, n_obs, n_actions
        seeds = member_seeds(seed, members)
        n_inputs = n_obs + (WALL_FEATURES if config.wall_features else 0)
        self.online = DuelingQNetwork(n_inputs, n_actions, members=members, seed=seeds)
        self.target = DuelingQNetwork(n_inputs, n_actions, members=members, seed=seeds)
        self.target.load_state_dict(self.online.state_dict())  # starts as a copy (departure)
        self.target.requires_grad_(False)
        self.optimizer = FlatAdam(self.online, lr=config.learning_rate)
        self._target_flat = flatten_parameters(self.target)  # what the compiled update reads
        self._offsets = parameter_offsets(self.online)
        # numpy views of the flat buffers the kernels read and write (the tensors are never rebound)
        self._flat, self._grad = self.optimizer.flat.numpy(), self.optimizer.grad.numpy()
        self._target_np = self._target_flat.numpy()
        self.replay = ReplayStack(
            members,
            config.buffer_size,
            n_obs,
            alpha=config.alpha,
            priority_epsilon=config.priority_epsilon,
            prioritized=config.prioritized,
        )
        self.rngs = [np.random.default_rng(s) for s in seeds]  # exploration and replay sampling
        self._compiled_rngs = CompiledGenerators()
        self.steps = 0  # transitions stored per member
        self.updates = 0
        self._owed_updates = 0.0  # replay_ratio × transitions, not yet done
        self._next_target_copy = config.target_update_every

    @property
    def epsilon(self) -> float:
        return self.config.epsilon(self.steps)

    @property
    def beta(self) -> float:
        return self.config.beta(self.steps)

    def encode(self, obs: np.ndarray | torch.Tensor) -> torch.Tensor:
        """What the networks see of observations (…, n_obs): the observations, with the wall
        features when the config asks for them (the replay keeps the observations)."""
        tensor = torch.as_tensor(obs, dtype=torch.float32)
        return wall_features(tensor) if self.config.wall_features else tensor

    def evaluate(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Q-values (M, B, A) and V(s) (M, B) of the online network for observations (M, B, n_obs)."""
        with torch.no_grad():
            q, value = self.online.q_and_value(self.encode(obs))
        return q.numpy(), value.numpy()

    def decisive_q(self, obs: np.ndarray, member: int, parts: np.ndarray | None = None) -> np.ndarray:
        """Member ``member``'s Q-values (B, A) for observations (B, n_obs), fast, with every row's
        argmax that of :meth:`evaluate` (torch's network, which the committed evaluations used):
        the compiled forward pass, and torch's for the whole batch where some row's two best
        actions lie closer than the two passes can differ (:data:`DECISIVE_GAP`, relative to the
        row's :func:`decision_scale`). ``parts`` (B,) labels runs of consecutive rows as batches
        of their own: torch's pass, whose result for a row may depend on the rows beside it, is
        then made per run that holds such a row, on that run's rows alone (so rows batched
        together here choose as they would have in batches of their own)."""
        if not 0 <= member < self.members:
            raise ValueError(f"member={member!r}: expected one of 0 … {self.members - 1}")
        obs = np.asarray(obs, dtype=np.float32)
        if obs.ndim != 2 or obs.shape[1] != self.n_obs:
            raise ValueError(f"obs of shape {obs.shape}: expected (B, {self.n_obs})")
        flat = self.optimizer.flat.numpy()
        stacked = np.ascontiguousarray(obs)[None]
        wall = self.config.wall_features
        q_all, value_all = q_and_value_kernel(flat, self._offsets, self.n_actions, stacked, wall, member)
        q, value = q_all[0], value_all[0]
        close = undecided_kernel(q, value, np.float32(DECISIVE_GAP))  # one compiled pass: the gap and the scale
        if not close.any():
            return q
        if parts is None:
            return self._torch_q(obs, member)
        q = q.copy()
        starts = np.flatnonzero(np.r_[True, parts[1:] != parts[:-1]])
        for start, end in zip(starts.tolist(), [*starts[1:].tolist(), len(obs)], strict=True):
            if close[start:end].any():
                q[start:end] = self._torch_q(obs[start:end], member)
        return q

    def _torch_q(self, obs: np.ndarray, member: int) -> np.ndarray:
        """Member ``member``'s Q-values (B, A) by torch's network, the other members given zeros."""
        everyone = np.zeros((self.members, *obs.shape), dtype=np.float32)
        everyone[member] = obs
        return self.evaluate(everyone)[0][member]

    def _checked(self, obs: np.ndarray, what: str) -> np.ndarray:
        """``obs`` (M, B, n_obs) for the compiled passes, which read parameters by offset and
        would read past a member's block on a wrong shape: ValueError naming the shape instead."""
        if obs.ndim != 3 or obs.shape[0] != self.members or obs.shape[2] != self.n_obs:
            raise ValueError(f"{what} of shape {obs.shape}: expected ({self.members}, B, {self.n_obs})")
        return obs

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        """Q-values (M, B, A) for observations (M, B, n_obs)."""
        return self.evaluate(obs)[0]

    def choose(self, q_values: np.ndarray, *, explore: bool, epsilon: float | None = None) -> np.ndarray:
        """Actions (M, B) from Q-values: greedy, or ε-greedy when ``explore`` (ε from the schedule
        unless ``epsilon`` is given)."""
        q = np.ascontiguousarray(q_values)
        return choose_kernel(q, *self._exploration(q.shape[1], explore, epsilon))

    def _exploration(self, rows: int, explore: bool, epsilon: float | None) -> tuple[np.ndarray, np.ndarray, float]:
        """The draws of ε-greedy for ``rows`` choices per member (:func:`exploration_kernel`:
        member m's uniforms, then its random actions, both from its own generator) and ε; empty
        arrays when not ``explore``."""
        if not explore:
            return np.empty((self.members, 0)), np.empty((self.members, 0), dtype=np.int64), 0.0
        uniforms, randoms = exploration_kernel(self.generators(), rows, self.n_actions)
        return uniforms, randoms, self.epsilon if epsilon is None else epsilon

    def generators(self) -> Any:
        """The members' generators (``rngs``) as the compiled kernels take them: the same objects,
        so that a draw in a kernel moves them on as numpy's would."""
        return self._compiled_rngs.of(self.rngs)

    def act_members(self, obs: np.ndarray, *, explore: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Actions (M, B), Q-values (M, B, A) and V(s) (M, B) for observations (M, B, n_obs): the
        training loop's acting step, :meth:`act_values` and :meth:`choose` in one compiled call
        when ``explore`` (the ε-greedy draws made in it); greedy, the forward pass and then the
        choice."""
        obs = self._checked(np.ascontiguousarray(obs, dtype=np.float32), "obs")
        if not explore:
            q, value = q_and_value_kernel(self._flat, self._offsets, self.n_actions, obs, self.config.wall_features)
            return self.choose(q, explore=False), q, value
        wall, epsilon = self.config.wall_features, self.epsilon
        return act_kernel(self._flat, self._offsets, self.n_actions, obs, wall, self.generators(), epsilon)

    def act(self, obs: np.ndarray, *, explore: bool, epsilon: float | None = None) -> np.ndarray:
        """Actions (M, B) for observations (M, B, n_obs); see :meth:`choose`."""
        return self.choose(self.q_values(obs), explore=explore, epsilon=epsilon)

    def store(
        self, obs: np.ndarray, actions: np.ndarray, rewards: np.ndarray, next_obs: np.ndarray, terminated: np.ndarray
    ) -> None:
        """Store k transitions per member (arrays (M, k, …)) and copy the target net whenever
        another ``target_update_every`` transitions have been stored."""
        self.replay.add(obs, actions, rewards, next_obs, terminated)
        k = actions.shape[1]
        self.steps += k
        if self.steps >= self.config.learning_starts:
            self._owed_updates += k * self.config.replay_ratio
        while self.steps >= self._next_target_copy:
            self._target_flat.copy_(self.optimizer.flat)  # both networks' parameters, one flat layout
            self._next_target_copy += self.config.target_update_every

    def train(self) -> np.ndarray | None:
        """Do the updates owed by the replay ratio; the members' last losses (M,), or None."""
        losses = None
        while self._owed_updates >= 1.0:
            self._owed_updates -= 1.0
            losses = self.update()
        return losses

    def update(self) -> np.ndarray:
        """One gradient step for every member on its own prioritized batch; losses (M,). The
        numbers of :meth:`learn` on ``replay.sample``'s batch, in one compiled call
        (:func:`~pursuit_bench.agents.fused.replay_update_kernel`)."""
        self.replay.check_drawable(len(self.rngs))  # an empty replay is refused before any draw
        losses = replay_update_kernel(
            self.replay.arrays(),
            self.generators(),
            self.config.batch_size,
            self.beta,
            self._flat,
            self._target_np,
            self._grad,
            self._offsets,
            self.n_actions,
            self.config.gamma,
            self.config.huber_delta,
            self.config.wall_features,
            self.optimizer.arguments(self.optimizer.step_count + 1),
        )
        self.optimizer.step_count += 1
        self.updates += 1
        return losses

    def learn(self, batch: Batch) -> np.ndarray:
        """One gradient step on a batch with the member axis first (M, B, …), then its new
        priorities: the gradient of the Huber loss of the double-DQN targets, weighted by the
        importance weights and summed over the members (the torch reference of
        ``tests/reference/dqn_loss.py``, which the tests hold it to), from the compiled
        update of :mod:`pursuit_bench.agents.fused` (autograd's numbers to float rounding)."""
        self._checked(batch.obs, "batch.obs")
        self._checked(batch.next_obs, "batch.next_obs")
        if (
            batch.actions.shape != batch.obs.shape[:2]
            or not 0 <= batch.actions.min() <= batch.actions.max() < self.n_actions
        ):
            raise ValueError(f"batch.actions: expected shape {batch.obs.shape[:2]} and values in [0, {self.n_actions})")
        losses, td = update_kernel(
            self._flat,
            self._target_np,
            self._grad,
            self._offsets,
            self.n_actions,
            np.ascontiguousarray(batch.obs, dtype=np.float32),
            np.ascontiguousarray(batch.next_obs, dtype=np.float32),
            np.ascontiguousarray(batch.actions, dtype=np.int64),
            np.ascontiguousarray(batch.rewards, dtype=np.float32),
            np.ascontiguousarray(batch.terminated, dtype=np.float32),
            np.ascontiguousarray(batch.weights, dtype=np.float32),
            self.config.gamma,
            self.config.huber_delta,
            self.config.wall_features,
        )
        self.optimizer.step()
        self.replay.update_priorities(batch.indices, td)
        self.updates += 1
        return losses

    def act_values(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Q-values (M, B, A) and V(s) (M, B) for observations (M, B, n_obs) by the compiled
        forward pass the training loop acts with: :meth:`evaluate`'s to float rounding (the
        evaluations use that one, torch's, whose numbers the committed results hold)."""
        obs = self._checked(np.ascontiguousarray(obs, dtype=np.float32), "obs")
        return q_and_value_kernel(self._flat, self._offsets, self.n_actions, obs, self.config.wall_features)

    def take(self, members: Sequence[int]) -> DQNLearner:
        """A learner of these members only (in this order), each with its parameters, target,
        Adam moments, replay, generator and the shared counters: it learns on exactly as they
        would have in this one (a stack's finished runs leave it this way)."""
        keep = list(members)
        new = DQNLearner(self.n_obs, self.n_actions, self.config, members=len(keep), seed=[0] * len(keep))
        with torch.no_grad():
            for mine, theirs in ((self.online, new.online), (self.target, new.target)):
                for param, new_param in zip(mine.parameters(), theirs.parameters(), strict=True):
                    new_param.copy_(param[keep])
            for source, destination in zip(
                self.optimizer.exp_avg + self.optimizer.exp_avg_sq,
                new.optimizer.exp_avg + new.optimizer.exp_avg_sq,
                strict=True,
            ):
                destination.copy_(source[keep])
        new.optimizer.step_count = self.optimizer.step_count
        new.replay = self.replay.take(keep)
        new.rngs = [self.rngs[m] for m in keep]
        new.steps, new.updates = self.steps, self.updates
        new._owed_updates, new._next_target_copy = self._owed_updates, self._next_target_copy
        return new

    def member_weights(self, m: int) -> dict[str, torch.Tensor]:
        """Member m's online network: its parameters by name, without the member axis."""
        return {k: v[m].clone() for k, v in self.online.state_dict().items()}

    def load_member_weights(self, m: int, weights: dict[str, torch.Tensor]) -> None:
        """Give member m these online weights (:meth:`member_weights`), its target net too;
        ``ValueError`` if a name or a shape differs from this learner's network."""
        ours = {k: tuple(v.shape[1:]) for k, v in self.online.state_dict().items()}
        theirs = {k: tuple(v.shape) for k, v in weights.items()}
        if ours != theirs:
            raise ValueError(f"weights of shapes {theirs}: expected {ours}")
        with torch.no_grad():
            for net in (self.online, self.target):
                for name, tensor in net.state_dict().items():
                    tensor[m] = weights[name]

    def member_state(self, m: int) -> dict[str, Any]:
        """Member m's parameters, target, Adam moments, replay and counters, as plain data."""
        adam = self.optimizer
        return {
            "online": self.member_weights(m),
            "target": {k: v[m].clone() for k, v in self.target.state_dict().items()},
            "adam_step": [float(adam.step_count)] * len(adam.params),
            "adam_exp_avg": [avg[m].clone() for avg in adam.exp_avg],
            "adam_exp_avg_sq": [avg_sq[m].clone() for avg_sq in adam.exp_avg_sq],
            "replay": {
                k: (torch.from_numpy(v) if isinstance(v, np.ndarray) else v)
                for k, v in self.replay.member_state(m).items()
            },
            "steps": self.steps,
            "updates": self.updates,
            "owed_updates": self._owed_updates,
            "next_target_copy": self._next_target_copy,
            "rng": self.rngs[m].bit_generator.state,
        }

    def load_member_state(self, m: int, state: dict[str, Any]) -> None:
        """Restore member m from :meth:`member_state` (counters are shared by all members)."""
        with torch.no_grad():
            for net, key in ((self.online, "online"), (self.target, "target")):
                for name, tensor in net.state_dict().items():
                    tensor[m] = state[key][name]
            adam = self.optimizer
            adam.step_count = int(max(state["adam_step"], default=0))
            for exp_avg, exp_avg_sq, avg, avg_sq in zip(
                adam.exp_avg, adam.exp_avg_sq, state["adam_exp_avg"], state["adam_exp_avg_sq"], strict=True
            ):
                if avg is not None:  # None: a parameter that had no Adam state yet
                    exp_avg[m], exp_avg_sq[m] = avg, avg_sq
        replay = {k: (v.numpy() if isinstance(v, torch.Tensor) else v) for k, v in state["replay"].items()}
        self.replay.load_member_state(m, replay)
        self.steps, self.updates = int(state["steps"]), int(state["updates"])
        self._owed_updates, self._next_target_copy = float(state["owed_updates"]), int(state["next_target_copy"])
        self.rngs[m].bit_generator.state = state["rng"]
