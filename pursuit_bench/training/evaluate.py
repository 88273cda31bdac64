"""The paper's evaluation protocol: fixed agents played for many episodes in B arenas
(:func:`run_episodes`), the protocol's variants played together with common random numbers
(:func:`play_variants`: episode e's start state and exploration draws depend on the evaluation
seed, e and the agent alone) and what they did (:func:`evaluate_agents`), and a run folder's
evaluation written beside it (:func:`evaluate_folder`, :func:`evaluate_into`)."""

from __future__ import annotations

import functools
import json
import os
import shutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from pursuit_bench.agents.kinds import HierarchicalPredator, LearningAgent, ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS, resolve_condition
from pursuit_bench.env.perturbations import Perturbations, PerturbedEnv
from pursuit_bench.env.vector import VectorPursuitEnv, put_actions
from pursuit_bench.env.world import MAX_BLOCKS, Backend
from pursuit_bench.io.files import atomic_write_bytes, atomic_write_text
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey
from pursuit_bench.training import runs
from pursuit_bench.training.train_config import TrainConfig
from pursuit_bench.trajectories.movement_tracks import MovementTracks
from pursuit_bench.trajectories.recording import EpisodeSink, EpisodeTraces, Recorder, Sinks
from pursuit_bench.trajectories.trajectory_csv import TrajectoryCSV

#: Draws an evaluation's figure: ``figure(result, run name) -> PNG bytes`` (the command line
#: passes ``figures.plots.reward_bars_png``; this layer draws nothing itself).
Figure = Callable[[dict[str, Any], str], bytes]


class Actor(Protocol):
    def act_batch(self, obs: np.ndarray, *, explore: bool = False, epsilon: float | None = None) -> Any: ...


@dataclass
class Episodes:
    """Per-episode results, in the order the episodes finished."""

    returns: np.ndarray
    """(E, n_agents) cumulative reward."""
    lengths: np.ndarray
    """(E,) steps."""
    captured: np.ndarray
    """(E,) bool."""
    chase_fraction: np.ndarray
    """(E, n_predators) fraction of steps in chase mode."""
    distance: np.ndarray
    """(E, n_agents) distance travelled."""
    left_area: np.ndarray
    """(E, n_agents) bool: the agent touched a wall on the episode's last step."""
    collisions: np.ndarray
    """(E, n_agents) collisions with obstacles: steps on which the agent came to touch one it
    had not touched on the step before (0 without obstacles)."""
    contact_steps: np.ndarray
    """(E, n_agents) steps that ended with the agent touching an obstacle."""


