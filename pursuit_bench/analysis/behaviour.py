"""The behaviour behind the numbers (the paper's Fig. 3 and section 3.4): what each trained
predator's value stream represents, and when it chases.

:func:`collect` plays evaluation episodes by the paper's protocol (predators greedy, the prey
ε-greedy with ε = 0.1) and keeps, for every step and every hierarchical predator, the value
stream's last hidden layer, V(s), the mode chosen, its distance to the prey and whether it is
the closest predator. :func:`embed` maps a subsample of the hidden layers to 2-D with
scikit-learn's t-SNE (seeded; scikit-learn rather than openTSNE because it also provides the
k-NN regression that scores the embedding, and openTSNE would bring it anyway), and
:func:`organisation` scores how well the embedding is organised by a quantity: the
cross-validated R² of a k-nearest-neighbour regression of that quantity on the embedding (1: the
neighbours of a point predict it exactly; about 0 or below: no organisation).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pursuit_bench.agents.kinds import HierarchicalPredator
from pursuit_bench.agents.residual import ResidualPredator
from pursuit_bench.env.task import N_DIRECTIONS
from pursuit_bench.rules.navigation import navigate
from pursuit_bench.training.evaluate import Actor, run_episodes

#: Distance bins of P(chase | distance), in arena units (the arena is 2 wide).
DISTANCE_BINS = np.round(np.arange(0.0, 2.01, 0.1), 2)
#: States embedded per predator at most (t-SNE's cost grows faster than the states).
EMBEDDED = 2000
NEIGHBOURS = 10


@dataclass
class PredatorStates:
    """Every state one predator acted in, in the order played."""

    features: np.ndarray
    """(N, 32) the value stream's last hidden layer."""
    value: np.ndarray
    """(N,) V(s)."""
    mode: np.ndarray
    """(N,) 0 stalk, 1 chase."""
    distance: np.ndarray
    """(N,) distance to the prey."""
    closest: np.ndarray
    """(N,) bool: no other predator is closer to the prey."""
    onsets: np.ndarray
    """Distances to the prey at which chase bouts started (a step in chase after one in stalk,
    within an episode)."""
    positions: np.ndarray
    """(N, n_agents, 2) every agent's position in that state."""
    correction: np.ndarray | None = None
    """(N,) a residual predator's correction of its rule's direction, in steps of 30° (−6 … +5:
    the direction it took minus the one the rule gives); None for the hierarchical predator."""


