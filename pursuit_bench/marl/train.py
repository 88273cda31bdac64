"""Train one of BenchMARL's algorithms on a pursuit-bench condition and write its teams as team
files (``agents/team_file.py``) that ``score`` and ``eval --agent`` play.

The library's own experiment runs as it is: its default configuration (BenchMARL's
``base_experiment.yaml``, the algorithm's and the MLP's yaml), changed only where running here
needs it (:func:`experiment_config`: the budget, the CSV logger alone, no rendering, checkpoints
for resuming). A run folder holds BenchMARL's experiment (``benchmarl/``), ``predator.safetensors``
and ``prey.safetensors`` (each group's final policy, greedy) and ``marl.json`` (what was run).
Rerunning the same command on the same folder resumes from the last checkpoint."""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np
import torch
from benchmarl.algorithms import IppoConfig, IqlConfig, MappoConfig, QmixConfig
from benchmarl.experiment import Experiment, ExperimentConfig
from benchmarl.experiment.callback import Callback
from benchmarl.models.mlp import MlpConfig
from tensordict import TensorDict
from torchrl.envs.utils import ExplorationType, set_exploration_type

from pursuit_bench.agents import team_file
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.io.files import atomic_write_text
from pursuit_bench.marl.benchmarl_task import PursuitTask, task_name

#: The algorithms ``marl train`` offers, by BenchMARL's names.
ALGORITHMS = {"ippo": IppoConfig, "mappo": MappoConfig, "iql": IqlConfig, "qmix": QmixConfig}
#: Checkpoints every this many collection batches (BenchMARL's own, for resuming).
CHECKPOINT_EVERY = 10
#: Observations drawn to check that a written team file acts as BenchMARL's policy does.
CHECK_ROWS = 4096


#: Settings ``marl train`` owns (the budget, logging, where and how often it saves).
RESERVED = frozenset(
    {"max_n_frames", "max_n_iters", "loggers", "render", "save_folder", "restore_file", "checkpoint_interval",
     "checkpoint_at_end", "keep_checkpoints_num", "sampling_device", "train_device", "buffer_device",
     "restore_map_location"}
)  # fmt: skip


def _settable() -> str:
    fields = [k for k in vars(ExperimentConfig.get_from_yaml()) if k not in RESERVED]
    return f"BenchMARL's ExperimentConfig fields but {', '.join(sorted(RESERVED))}; e.g. {', '.join(fields[:3])}"


def _typed(key: str, value: str, default: Any) -> Any:
    """``value`` as the type of the setting's default; ValueError in one line if it is not one."""
    if isinstance(default, (dict, list, tuple)):
        raise ValueError(f"--set {key}=…: a {type(default).__name__} setting; only numbers, flags and words here")
    try:
        if isinstance(default, bool):
            if value.lower() not in ("true", "false"):
                raise ValueError
            return value.lower() == "true"
        if isinstance(default, int):
            return int(value.replace("_", ""))
        if isinstance(default, float) or default is None:
            return float(value) if default is not None or value.lower() != "null" else None
        return value
    except ValueError:
        raise ValueError(
            f"--set {key}={value}: expected a value of type {type(default).__name__} like {default!r}"
        ) from None


@dataclass(frozen=True)
class MarlRun:
    """One BenchMARL training run on pursuit-bench."""

    algorithm: str
    """One of :data:`ALGORITHMS` (ippo, mappo, iql, qmix)."""
    condition: str
    """One of the ten conditions (``pursuit-bench conditions``)."""
    frames: int
    """The budget in env steps (BenchMARL's frames: one per step of one env); at least one
    collection batch of the library's default size (6000), or the whole budget as one batch when smaller."""
    seed: int
    """BenchMARL's experiment seed (its generators, the envs' draws)."""
    settings: tuple[tuple[str, str], ...] = ()
    """Changes to BenchMARL's experiment configuration (``ExperimentConfig`` fields, e.g.
    ``("on_policy_n_minibatch_iters", "2")``), each value read as the field's type; none by default."""

    def __post_init__(self) -> None:
        if self.algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm {self.algorithm!r}: expected one of {', '.join(ALGORITHMS)}")
        if self.condition not in CONDITIONS:
            raise ValueError(f"condition {self.condition!r}: expected one of {', '.join(CONDITIONS)}")
        if self.frames < 1 or self.seed < 0:
            raise ValueError(f"frames {self.frames} and seed {self.seed}: expected frames >= 1, seed >= 0")
        defaults = ExperimentConfig.get_from_yaml()
        for key, value in self.settings:
            if key in RESERVED or not hasattr(defaults, key):
                raise ValueError(f"--set {key}=…: not an experiment setting one may change here ({_settable()})")
            _typed(key, value, getattr(defaults, key))