def run_episodes(
    condition: str,
    actors: dict[str, Actor],
    episodes: int,
    *,
    seed: int,
    num_envs: int = 16,
    epsilons: dict[str, float] | None = None,
    backend: Backend = "pymunk",
    recorder: EpisodeSink | None = None,
    record: Callable[[int], bool] = lambda episode: True,
    on_step: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None] | None = None,
    check: Callable[[], None] = lambda: None,
    task_options: Mapping[str, Any] | None = None,
    perturbations: Perturbations | None = None,
) -> Episodes:
    """Play ``episodes`` episodes with ``actors`` (one per agent name). Agents named in
    ``epsilons`` act ε-greedily with that ε (learning agents only), the rest greedily. With a
    ``recorder``, the episodes numbered (from 1, in the order they end) where ``record`` says so
    go into it, with the hierarchical predators' Q-values and V(s). The episodes are the first
    ``episodes`` to start, each played to its end (an arena that ends one starts the next while
    any is left, then plays on unheard); they come in the order they end. ``on_step(obs, actions,
    done, counted)`` hears every step: the observations acted on (B, n_agents, n_obs), the actions
    (B, n_agents, 2), which arenas' episodes the step ended (B,) and which arenas were playing
    one of the ``episodes`` (B,; an arena stops counting for good). ``check()`` is called
    before every step: the place to stop (by raising) when the caller was asked to.
    ``task_options``: task options beside the condition (``obstacles``, ``obstacle_radius``).
    ``perturbations``: the world's changes join the task options, and the agents sense and act
    through :class:`~pursuit_bench.env.perturbations.PerturbedEnv` (seeded by ``seed``)."""
    p = perturbations or Perturbations()
    options = {**(task_options or {}), **p.task_options()}
    plain = VectorPursuitEnv(min(num_envs, episodes), condition, backend=backend, **options)
    env = PerturbedEnv(plain, p, seed) if p.senses else plain
    epsilons = epsilons or {}
    names, n_pred = env.agents, env.n_agents - 1
    obs, _ = env.reset(seed=seed)
    traces = None
    if recorder is not None:
        traces = EpisodeTraces(env.core.world.positions, env.config.max_steps, env.core.obstacles)
    chase = np.zeros((env.num_envs, n_pred))
    travelled = np.zeros((env.num_envs, env.n_agents))
    touching = np.zeros((env.num_envs, env.n_agents), dtype=bool)
    collisions = np.zeros((env.num_envs, env.n_agents))
    contact = np.zeros((env.num_envs, env.n_agents))
    rows: list[tuple[np.ndarray, int, bool, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    # Each arena's episode counts if it was one of the first ``episodes`` to start: an arena whose
    # episode ends starts a counted one while any is left, else plays on unheard. So every counted
    # episode is played to its end (keeping the first to *finish* would favour short ones).
    counting = np.ones(env.num_envs, dtype=bool)
    started = env.num_envs
    while counting.any():
        check()
        actions = np.zeros((env.num_envs, env.n_agents, 2), dtype=np.int64)
        q_values = np.full((env.num_envs, n_pred, 2), np.nan)
        values = np.full((env.num_envs, n_pred), np.nan)
        for i, name in enumerate(names):
            actor, eps = actors[name], epsilons.get(name)
            if traces is not None and isinstance(actor, HierarchicalPredator):
                _, chosen, q, values[:, i] = actor.decide(obs[:, i], explore=eps is not None, epsilon=eps)
                q_values[:, i] = actor.mode_q(q)
            else:
                chosen = np.asarray(actor.act_batch(obs[:, i], explore=eps is not None, epsilon=eps))
            put_actions(actions, i, chosen)
        before = env.core.world.positions.copy()
        acted_on = obs
        obs, rewards, _, truncated, info = env.step(actions)
        if on_step is not None:
            on_step(acted_on, actions, info["done"], counting.copy())
        travelled += np.hypot(*(info["positions"] - before).transpose(2, 0, 1))
        chase += actions[:, :-1, 0]
        collisions += info["touching_obstacle"] & ~touching
        contact += info["touching_obstacle"]
        touching = info["touching_obstacle"] & ~info["done"][:, None]
        if traces is not None:
            traces.add_step(actions, rewards, info, q_values, values)
        for arena in np.flatnonzero(info["done"]):
            counted = bool(counting[arena])
            if counted:
                length = int(info["episode_length"][arena])
                counting[arena] = started < episodes
                started += int(counting[arena])
                rows.append(
                    (
                        info["episode_return"][arena].copy(),
                        length,
                        bool(info["captured"][arena]),
                        chase[arena] / length,
                        travelled[arena].copy(),
                        info["left_area"][arena].copy(),
                        collisions[arena].copy(),
                        contact[arena].copy(),
                    )
                )
            chase[arena] = 0.0
            travelled[arena] = 0.0
            collisions[arena] = 0.0
            contact[arena] = 0.0
            if traces is not None:
                trace = traces.finish(
                    int(arena),
                    bool(truncated[arena, 0]),
                    env.core.world.positions[arena],
                    env.core.world.obstacles[arena],
                )
                if counted and recorder is not None and record(len(rows)):
                    recorder.log_episode(len(rows), trace)
    return Episodes(
        returns=np.array([r[0] for r in rows]),
        lengths=np.array([r[1] for r in rows]),
        captured=np.array([r[2] for r in rows]),
        chase_fraction=np.array([r[3] for r in rows]).reshape(len(rows), n_pred),
        distance=np.array([r[4] for r in rows]),
        left_area=np.array([r[5] for r in rows]).reshape(len(rows), len(names)),
        collisions=np.array([r[6] for r in rows]).reshape(len(rows), len(names)),
        contact_steps=np.array([r[7] for r in rows]).reshape(len(rows), len(names)),
    )


# --- common random numbers -----------------------------------------------------------------------

#: The evaluation protocol a result was made by (its ``protocol["draws"]``): ``"crn-1"``, common
#: random numbers (:func:`play_variants`). Results without the field were made before it (issue
#: 47): one generator per learner, run through the variants in turn, episodes kept in the order
#: they finished.
PROTOCOL = "crn-1"
#: ``protocol["draws"]`` of an evaluation with perturbed senses: each variant played alone by
#: :func:`run_episodes`, every episode to its end (``"sequential"`` before 2026-12-03: the
#: episodes that finished first).
SEQUENTIAL = "sequential-to-end"


def episode_seed(seed: int, episode: int) -> int:
    """The start-state seed of episode ``episode`` of an evaluation seeded ``seed``, in whichever
    arena and variant it is played."""
    return int(np.random.SeedSequence([seed, 0, episode]).generate_state(1, np.uint64)[0])


def exploration_draws(seed: int, episode: int, agent: int, steps: int, n_actions: int) -> tuple[np.ndarray, np.ndarray]:
    """The exploration draws of agent number ``agent`` in episode ``episode`` of an evaluation
    seeded ``seed``: per step, a uniform number (the agent explores where it is below ε) and the
    random action it then takes. They depend on nothing else, so every variant, every run and
    every kind of predator meets the same draws in the same episode."""
    rng = np.random.default_rng([seed, 1, episode, agent])
    return rng.random(steps), rng.integers(0, n_actions, steps)


Variant = tuple[dict[str, Actor], dict[str, float]]
"""One variant of an evaluation: the actor of each agent and the ε of those that explore."""


def play_variants(
    condition: str,
    variants: list[Variant],
    episodes: int,
    *,
    seed: int,
    num_envs: int = 64,
    backend: Backend = "pymunk",
    recorder: EpisodeSink | None = None,
    check: Callable[[], None] = lambda: None,
    task_options: Mapping[str, Any] | None = None,
    parts: list[int] | None = None,
) -> list[Episodes]:
    """Play episodes ``0 … episodes-1`` of every variant (the actors of each agent; a learning
    agent named in the ε dict acts ε-greedily) in one batch of ``min(num_envs, episodes)``
    arenas per variant, with common random numbers: episode ``e`` starts from the state
    :func:`episode_seed` gives it and each exploring agent draws from :func:`exploration_draws` of
    (``seed``, ``e``, agent), in whichever arena it is played. So episode ``e`` differs between
    variants only where their actors do, and a variant's result does not depend on the others
    played beside it. An arena that ends an episode starts the variant's next unplayed one; all
    are played to their end (none is dropped for being long). Results come per variant in
    episode order. A ``recorder`` (one variant only) receives every episode, numbered from 1,
    with the hierarchical predators' Q-values and V(s); ``check()`` is called before every step.

    ``parts`` (one label per variant, in non-decreasing order; by default all one part) says
    which variants used to be played in calls of their own: a network's forward pass covers all
    its rows at once, and where it falls back on torch's pass (:meth:`DQNLearner.decisive_q`) it
    makes it per part, so every variant plays exactly as it did in its own call."""
    if recorder is not None and len(variants) != 1:
        raise ValueError(f"a recorder records one variant, got {len(variants)}")
    labels = np.zeros(len(variants), dtype=np.int64) if parts is None else np.asarray(parts, dtype=np.int64)
    if labels.shape != (len(variants),) or np.any(np.diff(labels) < 0):
        raise ValueError(f"parts={parts!r}: expected one label per variant, in non-decreasing order")
    options = dict(task_options or {})
    task = resolve_condition(condition, **options)
    static = task.wall_rule == "contain" or task.obstacles > 0
    if static and len(np.unique(labels)) > MAX_BLOCKS:  # one world keeps that many parts' walls apart
        begins = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
        cut = int(begins[MAX_BLOCKS])
        play = functools.partial(
            play_variants, condition, episodes=episodes, seed=seed, num_envs=num_envs, backend=backend,
            check=check, task_options=task_options,
        )  # fmt: skip
        return play(variants[:cut], parts=labels[:cut].tolist()) + play(variants[cut:], parts=labels[cut:].tolist())
    arenas = min(num_envs, episodes)
    n, count = len(variants) * arenas, len(variants)
    # each part's arenas laid out in the physics as the part's own env would lay them out
    blocks = (np.bincount(labels)[np.unique(labels)] * arenas).tolist()
    env = VectorPursuitEnv(n, condition, backend=backend, blocks=blocks, **options)
    names, n_pred, steps = env.agents, env.n_agents - 1, env.config.max_steps
    variant = np.arange(n) // arenas
    part = labels[variant]  # each row's part: rows of one actor lie in variant order, so parts run in blocks
    playing = np.arange(n) % arenas  # each arena's episode now (``episodes`` or more: idle)
    following = playing + arenas  # the episode it starts next (reserved: its start is set ahead)
    handed = np.full(count, 2 * arenas)  # per variant, the next episode not yet reserved
    # every episode's start drawn once, for all the variants that play it: what an arena reset
    # with the episode's seed draws (the first arenas are reset so; the others queue theirs),
    # kept until every variant has queued it
    obs, _ = env.reset(seed=[episode_seed(seed, int(e)) for e in playing])
    drawn: dict[int, tuple[np.ndarray, np.ndarray, int]] = {}
    idle_start = env.core.first_start(np.random.default_rng(episode_seed(seed, 0)))

    def start_of(e: int) -> tuple[np.ndarray, np.ndarray]:
        if e >= episodes:  # an idle arena (its variant's episodes all handed out) replays episode 0's start, unheard
            return idle_start
        if e not in drawn:
            drawn[e] = (*env.core.first_start(np.random.default_rng(episode_seed(seed, e))), count)
        layout, around, left = drawn[e]
        if left == 1:
            del drawn[e]
        else:
            drawn[e] = (layout, around, left - 1)
        return layout, around

    def queue(rows: np.ndarray) -> None:
        if len(rows):
            chosen = [start_of(e) for e in following[rows].tolist()]
            layouts = np.array([layout for layout, _ in chosen])
            around = np.array([a for _, a in chosen]) if env.config.obstacles else None
            env.queue_starts(rows, layouts, around)

    queue(np.arange(n))
    # per agent: rows grouped by actor (one forward pass or call each), and each row's ε (0: greedy)
    groups: list[list[tuple[Actor, np.ndarray]]] = []
    eps = np.zeros((n, env.n_agents))
    for i, name in enumerate(names):
        by_actor: dict[Any, tuple[Actor, list[np.ndarray]]] = {}
        for v, (actors, epsilons) in enumerate(variants):
            rows = np.flatnonzero(variant == v)
            by_actor.setdefault(_batch_key(actors[name]), (actors[name], []))[1].append(rows)
            if isinstance(actors[name], LearningAgent) and name in epsilons:
                eps[rows, i] = epsilons[name]
        groups.append([(actor, np.concatenate(rows)) for actor, rows in by_actor.values()])
    exploring = [i for i in range(env.n_agents) if eps[:, i].any()]
    draws = {i: (np.ones((n, steps)), np.zeros((n, steps), dtype=np.int64)) for i in exploring}
    # each episode's exploration draws made once for every variant that plays it, kept until the last has
    players = {i: np.bincount(variant[eps[:, i] > 0], minlength=count).astype(bool).sum() for i in exploring}
    made: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, int]] = {}

    def redraw(rows: np.ndarray) -> None:
        for i in exploring:
            n_actions = next(a.n_actions for a, _ in groups[i] if isinstance(a, LearningAgent))
            for row in rows[(eps[rows, i] > 0) & (playing[rows] < episodes)].tolist():
                key = (i, int(playing[row]))
                if key not in made:
                    made[key] = (*exploration_draws(seed, key[1], i, steps, n_actions), int(players[i]))
                uniform, action, left = made[key]
                draws[i][0][row], draws[i][1][row] = uniform, action
                if left == 1:
                    del made[key]
                else:
                    made[key] = (uniform, action, left - 1)

    redraw(np.arange(n))
    shapes = {
        "returns": (env.n_agents,), "lengths": (), "captured": (), "chase_fraction": (n_pred,),
        "distance": (env.n_agents,), "left_area": (env.n_agents,), "collisions": (env.n_agents,),
        "contact_steps": (env.n_agents,),
    }  # fmt: skip
    kinds = {"lengths": np.int64, "captured": bool, "left_area": bool}
    out = {k: np.zeros((count, episodes, *shape), dtype=kinds.get(k, float)) for k, shape in shapes.items()}
    traces = None
    if recorder is not None:
        traces = EpisodeTraces(env.core.world.positions, steps, env.core.obstacles)
    chase = np.zeros((n, n_pred))
    travelled = np.zeros((n, env.n_agents))
    touching = np.zeros((n, env.n_agents), dtype=bool)
    collisions = np.zeros((n, env.n_agents))
    contact = np.zeros((n, env.n_agents))
    step = np.zeros(n, dtype=np.int64)
    while (busy := playing < episodes).any():  # idle arenas step on with action 0, unheard
        check()
        actions = np.zeros((n, env.n_agents, 2), dtype=np.int64)
        if traces is not None:  # what a recording shows of the hierarchical predators
            q_values = np.full((n, n_pred, 2), np.nan)
            values = np.full((n, n_pred), np.nan)
        for i in range(env.n_agents):
            for actor, every in groups[i]:
                rows = every[busy[every]]
                if not len(rows):
                    continue
                seen = obs[rows, i]
                if isinstance(actor, LearningAgent):
                    choices = actor.learner.decisive_q(seen, actor.member, part[rows]).argmax(axis=-1)
                    if i in exploring:
                        at = step[rows]
                        random = draws[i][0][rows, at] < eps[rows, i]
                        choices = np.where(random, draws[i][1][rows, at], choices)
                    chosen = actor.to_env(choices, seen)
                    if traces is not None and isinstance(actor, HierarchicalPredator):
                        _, _, q, values[rows, i] = actor.decide(seen, explore=False)
                        q_values[rows, i] = actor.mode_q(q)
                else:
                    chosen = np.asarray(actor.act_batch(seen))
                if chosen.ndim == 2:
                    actions[rows, i] = chosen
                else:
                    actions[rows, i, 1] = chosen
        before = env.core.world.positions.copy()
        obs, rewards, _, truncated, info = env.step(actions)
        travelled += np.hypot(*(info["positions"] - before).transpose(2, 0, 1))
        chase += actions[:, :-1, 0]
        collisions += info["touching_obstacle"] & ~touching
        contact += info["touching_obstacle"]
        touching = info["touching_obstacle"] & ~info["done"][:, None]
        step += 1
        if traces is not None:
            traces.add_step(actions, rewards, info, q_values, values)
        ended = np.flatnonzero(info["done"])
        real = ended[playing[ended] < episodes]  # idle arenas' endings are not heard
        at_v, at_e = variant[real], playing[real]
        lengths = info["episode_length"][real]
        out["returns"][at_v, at_e] = info["episode_return"][real]
        out["lengths"][at_v, at_e] = lengths
        out["captured"][at_v, at_e] = info["captured"][real]
        out["chase_fraction"][at_v, at_e] = chase[real] / lengths[:, None]
        out["distance"][at_v, at_e] = travelled[real]
        out["left_area"][at_v, at_e] = info["left_area"][real]
        out["collisions"][at_v, at_e] = collisions[real]
        out["contact_steps"][at_v, at_e] = contact[real]
        if traces is not None and recorder is not None:
            for row in ended.tolist():
                trace = traces.finish(
                    row, bool(truncated[row, 0]), env.core.world.positions[row], env.core.world.obstacles[row]
                )
                if playing[row] < episodes:
                    recorder.log_episode(int(playing[row]) + 1, trace)
        # in arena order: an ended arena starts its variant's next reserved episode and reserves the
        # next unreserved one (a variant's arenas are consecutive rows, so a rank within it is an offset)
        mine = variant[ended]
        rank = np.arange(len(ended)) - np.searchsorted(mine, mine)
        playing[ended] = following[ended]
        following[ended] = handed[mine] + rank
        handed += np.bincount(mine, minlength=count)
        queue(ended)
        chase[ended] = travelled[ended] = collisions[ended] = contact[ended] = 0.0
        step[ended] = 0
        redraw(ended)
    return [Episodes(**{k: x[v] for k, x in out.items()}) for v in range(count)]


