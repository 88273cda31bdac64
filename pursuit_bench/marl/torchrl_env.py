"""pursuit-bench as one batched TorchRL env: B arenas of a condition stepped together by the
batched core, with the keys, specs and values that TorchRL's ``PettingZooWrapper`` gives for B
single envs stacked by a ``SerialEnv`` (``benchmarl_task.make_env``), arena for arena and bit for
bit (``tests/test_marl_torchrl_env.py`` compares them step by step).

Why: BenchMARL runs a task that is not vectorized as ``SerialEnv`` over its envs, and that path
cost 4.5–6 ms of CPU per env step here (TensorDict bookkeeping per env and per agent), against
0.2–0.3 ms batched (``benchmarks/bench_marl_env.py``), about a third of a whole IPPO run's CPU;
a vectorized task is stepped as one env (BenchMARL's own rule: an env whose ``batch_size`` is
not empty is taken as it is). The predators act by one of 24 joint actions
(``env/joint_actions.py``), the prey by its 12 directions.

Arena ``i`` plays what a single PettingZoo env seeded ``seeds[i]`` plays once wrapped: the wrapper
resets its env with the seed when it is built (a start drawn and never played), and each later
reset draws the next start from the same generator. ``set_seed(s)`` seeds the arenas as a
``SerialEnv`` seeds its envs: by TorchRL's seed chain (``s``, then each next seed from the last),
and returns the seed after the last arena's. Episodes end for all agents at once; an ended arena
must be reset (a ``_reset`` mask, as TorchRL's collectors and ``rollout`` give) before it is
stepped again, and a reset leaves the live arenas' entries as they were.

Tested bit for bit against the ``SerialEnv`` it replaces through ``step_and_maybe_reset`` (the
collectors' loop) with partial resets, and after ``set_seed``; not through every TorchRL
transform or path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import torch
from tensordict import TensorDict, TensorDictBase
from torchrl._utils import seed_generator
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from pursuit_bench.env import task
from pursuit_bench.env.agent_spaces import POSITION_BOUND, VELOCITY_BOUND, observation_bounds
from pursuit_bench.env.conditions import OBSTACLE_RADII, TaskConfig, resolve_condition
from pursuit_bench.env.core import PursuitCore
from pursuit_bench.env.joint_actions import N_JOINT
from pursuit_bench.env.world import MAX_BLOCKS, Backend

#: The info entries of each group, in the order the PettingZoo env's infos hold them.
PREDATOR_INFO = ("captured", "left_area", "mode", "distance_to_prey")
PREY_INFO = ("captured", "left_area", "distance_to_prey")


class PursuitTorchRLEnv(EnvBase):
    """``len(seeds)`` arenas of ``condition`` as one TorchRL env of batch size ``(len(seeds),)``.

    Args:
        condition: one of the ten conditions, or None with the options.
        seeds: one seed per arena (the seed its wrapped single env would be given).
        device: where the tensors live (the arenas run on the CPU).
        backend: the physics, ``"pymunk"`` (the reference) or ``"numpy"``.
        **options: the task's options (``max_steps``, ``wall_rule``, ``obstacles`` …).

    Groups ``predator`` (the predators, joint actions 0..23) and ``prey`` (one agent, 0..11);
    per group ``observation``, ``info`` (``captured``, ``left_area``, the predators' ``mode``
    (-1 at a reset), ``distance_to_prey``), ``reward``, ``done``, ``terminated``, ``truncated``;
    at the root the global ``state`` and the episode's ``done``, ``terminated``, ``truncated``.
    """

    def __init__(
        self,
        condition: str | None,
        seeds: Sequence[int],
        device: Any = "cpu",
        *,
        backend: Backend = "pymunk",
        **options: Any,
    ) -> None:
        if not len(seeds):
            raise ValueError("seeds: expected one seed per arena, got none")
        config: TaskConfig = resolve_condition(condition, **options)
        if config.continuous:
            raise ValueError("the TorchRL env plays the discrete task: make it with continuous=False")
        arenas = len(seeds)
        if (config.obstacles or config.wall_rule == "contain") and arenas > MAX_BLOCKS:
            raise ValueError(
                f"seeds: {arenas} arenas; at most {MAX_BLOCKS} where there are obstacles or walls that contain "
                "(each arena is laid out as its single env lays it out, one of pymunk's 32 collision categories each)"
            )
        super().__init__(batch_size=torch.Size([arenas]), device=device)
        self.config = config
        names = list(config.agent_names)
        self.group_map = {"predator": names[:-1], "prey": names[-1:]}
        self._n_pred = config.n_predators
        self._arenas = np.arange(arenas)
        self._core = PursuitCore(config, arenas, backend=backend, blocks=[1] * arenas)
        self._obs_size = task.obs_size(config.n_agents, config.obstacles > 0)
        self._rngs = [np.random.default_rng(int(seed)) for seed in seeds]
        self._core.reset(self._arenas, self._rngs)  # the wrapper's reset with the seed when it is built
        self._last: TensorDictBase | None = None  # the last step's or reset's output: a live arena's entries
        self._make_specs()

    def _make_specs(self) -> None:
        b, config = self.batch_size, self.config
        low, high = (torch.from_numpy(v) for v in observation_bounds(config.n_agents, config.obstacles > 0))
        state_bound = np.array(  # the PettingZoo env's state space
            ([POSITION_BOUND] * 2 + [VELOCITY_BOUND] * 2) * config.n_agents
            + [POSITION_BOUND, POSITION_BOUND, OBSTACLE_RADII[1]] * config.obstacles,
            dtype=np.float32,
        )
        device, flags = self.device, ("done", "terminated", "truncated")
        observation, action, reward, done = {}, {}, {}, {}
        for group, agents in self.group_map.items():
            k = len(agents)
            shape = torch.Size([*b, k])
            info = PREDATOR_INFO if group == "predator" else PREY_INFO
            observation[group] = Composite(
                observation=Bounded(
                    low=low.expand(*shape, -1),
                    high=high.expand(*shape, -1),
                    shape=(*shape, len(low)),
                    dtype=torch.float32,
                    device=self.device,
                ),
                info=Composite(
                    {key: Unbounded(shape=shape, device=device) for key in info}, shape=shape, device=device
                ),
                shape=shape,
                device=self.device,
            )
            action[group] = Composite(
                action=Categorical(
                    n=N_JOINT if group == "predator" else task.N_DIRECTIONS, shape=shape, device=self.device
                ),
                shape=shape,
                device=self.device,
            )
            reward[group] = Composite(reward=Unbounded(shape=(*shape, 1), device=device), shape=shape, device=device)
            done[group] = Composite(
                {key: Categorical(n=2, shape=(*shape, 1), device=device, dtype=torch.bool) for key in flags},
                shape=shape,
                device=self.device,
            )
        bound = torch.from_numpy(state_bound)
        self.observation_spec = Composite(
            **observation,
            state=Bounded(
                low=-bound.expand(*b, -1),
                high=bound.expand(*b, -1),
                shape=(*b, len(bound)),
                dtype=torch.float32,
                device=self.device,
            ),
            shape=b,
            device=self.device,
        )
        self.action_spec = Composite(**action, shape=b, device=self.device)
        self.reward_spec = Composite(**reward, shape=b, device=self.device)
        self.done_spec = Composite(
            **done,
            **{key: Categorical(n=2, shape=(*b, 1), device=device, dtype=torch.bool) for key in flags},
            shape=b,
            device=self.device,
        )

    def set_seed(self, seed: int | None = None, static_seed: bool = False) -> int | None:
        """Seed the arenas as a ``SerialEnv`` of the wrapped envs seeds its envs: arena 0 ``seed``,
        each next arena TorchRL's next seed in the chain (all ``seed`` with ``static_seed``), each
        arena's next start drawn now (the wrapped env resets with its seed); returns the seed after
        the last arena's. ``None`` leaves the arenas as they are."""
        if seed is None:
            return None
        seeds = []
        for _ in self._arenas:
            seeds.append(seed)
            seed = seed if static_seed else seed_generator(seed)
        self._rngs = [np.random.default_rng(int(s)) for s in seeds]
        self._core.reset(self._arenas, self._rngs)
        self._last = None
        return seed

    def _set_seed(self, seed: int | None) -> None:
        if seed is not None:
            self.set_seed(seed)

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        if kwargs:
            given = ", ".join(sorted(kwargs))
            raise ValueError(f"reset: takes no options (got {given}); seed the arenas with set_seed")
        mask = self._reset_mask(tensordict)
        if self._last is None and not mask.all():
            raise ValueError("reset: the first reset resets every arena (no _reset mask)")
        arenas = self._arenas[mask]
        n = len(self._arenas)
        obs = np.zeros((n, self.config.n_agents, self._obs_size), np.float32)
        obs[arenas] = self._core.reset(arenas, [self._rngs[i] for i in arenas.tolist()])
        distance = task.distances_to_prey(self._core.world.positions)
        no = np.zeros((n, self.config.n_agents), dtype=bool)
        modes = np.full((n, self._n_pred), -1)
        out = TensorDict(self._observations(obs, no[:, :-1], no, modes, distance), batch_size=self.batch_size)
        for group, agents in self.group_map.items():
            for key in ("done", "terminated", "truncated"):
                out[group, key] = torch.zeros((*self.batch_size, len(agents), 1), dtype=torch.bool)
        for key in ("done", "terminated", "truncated"):
            out[key] = torch.zeros((*self.batch_size, 1), dtype=torch.bool)
        out = out.to(self.device)
        if self._last is not None and not mask.all():  # the live arenas' entries as they were
            live = torch.as_tensor(~mask, device=self.device)
            for key in out.keys(True, True):
                kept = self._last.get(key)
                out.set(key, torch.where(live.reshape(-1, *([1] * (kept.dim() - 1))), kept, out.get(key)))
        self._last = out
        return out

    def _reset_mask(self, tensordict: TensorDictBase | None) -> np.ndarray:
        """Which arenas to reset: those any ``_reset`` entry names (all when none is given)."""
        if tensordict is None:
            return np.ones(len(self._arenas), dtype=bool)
        flags = [tensordict.get(key, None) for key in ("_reset", ("predator", "_reset"), ("prey", "_reset"))]
        given = [f.reshape(len(self._arenas), -1).any(-1) for f in flags if f is not None]
        if not given:
            return np.ones(len(self._arenas), dtype=bool)
        mask = given[0]
        for more in given[1:]:
            mask = mask | more
        return mask.cpu().numpy()

    def _observations(
        self, obs: np.ndarray, prey_contact: np.ndarray, wall: np.ndarray, modes: np.ndarray, distance: np.ndarray
    ) -> dict[str, Any]:
        """The groups' observations and infos and the global state, as tensors."""
        n = self._n_pred
        device = self.device

        def t(a: np.ndarray) -> torch.Tensor:
            return torch.as_tensor(np.ascontiguousarray(a, dtype=np.float32), device=device)

        b = self.batch_size
        predator = TensorDict(
            observation=t(obs[:, :n]),
            info=TensorDict(
                captured=t(prey_contact),
                left_area=t(wall[:, :n]),
                mode=t(modes),
                distance_to_prey=t(distance[:, :n]),
                batch_size=(*b, n),
                device=device,
            ),
            batch_size=(*b, n),
            device=device,
        )
        prey = TensorDict(
            observation=t(obs[:, n:]),
            info=TensorDict(
                captured=t(np.asarray(prey_contact.any(axis=1, keepdims=True))),
                left_area=t(wall[:, n:]),
                distance_to_prey=t(distance[:, n:]),
                batch_size=(*b, 1),
                device=device,
            ),
            batch_size=(*b, 1),
            device=device,
        )
        return {"predator": predator, "prey": prey, "state": t(self._core.state())}

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        ended = (
            np.zeros(len(self._arenas), bool) if self._last is None else self._last["done"].reshape(-1).cpu().numpy()
        )
        if ended.any():
            raise ValueError(
                f"step: arenas {self._arenas[ended].tolist()} ended their episodes; reset them first "
                "(reset with a _reset mask, as step_and_maybe_reset and rollout do)"
            )
        joint = tensordict.get(("predator", "action")).cpu().numpy()
        prey = tensordict.get(("prey", "action")).cpu().numpy()
        for name, given, n in (("predator", joint, N_JOINT), ("prey", prey, task.N_DIRECTIONS)):
            if given.shape != (len(self._arenas), len(self.group_map[name])):
                shape = (len(self._arenas), len(self.group_map[name]))
                raise ValueError(f"actions: ({name!r}, 'action') of shape {tuple(given.shape)}; expected {shape}")
            if given.size and not 0 <= given.min() <= given.max() < n:
                raise ValueError(
                    f"actions: ({name!r}, 'action') holds {given.min()}..{given.max()}; expected integers in 0..{n - 1}"
                )
        modes, directions = np.divmod(joint.astype(np.int64), task.N_DIRECTIONS)
        r = self._core.step(modes, np.concatenate([directions, prey.astype(np.int64)], axis=1))
        out = self._observations(r.observations, r.contacts.prey, r.contacts.wall, r.modes, r.distance_to_prey)
        n = self._n_pred
        rewards = torch.as_tensor(r.rewards.astype(np.float32), device=self.device)
        terminated = torch.as_tensor(r.terminated, device=self.device).reshape(*self.batch_size, 1)
        truncated = torch.as_tensor(r.truncated, device=self.device).reshape(*self.batch_size, 1)
        done = terminated | truncated
        for group, columns in (("predator", slice(0, n)), ("prey", slice(n, None))):
            k = len(self.group_map[group])
            out[group]["reward"] = rewards[:, columns].unsqueeze(-1)
            out[group]["done"] = done.unsqueeze(1).expand(-1, k, -1).clone()
            out[group]["terminated"] = terminated.unsqueeze(1).expand(-1, k, -1).clone()
            out[group]["truncated"] = truncated.unsqueeze(1).expand(-1, k, -1).clone()
        out["done"], out["terminated"], out["truncated"] = done, terminated.clone(), truncated.clone()
        self._last = TensorDict(out, batch_size=self.batch_size, device=self.device)
        return self._last
