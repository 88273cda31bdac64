"""pursuit-bench as a BenchMARL task: its ten conditions through BenchMARL's own extension point
(a ``TaskClass`` and a ``Task`` enum), the env one batched TorchRL env of BenchMARL's
``num_envs`` arenas (``torchrl_env.py``: what TorchRL's ``SerialEnv`` of as many
``PettingZooWrapper`` envs gives, bit for bit through the collectors' loop; stepping it took 17–20×
less CPU, ``benchmarks/bench_marl_env.py``).

Two groups, ``predator`` (1–3 agents) and ``prey`` (1): BenchMARL trains every group of a task,
so the prey learns beside the predators, as the paper's learned runs have it. A predator acts by
one of 24 joint actions (``env/joint_actions.py``), since BenchMARL's algorithms take one
categorical action per agent; the prey by its 12 directions. The group's observation is each
agent's own (docs/spec.md); the env's global state (``env.state()``) is the task's state, which
the centralised critics (MAPPO) and mixers (QMIX) read. Episodes end for all at once
(a capture, a wall, 300 steps): ``terminated`` and ``truncated`` as the env says.

``PursuitTask.PURSUIT_1P_HIGH.get_task()`` is condition 1p-high (any condition: upper case,
``-`` as ``_``, ``PURSUIT_`` in front); its config may hold the env's options
(``max_steps``, ``wall_rule``, ``obstacles``, …; ``pursuit_bench.parallel_env``).

BenchMARL gives its test env (``evaluation=true``, its default; off in ``pursuit-bench marl
train``) the experiment's seed too, as it does for its VMAS tasks: its ``evaluation_episodes``
arenas are seeded as the first training arenas and play their episodes at once, so the first
evaluation starts where the first training episodes started (``evaluation_static`` reseeds them by
``set_seed``, TorchRL's seed chain, to other starts).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from benchmarl.environments.common import Task, TaskClass
from torchrl.data import Composite
from torchrl.envs import EnvBase, PettingZooWrapper

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.joint_actions import JointActionParallelEnv
from pursuit_bench.env.pettingzoo_env import parallel_env
from pursuit_bench.marl.torchrl_env import PursuitTorchRLEnv

PREFIX = "PURSUIT_"
#: Arena ``i`` of a task of experiment seed ``s`` is seeded ``SEED_STRIDE * s + 1 + i``: distinct
#: across the arenas of a run and across the seeds of a study (up to this many arenas a run).
SEED_STRIDE = 1000


def first_seeds(seed: int, num_envs: int) -> list[int]:
    """The arenas' seeds of a run of experiment seed ``seed``. The rows trained before the task was
    vectorized ran ``SerialEnv`` over :func:`make_env` envs made by one counting function, whose
    first env (seed ``SEED_STRIDE * seed``) only gave TorchRL the specs; the envs that trained
    were the next ``num_envs``: these seeds, so that a run's arenas draw the starts they drew
    then (BenchMARL's training itself is not repeatable run to run: PLAN.md)."""
    return [SEED_STRIDE * seed + 1 + i for i in range(num_envs)]


def task_name(condition: str) -> str:
    """The ``PursuitTask`` member's name of a condition: 1p-high → PURSUIT_1P_HIGH."""
    return PREFIX + condition.upper().replace("-", "_")


def condition_of(name: str) -> str:
    """The condition a ``PursuitTask`` member's name stands for."""
    return name.removeprefix(PREFIX).lower().replace("_", "-")


def _only(spec: Composite, groups: list[str], key: str) -> Composite:
    """``spec`` with each group's entries but ``key`` removed, and the global state removed."""
    spec = spec.clone()
    for group in groups:
        for entry in list(spec[group].keys()):
            if entry != key:
                del spec[group][entry]
        if spec[group].is_empty():
            del spec[group]
    if "state" in spec.keys():
        del spec["state"]
    return spec


def make_env(condition: str, seed: int | None, device: Any, **options: Any) -> EnvBase:
    """One env of ``condition`` through TorchRL's ``PettingZooWrapper`` (joint predator actions,
    the global state): the library's generic path, which the batched env reproduces arena for
    arena (``torchrl_env.py``, tested against it)."""
    wrapped = JointActionParallelEnv(parallel_env(condition, **options))
    return PettingZooWrapper(
        wrapped, categorical_actions=True, return_state=True, use_mask=False, seed=seed, device=device
    )


class PursuitTaskClass(TaskClass):
    """A pursuit-bench condition as a BenchMARL task (the module's docstring)."""

    def get_env_fun(
        self, num_envs: int, continuous_actions: bool, seed: int | None, device: Any
    ) -> Callable[[], EnvBase]:
        condition, options = condition_of(self.name), dict(self.config)
        seeds = first_seeds(0 if seed is None else seed, num_envs)  # None: experiment seed 0's arenas

        def batched() -> EnvBase:  # vectorized: BenchMARL steps it as one env (no SerialEnv of num_envs)
            return PursuitTorchRLEnv(condition, seeds, device, **options)

        return batched

    def supports_continuous_actions(self) -> bool:
        return False

    def supports_discrete_actions(self) -> bool:
        return True

    def has_render(self, env: EnvBase) -> bool:
        return False

    def max_steps(self, env: EnvBase) -> int:
        return int(self.config.get("max_steps", CONDITIONS[condition_of(self.name)].max_steps))

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return dict(env.group_map)

    def observation_spec(self, env: EnvBase) -> Composite:
        return _only(env.full_observation_spec_unbatched, list(self.group_map(env)), "observation")

    def info_spec(self, env: EnvBase) -> Composite | None:
        return _only(env.full_observation_spec_unbatched, list(self.group_map(env)), "info")

    def state_spec(self, env: EnvBase) -> Composite | None:
        return Composite({"state": env.full_observation_spec_unbatched["state"].clone()})

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec_unbatched

    @staticmethod
    def env_name() -> str:
        return "pursuit_bench"


class PursuitTask(Task):
    """The ten conditions as BenchMARL tasks (``task_name``: one member per condition, tested)."""

    PURSUIT_1P_LOW = None
    PURSUIT_1P_HIGH = None
    PURSUIT_2P_LOW_SHARED = None
    PURSUIT_2P_LOW_INDIVIDUAL = None
    PURSUIT_2P_HIGH_SHARED = None
    PURSUIT_2P_HIGH_INDIVIDUAL = None
    PURSUIT_3P_LOW_SHARED = None
    PURSUIT_3P_LOW_INDIVIDUAL = None
    PURSUIT_3P_HIGH_SHARED = None
    PURSUIT_3P_HIGH_INDIVIDUAL = None

    @staticmethod
    def associated_class() -> type[TaskClass]:
        return PursuitTaskClass