def _batch_key(actor: Actor) -> Any:
    """What an actor's rows are grouped by for one call a step: the actor itself, or for a
    scripted rule whose rows act independently (``row_wise``) its kind and settings, so that
    copies made for many variants act in one call."""
    policy = getattr(actor, "policy", None)
    if isinstance(actor, ScriptedAgent) and getattr(policy, "row_wise", False):
        return (type(policy), tuple(sorted(vars(policy).items())))
    return id(actor)


def standard_error(values: np.ndarray) -> float:
    """The standard error of the mean of ``values`` (0 for a single value)."""
    return float(values.std(ddof=1) / np.sqrt(len(values))) if len(values) > 1 else 0.0


def prey_outcomes(played: Episodes, max_steps: int) -> dict[str, float]:
    """The prey's (the last agent's) mean return, and the fraction of episodes in which it was
    caught, ran into a wall uncaught (``left_area``: caught against a wall counts as caught), or
    survived to the time limit (not caught, nobody at a wall): the three add to one but for
    episodes a predator ended by running into a wall."""
    caught = played.captured.astype(bool)
    left = played.left_area.astype(bool)
    return {
        "return": float(played.returns[:, -1].mean()),
        "left_area": float((left[:, -1] & ~caught).mean()),
        "captured": float(caught.mean()),
        "survived": float(((played.lengths == max_steps) & ~caught & ~left.any(axis=1)).mean()),
    }