def collect(
    condition: str,
    agents: dict[str, Actor],
    *,
    episodes: int,
    seed: int,
    num_envs: int = 32,
    task_options: Mapping[str, Any] | None = None,
) -> dict[str, PredatorStates]:
    """Play ``episodes`` by the paper's protocol (in the task ``task_options`` make of the
    condition: obstacles); the states of every hierarchical predator."""
    names = list(agents)
    predators = [i for i, n in enumerate(names[:-1]) if isinstance(agents[n], HierarchicalPredator)]
    steps: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []

    def on_step(obs: np.ndarray, actions: np.ndarray, done: np.ndarray, counted: np.ndarray) -> None:
        steps.append((obs.copy(), actions[:, :-1].copy(), done.copy(), counted))

    epsilons = {names[-1]: 0.1}
    run_episodes(
        condition,
        agents,
        episodes,
        seed=seed,
        num_envs=num_envs,
        epsilons=epsilons,
        on_step=on_step,
        task_options=task_options,
    )
    obs = np.stack([s[0] for s in steps])  # (T, B, n, n_obs)
    actions = np.stack([s[1] for s in steps])  # (T, B, n_pred, 2)
    modes = actions[..., 0]  # (T, B, n_pred)
    done = np.stack([s[2] for s in steps])  # (T, B)
    counted = np.stack([s[3] for s in steps])  # (T, B): the step belongs to one of the episodes
    positions = obs[..., 0:2]  # (T, B, n, 2): every agent's own position
    distances = np.linalg.norm(positions[:, :, :-1] - positions[:, :, -1:], axis=-1)  # (T, B, n_pred)
    closest = distances == distances.min(axis=-1, keepdims=True)
    fresh = np.concatenate([np.ones((1, done.shape[1]), dtype=bool), done[:-1]])  # first step of an episode
    out = {}
    for i in predators:
        agent = agents[names[i]]
        assert isinstance(agent, HierarchicalPredator)
        flat_obs = obs[:, :, i][counted]
        features, value = agent.value_features(flat_obs)
        started = (modes[1:, :, i] == 1) & (modes[:-1, :, i] == 0) & ~fresh[1:] & counted[1:]
        correction = None
        if isinstance(agent, ResidualPredator):
            rule = navigate(flat_obs, modes[:, :, i][counted], avoidance=agent.avoidance)
            taken = actions[:, :, i, 1][counted]
            correction = (taken - rule + N_DIRECTIONS // 2) % N_DIRECTIONS - N_DIRECTIONS // 2
        out[names[i]] = PredatorStates(
            features=features,
            value=value,
            mode=modes[:, :, i][counted],
            distance=distances[:, :, i][counted],
            closest=closest[:, :, i][counted],
            onsets=distances[1:, :, i][started],
            positions=positions[counted],
            correction=correction,
        )
    return out


def chase_by_distance(distance: np.ndarray, mode: np.ndarray) -> dict[str, list[float | None] | list[int]]:
    """P(chase) per distance bin (None for an empty bin) and the number of states behind each."""
    index = np.clip(np.digitize(distance, DISTANCE_BINS) - 1, 0, len(DISTANCE_BINS) - 2)
    counts = np.bincount(index, minlength=len(DISTANCE_BINS) - 1)
    chases = np.bincount(index, weights=mode, minlength=len(DISTANCE_BINS) - 1)
    probability = [float(c / n) if n else None for c, n in zip(chases, counts, strict=True)]
    return {"bins": DISTANCE_BINS.tolist(), "p_chase": probability, "states": counts.tolist()}


def correction_by_distance(distance: np.ndarray, mode: np.ndarray, correction: np.ndarray) -> dict[str, Any]:
    """A residual predator's corrections per mode and distance bin: the share of states it
    corrected the rule (k ≠ 0) and the mean correction (steps of 30°), None for an empty bin;
    and over all its states, how often it used each correction."""
    index = np.clip(np.digitize(distance, DISTANCE_BINS) - 1, 0, len(DISTANCE_BINS) - 2)
    by_mode: dict[str, Any] = {}
    for value, label in ((0, "stalk"), (1, "chase")):
        chosen = mode == value
        counts = np.bincount(index[chosen], minlength=len(DISTANCE_BINS) - 1)
        corrected = np.bincount(index[chosen], weights=correction[chosen] != 0, minlength=len(DISTANCE_BINS) - 1)
        total = np.bincount(index[chosen], weights=correction[chosen], minlength=len(DISTANCE_BINS) - 1)
        by_mode[label] = {
            "corrected": [float(c / n) if n else None for c, n in zip(corrected, counts, strict=True)],
            "mean_correction": [float(t / n) if n else None for t, n in zip(total, counts, strict=True)],
            "states": counts.tolist(),
        }
    used = {int(k): int(n) for k, n in zip(*np.unique(correction, return_counts=True), strict=True)}
    return {"bins": DISTANCE_BINS.tolist(), **by_mode, "used": used}


def onset_summary(onsets: np.ndarray) -> dict[str, Any]:
    """Median and quartiles of the distances at which chase bouts start."""
    if len(onsets) == 0:
        return {"bouts": 0, "median": None, "quartiles": None}
    q1, median, q3 = np.percentile(onsets, [25, 50, 75])
    return {"bouts": len(onsets), "median": float(median), "quartiles": [float(q1), float(q3)]}


def embed(features: np.ndarray, seed: int) -> np.ndarray:
    """A 2-D t-SNE embedding (N, 2) of ``features`` (scikit-learn, PCA start, seeded)."""
    from sklearn.manifold import TSNE

    perplexity = float(min(30.0, max(2.0, (len(features) - 1) / 3)))
    tsne = TSNE(n_components=2, perplexity=perplexity, init="pca", random_state=seed)
    return np.asarray(tsne.fit_transform(features.astype(np.float64)))


def organisation(embedding: np.ndarray, quantity: np.ndarray, seed: int = 0) -> float:
    """Cross-validated R² (5 folds) of a k-NN regression of ``quantity`` on ``embedding``."""
    from sklearn.model_selection import KFold, cross_val_score
    from sklearn.neighbors import KNeighborsRegressor

    folds = KFold(n_splits=5, shuffle=True, random_state=seed)
    model = KNeighborsRegressor(n_neighbors=min(NEIGHBOURS, len(embedding) // 2))
    return float(np.mean(cross_val_score(model, embedding, quantity, cv=folds, scoring="r2")))


def subsample(count: int, seed: int, limit: int = EMBEDDED) -> np.ndarray:
    """Indices of at most ``limit`` of ``count`` states, drawn without replacement, in order."""
    if count <= limit:
        return np.arange(count)
    return np.sort(np.random.default_rng(seed).choice(count, size=limit, replace=False))


def analyse(states: dict[str, PredatorStates], seed: int) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The numbers of analysis.json, and each predator's embedded subsample's indices and
    coordinates (for the figures and the recording)."""
    result: dict[str, Any] = {}
    embeddings: dict[str, np.ndarray] = {}
    for name, s in states.items():
        picked = subsample(len(s.value), seed)
        embedding = embed(s.features[picked], seed)
        embeddings[name] = np.concatenate([picked[:, None], embedding], axis=1)
        result[name] = {
            "states": len(s.value),
            "embedded": len(picked),
            "organisation": {
                "distance": organisation(embedding, s.distance[picked], seed),
                "value": organisation(embedding, s.value[picked], seed),
            },
            "chase_by_distance": chase_by_distance(s.distance, s.mode),
            "chase_onset_distance": onset_summary(s.onsets),
            "p_chase": float(s.mode.mean()),
            **(
                {"correction_by_distance": correction_by_distance(s.distance, s.mode, s.correction)}
                if s.correction is not None
                else {}
            ),
            "distance": np.round(s.distance, 4).tolist(),
            "mode": s.mode.astype(int).tolist(),
        }
    return result, embeddings
