"""pursuit-bench as a BenchMARL task: its ten conditions through BenchMARL's own extension point
(a ``TaskClass`` and a ``Task`` enum), the env wrapped by TorchRL's ``PettingZooWrapper``.

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
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

from benchmarl.environments.common import Task, TaskClass
from torchrl.data import Composite
from torchrl.envs import EnvBase, PettingZooWrapper

from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.joint_actions import JointActionParallelEnv
from pursuit_bench.env.pettingzoo_env import parallel_env

PREFIX = "PURSUIT_"
#: Env ``i`` made by a task of experiment seed ``s`` is seeded ``SEED_STRIDE * s + i``: distinct
#: across the envs of a run and across the seeds of a study (up to this many envs a run).
SEED_STRIDE = 1000


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
    """One env of ``condition`` as TorchRL sees it (joint predator actions, the global state)."""
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
        made = itertools.count()  # BenchMARL builds its num_envs training envs from this one function

        def one() -> EnvBase:  # each env its own seed: one seed for all gave every env the same starts
            return make_env(condition, None if seed is None else SEED_STRIDE * seed + next(made), device, **options)

        return one

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
        return _only(env.observation_spec, list(self.group_map(env)), "observation")

    def info_spec(self, env: EnvBase) -> Composite | None:
        return _only(env.observation_spec, list(self.group_map(env)), "info")

    def state_spec(self, env: EnvBase) -> Composite | None:
        return Composite({"state": env.observation_spec["state"].clone()})

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec

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