def evaluate_agents(
    condition: str,
    agents: dict[str, Actor],
    *,
    episodes: int,
    seed: int,
    prey_epsilon: float | None = 0.1,
    num_envs: int = 64,
    recorder: EpisodeSink | None = None,
    backend: Backend = "pymunk",
    predator_kind: str | None = None,
    check: Callable[[], None] = lambda: None,
    task_options: Mapping[str, Any] | None = None,
    avoidance: bool = False,
    perturbations: Perturbations | None = None,
    prey_check: bool = True,
    outcomes: bool = False,
) -> dict[str, Any]:
    """The paper's protocol (section 3.4): predators greedy, the prey ε-greedy with ε = 0.1 (a
    learning prey; ``prey_epsilon=None`` for a scripted one). For each predator, its mean
    cumulative reward as trained, then with it replaced by always-chase and by always-stalk,
    the other agents fixed. Every variant plays the same episodes with common random numbers:
    the same start states and the same exploration draws of the prey (:func:`play_variants`, all
    variants in one batch of arenas; ``protocol["draws"]`` says :data:`PROTOCOL`); with
    perturbed senses each variant is played alone (:data:`SEQUENTIAL`: :func:`run_episodes`).
    Also the capture rate, time to capture, distance travelled and fraction of steps in chase, as
    trained. The episodes as
    trained go into ``recorder``. With a learning prey, ``prey_check`` compares it, greedy,
    with ``FleeingPrey`` in its place against the same predators on the same seeds: return,
    wall exits, captures, survival to the time limit.

    Each panel holds the mean returns ``trained`` (the predator as trained), ``always_chase``
    and ``always_stalk``, their standard errors and every episode's return (``stderr``,
    ``episode_returns``, keyed alike); ``predator_kind`` names what the trained predators are (``hierarchical``,
    ``flat``, …; by default read from the first predator's ``kind``). ``check()`` is called
    before every step (:func:`run_episodes`).

    With obstacles (``task_options``), the baselines' lower layer avoids them as ``avoidance``
    says (that of the trained predators), the scripted prey avoids them, and the result holds
    ``obstacle_collisions`` and ``obstacle_contact_steps``: each agent's collisions and steps
    in contact per episode, as trained (:class:`Episodes`).

    ``perturbations`` (:mod:`pursuit_bench.env.perturbations`) change every variant's world and
    senses alike; the result names them (``perturbations``). ``prey_check=False`` skips the
    prey's check (two plays fewer). ``outcomes=True`` adds ``prey_outcomes``: the prey's return,
    wall exits, captures and survival in the trained variant's episodes, as it played them
    (:func:`prey_outcomes`)."""
    variants, checking = _protocol_variants(agents, prey_epsilon, prey_check, avoidance, task_options)
    crn = perturbations is None or not perturbations.senses
    if crn:  # every variant in one batch of arenas, with common random numbers
        options = {**(task_options or {}), **(perturbations or Perturbations()).task_options()}

        def batch(chosen: list[Variant], rec: EpisodeSink | None = None) -> list[Episodes]:
            return play_variants(
                condition, chosen, episodes, seed=seed, num_envs=num_envs, backend=backend, recorder=rec,
                check=check, task_options=options,
            )  # fmt: skip

        played = batch(variants[:1], recorder) + batch(variants[1:]) if recorder else batch(variants)
    else:  # perturbed senses draw their noise across the arenas of one env: each variant played alone
        played = [
            run_episodes(
                condition, actors, episodes, seed=seed, num_envs=num_envs, epsilons=eps,
                recorder=recorder if k == 0 else None, backend=backend, check=check,
                task_options=task_options, perturbations=perturbations,
            )
            for k, (actors, eps) in enumerate(variants)
        ]  # fmt: skip
    return _protocol_result(
        condition, agents, played, episodes=episodes, seed=seed, prey_epsilon=prey_epsilon,
        predator_kind=predator_kind, checking=checking, crn=crn, task_options=task_options,
        perturbations=perturbations, outcomes=outcomes,
    )  # fmt: skip