def experiment_config(run: MarlRun, folder: Path) -> ExperimentConfig:
    """BenchMARL's default experiment configuration, with what running here changes: the budget,
    the batch no larger than it, the CSV logger alone (no Weights & Biases), no rendering,
    a checkpoint every :data:`CHECKPOINT_EVERY` batches and at the end (one kept)."""
    config = ExperimentConfig.get_from_yaml()
    on_policy = ALGORITHMS[run.algorithm].on_policy()
    for key, value in run.settings:
        setattr(config, key, _typed(key, value, getattr(config, key)))
    config.max_n_frames = run.frames
    batch = min(config.collected_frames_per_batch(on_policy), run.frames)
    if on_policy:
        config.on_policy_collected_frames_per_batch = batch
        config.on_policy_minibatch_size = min(config.on_policy_minibatch_size, batch)
    else:
        config.off_policy_collected_frames_per_batch = batch
    config.evaluation_interval = batch * max(1, config.evaluation_interval // batch)
    config.loggers = ["csv"]
    config.render = False
    config.save_folder = str(folder.resolve())  # pickled by BenchMARL: a resume from elsewhere finds it
    config.checkpoint_interval = batch * CHECKPOINT_EVERY
    config.checkpoint_at_end = True
    config.keep_checkpoints_num = 2  # the one before the newest, should a stop cut the newest off
    return config


class OneThread(Callback):
    """Keeps torch on one thread through the run, whatever sets it back. When the task ran under
    TorchRL's ``SerialEnv`` (before it was one batched env), closing a batched env set the count
    back to the one torch had when torchrl was imported (``BatchedEnvBase.close``): measured, 2
    after the first collection, and on two busy cores two threads made every op of the update 15×
    slower (tanh of 400 × 2 × 256 took 7.7 ms, 0.43 ms on one thread). The task no longer builds
    one; the callback stays as a guard, since a thread count set back costs that much."""

    def on_setup(self) -> None:
        torch.set_num_threads(1)

    def on_batch_collected(self, batch: TensorDict) -> None:
        torch.set_num_threads(1)

    def on_evaluation_end(self, rollouts: list[TensorDict]) -> None:
        torch.set_num_threads(1)


def check_folder(run: MarlRun, folder: Path) -> None:
    """ValueError unless ``folder`` is new, empty, or holds this same run (``run.json``) to resume."""
    if not folder.exists() or not any(folder.iterdir()):
        return
    stored = folder / "run.json"
    if not stored.is_file():
        raise ValueError(f"{folder}: not empty and not a marl run folder (no run.json): pick another --out")
    before = json.loads(stored.read_text())
    if before != asdict(run) | {"settings": [list(pair) for pair in run.settings]}:
        raise ValueError(
            f"{folder}: holds another run ({before}); resume it with its own options or pick another --out"
        )


def last_checkpoint(folder: Path) -> Path | None:
    """The newest BenchMARL checkpoint under ``folder`` (most frames) that loads, or None. BenchMARL
    writes checkpoints in place, so one cut off by a stop is passed over for the one before it."""
    found = sorted(folder.glob("*/checkpoints/checkpoint_*.pt"), key=lambda p: int(p.stem.split("_")[-1]))
    for path in reversed(found):
        try:
            torch.load(path, map_location="cpu", weights_only=False)  # BenchMARL's own format (our own file)
        except Exception:  # a checkpoint cut off mid-write: torch raises several kinds
            continue
        return path
    return None


def experiment(run: MarlRun, folder: Path) -> Experiment:
    """The run's BenchMARL experiment: resumed from its last checkpoint in ``folder`` if any."""
    torch.set_num_threads(1)  # networks this small run fastest on one thread (and OneThread keeps it so)
    checkpoint = last_checkpoint(folder)
    if checkpoint is not None:
        return Experiment.reload_from_file(str(checkpoint), experiment_patch={"save_folder": str(folder.resolve())})
    task = getattr(PursuitTask, task_name(run.condition)).get_task(config={})
    return Experiment(
        task=task,
        algorithm_config=ALGORITHMS[run.algorithm].get_from_yaml(),
        model_config=MlpConfig.get_from_yaml(),
        critic_model_config=MlpConfig.get_from_yaml(),
        seed=run.seed,
        config=experiment_config(run, folder),
        callbacks=[OneThread()],
    )


def _dense_layers(policy: torch.nn.Module, n_agents: int) -> list[list[tuple[torch.Tensor, torch.Tensor]]]:
    """Each agent's (weight, bias) per dense layer of a group's BenchMARL MLP policy, in order
    (parameters shared within the group give every agent the same)."""
    params = dict(policy.named_parameters())
    found: dict[int, dict[str, torch.Tensor]] = {}
    for name, tensor in params.items():
        parts = name.split(".")
        if len(parts) >= 3 and parts[-3] == "params" and parts[-1] in ("weight", "bias"):
            found.setdefault(int(parts[-2]), {})[parts[-1]] = tensor
    if not found:
        raise ValueError("no MLP parameters in the policy: pursuit-bench exports BenchMARL's MlpConfig models only")
    layers = [(found[k]["weight"], found[k]["bias"]) for k in sorted(found)]
    if layers[0][0].dim() == 2:
        return [layers] * n_agents
    return [[(w[i], b[i]) for w, b in layers] for i in range(n_agents)]


def export(experiment: Experiment, run: MarlRun, folder: Path) -> dict[str, int]:
    """Write each group's final policy as ``{group}.safetensors`` and check that it acts as the
    library's greedy policy does on :data:`CHECK_ROWS` observations drawn from the group's
    observation space; returns the disagreements per group (expected 0)."""
    activation = experiment.model_config.activation_class
    name = {torch.nn.Tanh: "tanh", torch.nn.ReLU: "relu"}.get(activation)
    if name is None or experiment.model_config.norm_class is not None:
        raise ValueError(f"pursuit-bench exports MLPs with Tanh or ReLU and no norm layers, not {activation}")
    generator = torch.Generator().manual_seed(run.seed)
    disagreements = {}
    for group, agents in experiment.group_map.items():
        policy = experiment.group_policies[group]
        layers = _dense_layers(policy, len(agents))
        path = folder / f"{group}.safetensors"
        header = {
            "role": group,
            "condition": run.condition,
            "activation": name,
            "library": f"benchmarl {version('benchmarl')}",
            "algorithm": run.algorithm,
            "seed": str(run.seed),
            "frames": str(experiment.total_frames),
        }
        team_file.write(path, dict(zip(agents, layers, strict=True)), header)
        spec = experiment.observation_spec[group, "observation"]
        bound = torch.as_tensor(spec.space.high).clamp(max=3.0) if hasattr(spec.space, "high") else 3.0
        obs = (torch.rand((CHECK_ROWS, *spec.shape), generator=generator) * 2 - 1) * bound
        with torch.no_grad(), set_exploration_type(ExplorationType.DETERMINISTIC):
            acted = policy(TensorDict({group: {"observation": obs}}, batch_size=[CHECK_ROWS]))
        theirs = acted[group, "action"].numpy()
        team = team_file.Team(path)
        ours = np.stack([team.member(i).scores(obs[:, i].numpy()).argmax(-1).numpy() for i in range(len(agents))], 1)
        disagreements[group] = int((theirs.reshape(ours.shape) != ours).sum())
    return disagreements


def train(run: MarlRun, folder: Path) -> dict[str, Any]:
    """Train (or resume) ``run`` in ``folder``, write its team files and ``marl.json``; returns
    what ``marl.json`` holds. A finished run (its ``marl.json`` there) is not touched again.
    ValueError, and no team files, if a team file does not act as BenchMARL's policy does."""
    check_folder(run, folder)
    if (folder / "marl.json").is_file():
        done: dict[str, Any] = json.loads((folder / "marl.json").read_text())
        return done
    folder.mkdir(parents=True, exist_ok=True)
    stored = asdict(run) | {"settings": [list(pair) for pair in run.settings]}
    atomic_write_text(folder / "run.json", json.dumps(stored) + "\n")
    (folder / "benchmarl").mkdir(exist_ok=True)
    started = time.process_time()
    made = experiment(run, folder / "benchmarl")
    made.run()  # closes the experiment's envs itself, however it ends
    disagreements = export(made, run, folder)
    if any(disagreements.values()):
        for group in made.group_map:
            (folder / f"{group}.safetensors").unlink(missing_ok=True)
        raise ValueError(
            f"{folder}: the exported teams do not act as BenchMARL's policies ({disagreements} of "
            f"{CHECK_ROWS} observations differ): not written; a model other than BenchMARL's MlpConfig?"
        )
    summary = {
        "run": asdict(run),
        "library": {name: version(name) for name in ("benchmarl", "torchrl", "tensordict", "torch")},
        "frames": int(made.total_frames),
        "cpu_s_this_call": time.process_time() - started,
        "teams": {group: f"{group}.safetensors" for group in made.group_map},
        "export_disagreements": disagreements,
    }
    atomic_write_text(folder / "marl.json", json.dumps(summary, indent=1) + "\n")
    return summary
