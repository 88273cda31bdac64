"""A Stable-Baselines3 model as an agent: ``eval --agent NAME=MODEL.zip`` and ``score MODEL.zip``.

A model trained on the single-agent Gymnasium view (``pursuit_bench/Pursuit-v0``,
docs/tutorials/sb3.md) acts on the agent's own observation with the agent's own discrete action
space (a predator's ``MultiDiscrete([2, 12])``, the prey's ``Discrete(12)``), so its saved policy
answers the agent protocol (``agents/external.py``) as it is. Any algorithm's ``.zip`` (PPO, A2C,
DQN, …) loads the same way: its policy is built from the class, keyword arguments and spaces the
file names, its weights put in, and it acts greedily (``deterministic=True``).

Stable-Baselines3 stores those four entries pickled (cloudpickle): loading one runs code the file
names, as ``PPO.load`` does. Only they are read; every other entry of the file (schedules,
buffers, the last observations) is left unread. Load only models you trust."""

from __future__ import annotations

import json
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

#: The entries of a model file that building its policy needs; the rest is never unpickled.
NEEDED = ("policy_class", "policy_kwargs", "observation_space", "action_space")


def is_model_path(spec: str) -> bool:
    """Whether an ``--agent`` value names a Stable-Baselines3 model file rather than MODULE:FACTORY."""
    return spec.endswith(".zip")


class SB3Policy:
    """The policy of the Stable-Baselines3 model in ``path``, behind ``act_batch``."""

    def __init__(self, path: str | Path) -> None:
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"{path}: no such model file")
        try:
            from stable_baselines3.common.save_util import load_from_zip_file
        except ModuleNotFoundError:
            raise ValueError(
                f"{path}: a Stable-Baselines3 model needs stable-baselines3 (pip install stable-baselines3)"
            ) from None
        try:
            with zipfile.ZipFile(path) as archive:
                entries = json.loads(archive.read("data"))
        except (zipfile.BadZipFile, KeyError, ValueError):
            raise ValueError(f"{path}: not a Stable-Baselines3 model (no 'data' entry in a zip file)") from None
        missing = [k for k in NEEDED if k not in entries]
        if missing:
            raise ValueError(f"{path}: a Stable-Baselines3 file without {', '.join(missing)}")
        unread = {key: None for key in entries if key not in NEEDED}
        try:
            data, params, _ = load_from_zip_file(path, custom_objects=unread, device="cpu")
            assert data is not None
            policy = data["policy_class"](
                data["observation_space"], data["action_space"], _no_schedule, **(data["policy_kwargs"] or {})
            )
            policy.load_state_dict(params["policy"])
        except Exception as error:
            raise ValueError(f"{path}: its policy could not be built ({type(error).__name__}: {error})") from None
        policy.set_training_mode(False)
        self.path, self.policy = path, policy
        self.observes = int(np.prod(data["observation_space"].shape))
        self.action_space = data["action_space"]

    def check_role(self, predator: bool) -> None:
        """ValueError in one line unless the model's action space is the role's: a predator's
        ``MultiDiscrete([2, 12])`` (mode, direction), the prey's ``Discrete(12)``."""
        space = self.action_space
        nvec = getattr(space, "nvec", None)
        if predator and not (nvec is not None and list(np.ravel(nvec)) == [2, 12]):
            raise ValueError(
                f"{self.path}: a predator acts in MultiDiscrete([2, 12]) (mode, direction); this model in {space}"
            )
        if not predator and getattr(space, "n", None) != 12:
            raise ValueError(f"{self.path}: the prey acts in Discrete(12) (a direction); this model in {space}")

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        """Greedy actions for a stack of observations (B, 6n − 2)."""
        if observations.shape[1] != self.observes:
            raise ValueError(
                f"the model observes {self.observes} numbers, this agent {observations.shape[1]}: "
                "it was trained in a condition with another number of agents"
            )
        actions, _ = self.policy.predict(observations.astype(np.float32), deterministic=True)
        return np.asarray(actions)


def _no_schedule(_: float) -> float:
    """The learning-rate schedule a policy is built with: never used when it only acts."""
    return 0.0


def make_factory(spec: str) -> Callable[[], SB3Policy]:
    """The factory ``--agent NAME=MODEL.zip`` stands for (each call loads the model afresh)."""
    return lambda: SB3Policy(spec)