def evaluate_together(
    condition: str,
    setups: list[tuple[dict[str, Actor], float | None]],
    *,
    episodes: int,
    seed: int,
    num_envs: int = 64,
    backend: Backend = "pymunk",
    predator_kind: str | None = None,
    check: Callable[[], None] = lambda: None,
    task_options: Mapping[str, Any] | None = None,
    avoidance: bool = False,
    perturbations: Perturbations | None = None,
    prey_check: bool = True,
    outcomes: bool = False,
) -> list[dict[str, Any]]:
    """:func:`evaluate_agents` of each setup (the agents and the prey's ε, ``prey_epsilon``) with
    the options given, every setup's variants in one batch of arenas: the same results (common
    random numbers make an episode's play independent of what is played beside it), at a cost
    per step shared by all of them. A study judges a run against every member of a population
    so. Perturbed senses (each variant played alone) and a recording go through
    :func:`evaluate_agents`."""
    if perturbations is not None and perturbations.senses:
        raise ValueError("perturbed senses play each variant alone: use evaluate_agents")
    plans = [_protocol_variants(agents, eps, prey_check, avoidance, task_options) for agents, eps in setups]
    options = {**(task_options or {}), **(perturbations or Perturbations()).task_options()}
    played = play_variants(
        condition, [v for variants, _ in plans for v in variants], episodes, seed=seed, num_envs=num_envs,
        backend=backend, check=check, task_options=options,
        parts=[k for k, (variants, _) in enumerate(plans) for _ in variants],
    )  # fmt: skip
    out, at = [], 0
    for (agents, eps), (variants, checking) in zip(setups, plans, strict=True):
        mine, at = played[at : at + len(variants)], at + len(variants)
        out.append(
            _protocol_result(
                condition,
                agents,
                mine,
                episodes=episodes,
                seed=seed,
                prey_epsilon=eps,
                predator_kind=predator_kind,
                checking=checking,
                crn=True,
                task_options=task_options,
                perturbations=perturbations,
                outcomes=outcomes,
            )
        )
    return out


def _protocol_variants(
    agents: dict[str, Actor],
    prey_epsilon: float | None,
    prey_check: bool,
    avoidance: bool,
    task_options: Mapping[str, Any] | None,
) -> tuple[list[Variant], bool]:
    """The protocol's variants of ``agents`` (as trained, then each predator replaced by
    always-chase and by always-stalk, then the prey's check where it applies) and whether the
    prey's check is among them."""
    names = list(agents)
    predators, prey = names[:-1], names[-1]
    epsilons = {} if prey_epsilon is None else {prey: prey_epsilon}
    scripted_prey = isinstance(agents[prey], ScriptedAgent)  # FleeingPrey put in as a held-out opponent, say
    checking = prey_epsilon is not None and prey_check and not scripted_prey  # a learning prey: greedy, and FleeingPrey
    variants: list[Variant] = [(agents, epsilons)]
    for name in predators:
        for rule in (AlwaysChase, AlwaysStalk):
            variants.append(({**agents, name: ScriptedAgent(name, rule(avoidance=avoidance))}, epsilons))
    if checking:
        fleeing_prey = ScriptedAgent(prey, FleeingPrey(obstacles=bool((task_options or {}).get("obstacles"))))
        variants += [(agents, {}), ({**agents, prey: fleeing_prey}, {})]
    return variants, checking


def _protocol_result(
    condition: str,
    agents: dict[str, Actor],
    played: list[Episodes],
    *,
    episodes: int,
    seed: int,
    prey_epsilon: float | None,
    predator_kind: str | None,
    checking: bool,
    crn: bool,
    task_options: Mapping[str, Any] | None,
    perturbations: Perturbations | None,
    outcomes: bool = False,
) -> dict[str, Any]:
    """What :func:`evaluate_agents` returns, from its variants' episodes (``played``, in the
    order :func:`_protocol_variants` gives them)."""
    names = list(agents)
    obstacles = bool((task_options or {}).get("obstacles"))
    predators, prey = names[:-1], names[-1]
    kind = predator_kind or str(getattr(agents[predators[0]], "kind", "trained"))
    trained = played[0]
    panels = []
    for i, name in enumerate(predators):
        chase, stalk = played[1 + 2 * i], played[2 + 2 * i]
        variants_played = {"trained": trained, "always_chase": chase, "always_stalk": stalk}
        panels.append(
            {
                "predator": name,
                **{key: float(e.returns[:, i].mean()) for key, e in variants_played.items()},
                "stderr": {key: standard_error(e.returns[:, i]) for key, e in variants_played.items()},
                "episode_returns": {key: e.returns[:, i].round(6).tolist() for key, e in variants_played.items()},
            }
        )
    captured = trained.captured
    checked = None
    if checking:
        greedy, fleeing = played[-2:]
        checked = {
            name: prey_outcomes(e, CONDITIONS[condition].max_steps)
            for name, e in (("learned_greedy", greedy), ("fleeing_prey", fleeing))
        }
    return {
        "condition": condition,
        "episodes": episodes,
        "seed": seed,
        "predator_kind": kind,
        "prey_kind": str(getattr(agents[prey], "kind", "prey")),
        "panels": panels,
        "capture_rate": float(captured.mean()),
        "time_to_capture_s": float(trained.lengths[captured].mean() * 0.1) if captured.any() else None,
        "episode_length": float(trained.lengths.mean()),
        "mean_return": {a: float(r) for a, r in zip(names, trained.returns.mean(axis=0), strict=True)},
        "distance_travelled": {a: float(d) for a, d in zip(names, trained.distance.mean(axis=0), strict=True)},
        "chase_fraction": {a: float(c) for a, c in zip(predators, trained.chase_fraction.mean(axis=0), strict=True)},
        "protocol": {
            "predators": "greedy",
            # the ε the prey played with: only our learning prey explore (a scripted or external one acts as it is)
            "prey_epsilon": prey_epsilon if isinstance(agents[prey], LearningAgent) else None,
            "draws": PROTOCOL if crn else SEQUENTIAL,
        },
        "prey_check": checked,
        **({"prey_outcomes": prey_outcomes(trained, CONDITIONS[condition].max_steps)} if outcomes else {}),
        **({"perturbations": perturbations.changed} if perturbations is not None and perturbations.changed else {}),
        **(
            {
                "task_options": dict(task_options or {}),
                "obstacle_collisions": dict(zip(names, trained.collisions.mean(axis=0).tolist(), strict=True)),
                "obstacle_contact_steps": dict(zip(names, trained.contact_steps.mean(axis=0).tolist(), strict=True)),
            }
            if obstacles
            else {}
        ),
    }


def evaluate_folder(
    folder: Path, *, tag: str | None = None, checkpoint: str = runs.CHECKPOINT, **options: Any
) -> dict[str, Any]:
    """Evaluate a trained run folder (its lock held by the caller) by the paper's protocol and
    write ``eval.json``, ``eval.rrd`` and, with a ``figure``, ``eval.png`` (``eval-TAG.*``)
    into it: :func:`evaluate_into` with these ``options`` (``episodes`` and ``seed`` needed).
    ``checkpoint``: which of the folder's checkpoints (the latest by default, or a milestone's).
    Returns the result."""
    config, agents, about = runs.described(folder, checkpoint)
    return evaluate_into(runs.eval_paths(folder, tag), config, agents, {**about, "tag": tag}, **options)


def evaluate_into(
    paths: dict[str, Path],
    config: TrainConfig,
    agents: dict[str, LearningAgent | ScriptedAgent],
    about: dict[str, Any],
    *,
    episodes: int,
    seed: int,
    num_envs: int = 64,
    record: bool = True,
    check: Callable[[], None] = lambda: None,
    predator_kind: str | None = None,
    perturbations: Perturbations | None = None,
    figure: Figure | None = None,
    csv: bool = False,
    tracks: bool = False,
) -> dict[str, Any]:
    """Evaluate ``agents``, trained by ``config``, by the paper's protocol and write the result
    (with ``about`` and the training config), its ``figure`` (if given) and a recording to ``paths``
    (``runs.eval_paths``) together: each is written under a temporary name and renamed when all
    are complete, so an interruption leaves the previous ones as they were. ``check()`` is
    called before every step and once more before the files are put in place: an exception it
    raises stops the evaluation with the previous files untouched. ``predator_kind`` names the
    predators in the result (default: the config's); ``perturbations`` change the world and the
    senses of every variant alike (:mod:`pursuit_bench.env.perturbations`); with ``csv``, the
    trained variant's trajectories go to ``paths["csv"]`` as well (``trajectories/trajectory_csv.py``);
    with ``tracks``, to the folder ``paths["tracks"]`` as movement datasets (``trajectories/movement_tracks.py``)."""
    partial = {kind: path.with_name(f".{path.name}.tmp") for kind, path in paths.items()}
    recorder: EpisodeSink | None = None
    try:
        sinks: list[EpisodeSink] = []
        if record:
            described = {"condition": config.condition, "evaluation": True, **config.to_dict()}
            sinks.append(Recorder(partial["rrd"], list(agents), described))
        if csv:
            sinks.append(TrajectoryCSV(partial["csv"], list(agents)))
        if tracks:
            sinks.append(MovementTracks(partial["tracks"], list(agents), config.condition))
        recorder = sinks[0] if len(sinks) == 1 else Sinks(*sinks) if sinks else None
        result = evaluate_agents(
            config.condition,
            agents,  # type: ignore[arg-type]
            episodes=episodes,
            seed=seed,
            num_envs=num_envs,
            recorder=recorder,
            check=check,
            perturbations=perturbations,
            **{**config.protocol, "predator_kind": predator_kind or config.predator},
        )
        result.update({**about, "training": config.to_dict()})
        if recorder is not None:
            recorder.close()
        if figure is not None:
            atomic_write_bytes(partial["png"], figure(result, paths["json"].parent.name))
        atomic_write_text(partial["json"], json.dumps(result, indent=2) + "\n")
        check()  # the last point at which the previous results stay as they were
        if partial["tracks"].exists():  # a folder: the old one moved aside, the new one in, the old removed
            old = paths["tracks"].with_name(f".{paths['tracks'].name}.old")
            shutil.rmtree(old, ignore_errors=True)
            if paths["tracks"].exists():
                os.replace(paths["tracks"], old)
            os.replace(partial["tracks"], paths["tracks"])
            shutil.rmtree(old, ignore_errors=True)
        for kind in ("rrd", "csv", "png", "json"):  # eval.json last: it says the set is complete
            if partial[kind].exists():
                os.replace(partial[kind], paths[kind])
        if not record:
            paths["rrd"].unlink(missing_ok=True)  # an older recording would not match
        if not csv:
            paths["csv"].unlink(missing_ok=True)  # nor older trajectories
        if not tracks:
            shutil.rmtree(paths["tracks"], ignore_errors=True)
        if figure is None:
            paths["png"].unlink(missing_ok=True)  # nor an older figure
    except BaseException:
        if recorder is not None:
            recorder.close()
        for kind, path in partial.items():
            if kind == "tracks":
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
        raise
    return result
