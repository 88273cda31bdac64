"""Which pursuit law the predators follow: evaluation episodes played, every predator's attacks
cut out, the laws of :mod:`pursuit_bench.laws.guidance` fitted to each and one chosen by its
criterion, summaries per predator kind and phase; what ``pursuit-bench law`` writes
(``law.json``, ``law.png``).

**Attacks.** Every predator of the env has modes (its action carries one: chase or stalk). A
*phase* is a run of steps in one mode, stalking for at most :data:`GAP` steps inside a chase
bridged; a *chase phase* is an attack, from its onset to its end (capture, the episode's end, or
the return to stalking), and the stalking phases are fitted separately. Scripted predators hold
one mode, so their one phase is the whole episode. Each segment carries up to ``max_delay``
samples before its onset (the history a delayed law reads); it is kept when its onset is
followed by at least :data:`MIN_STEPS` samples (0.6 s) and the predator moves; stalking
phases are cut into pieces of at most :data:`STALK_PIECE` samples.

Episodes are played as the paper evaluates (predators greedy, the prey ε = 0.1); the scripted
predators (always-chase, which is the hierarchical predator's lower layer alone in chase mode,
always-stalk and pure pursuit) play the same seeds against the same prey as references.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pursuit_bench import stats
from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.task import CHASE
from pursuit_bench.env.world import DT
from pursuit_bench.laws import guidance
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, PurePursuitPredator
from pursuit_bench.training.evaluate import Actor, run_episodes

#: Samples a segment must last after its onset (0.6 s: the trained predators' chases are short).
MIN_STEPS = 6
#: Stalking phases are cut into pieces of at most this many samples (3 s), each simulated from
#: its own initial conditions: stalking is not an attack, and one simulation over 15 s of it
#: would say more about chaos than about steering.
STALK_PIECE = 30
#: Distance the predator must move in it.
MIN_PATH = 0.05
#: Interruptions of a phase by the other mode, in steps, that do not end it.
GAP = 2
#: Delays tried, in samples (0.5 s): also the history kept before each onset.
MAX_DELAY = 5
PHASES = ("chase", "stalk")
#: Scripted predators fitted beside the trained ones, by the name law.json gives them.
REFERENCES = {"always_chase": AlwaysChase, "always_stalk": AlwaysStalk, "pure_pursuit": PurePursuitPredator}


@dataclass(frozen=True)
class Segment:
    """One phase of one predator in one episode."""

    pursuer: np.ndarray
    """(T, 2) the predator's positions, the history before the onset included."""
    target: np.ndarray
    """(T, 2) the prey's."""
    start: int
    """The onset's sample in these arrays (the history before it)."""
    phase: str
    """``"chase"`` or ``"stalk"``."""
    episode: int
    """The episode (in the order episodes ended)."""
    onset: int
    """The onset's step in its episode."""
    episode_pursuer: np.ndarray
    """(L, 2) the predator's positions over the whole episode (for the figure)."""
    episode_target: np.ndarray
    """(L, 2) the prey's."""


def phases(modes: np.ndarray, gap: int = GAP) -> list[tuple[str, int, int]]:
    """The phases of one episode's modes (steps): ``(phase, first, last)`` steps, runs of one
    mode, where stalking for at most ``gap`` steps between two chase runs is bridged (the attack
    goes on; a chase that short is no attack either way)."""
    chase = np.asarray(modes) == CHASE

    def runs(flags: np.ndarray) -> list[tuple[bool, int, int]]:
        edges = np.flatnonzero(np.diff(flags.astype(np.int8))) + 1
        bounds = np.concatenate([[0], edges, [len(flags)]])
        return [(bool(flags[a]), int(a), int(b) - 1) for a, b in itertools.pairwise(bounds)]

    smoothed = chase.copy()
    for k, (flag, first, last) in enumerate(runs(chase)):
        if not flag and 0 < k < len(runs(chase)) - 1 and last - first + 1 <= gap:
            smoothed[first : last + 1] = True
    return [("chase" if flag else "stalk", first, last) for flag, first, last in runs(smoothed)]


def segments(track: np.ndarray, modes: np.ndarray, episode: int, predator: int) -> list[Segment]:
    """The kept segments of one episode: ``track`` (T, agents, 2) positions at each step,
    the prey last, ``modes`` (T,) the predator's mode at each step."""
    found = []
    pieces: list[tuple[str, int, int]] = []
    for phase, first, last in phases(modes):
        step = STALK_PIECE if phase == "stalk" else len(modes)
        pieces.extend((phase, a, min(a + step - 1, last)) for a in range(first, last + 1, step))
    for phase, first, last in pieces:
        lo = max(first - MAX_DELAY, 0)
        stop = min(last + 1, len(track) - 1)  # the sample the phase's last step reaches
        pursuer, target = track[lo : stop + 1, predator], track[lo : stop + 1, -1]
        path = np.linalg.norm(np.diff(pursuer[first - lo :], axis=0), axis=1).sum()
        if stop - first >= MIN_STEPS and path >= MIN_PATH:
            found.append(Segment(pursuer, target, first - lo, phase, episode, first, track[:, predator], track[:, -1]))
    return found


def attacks(
    condition: str,
    agents: dict[str, Actor],
    episodes: int,
    seed: int,
    prey_epsilon: float | None = 0.1,
    task_options: Mapping[str, Any] | None = None,
) -> dict[str, list[Segment]]:
    """Play ``episodes`` episodes (predators greedy, the prey ε-greedy as in the paper's
    evaluation; ``task_options``: obstacles) and return every predator's segments."""
    names = list(agents)
    predators, prey = names[:-1], names[-1]
    tracks: dict[int, list[np.ndarray]] = {}
    modes: dict[int, list[np.ndarray]] = {}
    found: dict[str, list[Segment]] = {p: [] for p in predators}
    ended = [0]

    def on_step(obs: np.ndarray, actions: np.ndarray, done: np.ndarray, counted: np.ndarray) -> None:
        for arena in np.flatnonzero(counted).tolist():
            tracks.setdefault(arena, []).append(obs[arena, :, 0:2].copy())  # each agent's own position
            modes.setdefault(arena, []).append(actions[arena, :-1, 0].copy())
            if done[arena]:
                track, mode = np.array(tracks.pop(arena)), np.array(modes.pop(arena))
                for i, name in enumerate(predators):
                    found[name].extend(segments(track, mode[:, i], ended[0], i))
                ended[0] += 1

    epsilons = {prey: prey_epsilon} if prey_epsilon is not None else {}
    run_episodes(
        condition,
        agents,
        episodes,
        seed=seed,
        num_envs=min(16, episodes),
        epsilons=epsilons,
        on_step=on_step,
        task_options=task_options,
    )
    return found


def censored_median(values: list[float], sides: list[str | None]) -> dict[str, Any]:
    """The median of fitted gains that counts the fits censored at a bound (``sides``: ``None``
    for an interior fit, ``"lower"`` or ``"upper"``): a fit at the upper bound of 15 says only
    "N ≥ 15", but it ranks above every interior fit, and the median needs only ranks. With fewer
    than half the fits at each bound, the middle of the sorted fits is interior, so the median is
    the ordinary median of every fit (the censored ones at the bound where they sit), which is
    then also the Kaplan–Meier median for censoring at one fixed bound. With half or more at a
    bound it cannot be estimated: only the bound is known (``"side"``: ``"upper"``, written
    ``">15"``, or ``"lower"``). Returns ``{"median", "side", "fits", "lower", "upper"}`` (shares at each
    bound; median ``None`` with no fit or none estimable)."""
    if len(values) != len(sides):
        raise ValueError(f"{len(values)} values and {len(sides)} sides: expected one side per value")
    count = len(values)
    lower = sum(s == "lower" for s in sides) / count if count else 0.0
    upper = sum(s == "upper" for s in sides) / count if count else 0.0
    side = "upper" if count and upper >= 0.5 else "lower" if count and lower >= 0.5 else None
    median = float(np.median(values)) if count and side is None else None
    return {"median": median, "side": side, "fits": count, "lower": lower, "upper": upper}


def _gain_summary(values: list[float], sides: list[str | None], seed: int) -> dict[str, Any]:
    """Over attacks: the median of the interior fits with its 95 % interval
    (:func:`stats.median_interval`; biased towards the middle of the range when fits sit
    at a bound), the fraction at each bound, and the median that counts the censored fits
    (:func:`censored_median`)."""
    interior = np.array([v for v, s in zip(values, sides, strict=True) if s is None])
    count = max(len(values), 1)
    censored = censored_median(values, sides)
    summary: dict[str, Any] = {
        "median": float(np.median(interior)) if len(interior) else None,
        "ci": stats.median_interval(interior, seed),
        "interior": len(interior),
        "lower": sum(s == "lower" for s in sides) / count,
        "upper": sum(s == "upper" for s in sides) / count,
        "censored_median": censored["median"],
        "censored_side": censored["side"],
    }
    return summary


def select(found: list[Segment]) -> list[guidance.Selection]:
    """Every law fitted to each segment and one chosen (:func:`guidance.select`)."""
    return [guidance.select(s.pursuer, s.target, DT, MAX_DELAY, s.start) for s in found]


def fit_segments(
    found: list[Segment], seed: int = 0, selections: list[guidance.Selection] | None = None
) -> dict[str, Any]:
    """Per phase, from each segment's :func:`select` (``selections``, in ``found``'s order, or
    made here): each attack's chosen law, every law's gains (with the bound they sit at, if
    any), delay, error, error relative to ``"none"`` and criterion; over attacks, how often
    each law is chosen and the gains' summaries (:func:`_gain_summary`)."""
    every = select(found) if selections is None else selections
    result: dict[str, Any] = {}
    for phase in PHASES:
        here = [k for k, s in enumerate(found) if s.phase == phase]
        chosen_here = [found[k] for k in here]
        selections = [every[k] for k in here]
        entry: dict[str, Any] = {
            "attacks": len(selections),
            "chosen": [sel.chosen.law for sel in selections],
            "episodes": [s.episode for s in chosen_here],
            "onsets": [s.onset for s in chosen_here],
            "samples": [sel.chosen.samples for sel in selections],
            "laws": {},
        }
        entry["share"] = {
            law: entry["chosen"].count(law) / len(selections) if selections else 0.0 for law in guidance.LAWS
        }
        for law in guidance.LAWS:
            fits = [sel.fits[law] for sel in selections]
            law_entry: dict[str, Any] = {
                "gains": {g: [f.gains[g] for f in fits] for g in guidance.LAW_GAINS[law]},
                "censored": [f.censored for f in fits],
                "delay": [f.delay for f in fits],
                "error": [f.error for f in fits],
                "relative_error": [sel.relative_errors[law] for sel in selections],
                "criterion": [f.criterion for f in fits],
            }
            law_entry["summary"] = {
                g: _gain_summary(law_entry["gains"][g], [f.censored.get(g) for f in fits], seed)
                for g in guidance.LAW_GAINS[law]
            }
            if fits:
                law_entry["summary"]["relative_error"] = float(np.median(law_entry["relative_error"]))
                law_entry["summary"]["delay"] = float(np.median(law_entry["delay"]))
            entry["laws"][law] = law_entry
        entry["winner"] = max(guidance.LAWS, key=lambda law: entry["share"][law]) if selections else None
        result[phase] = entry
    return result


def examples(found: list[Segment], selections: list[guidance.Selection], count: int = 3) -> list[dict[str, Any]]:
    """A few attacks (chase phases first) with each law's simulated trajectory (from their
    ``selections``, in ``found``'s order), for the figure."""
    ordered = sorted(range(len(found)), key=lambda k: (found[k].phase != "chase", found[k].episode))[:count]
    shown = []
    for s, selection in ((found[k], selections[k]) for k in ordered):
        shown.append(
            {
                "phase": s.phase,
                "episode": s.episode,
                "onset": s.onset,
                "start": s.start,
                "episode_pursuer": s.episode_pursuer.tolist(),
                "episode_target": s.episode_target.tolist(),
                "pursuer": s.pursuer.tolist(),
                "target": s.target.tolist(),
                "simulated": {law: f.simulated.tolist() for law, f in selection.fits.items()},
                "chosen": selection.chosen.law,
            }
        )
    return shown


def analyse(
    condition: str,
    agents: dict[str, Actor],
    kind: str,
    episodes: int,
    seed: int,
    references: bool = True,
    task_options: Mapping[str, Any] | None = None,
    avoidance: bool = False,
) -> dict[str, Any]:
    """law.json's content for one set of agents: per predator of ``kind`` (and, with
    ``references``, per scripted reference predator in the predators' places, their lower
    layer avoiding obstacles as ``avoidance`` says) the fits per phase; ``task_options``:
    obstacles."""
    predators = list(CONDITIONS[condition].agent_names[:-1])
    result: dict[str, Any] = {
        "condition": condition,
        "episodes": episodes,
        "seed": seed,
        "dt": DT,
        "criterion": "BIC",
        "parameters": guidance.PARAMETERS,
        "gain_bounds": guidance.GAIN_BOUNDS,
        "max_delay": MAX_DELAY * DT,
        "kinds": {},
    }
    found = attacks(condition, agents, episodes, seed, task_options=task_options)
    selections = {name: select(found[name]) for name in predators}
    result["kinds"][kind] = {name: fit_segments(found[name], seed, selections[name]) for name in predators}
    result["examples"] = {kind: examples(found[predators[0]], selections[predators[0]])}
    if references:
        for name, policy in REFERENCES.items():
            scripted = {**agents, **{p: ScriptedAgent(p, policy(avoidance=avoidance)) for p in predators}}
            found = attacks(condition, scripted, episodes, seed, task_options=task_options)
            result["kinds"][name] = {p: fit_segments(found[p], seed) for p in predators}
    return result


def over_seeds(per_run: list[dict[str, Any]]) -> dict[str, Any]:
    """A sweep's law.json: per condition, predator kind and phase, over seeds (runs: the unit of
    replication), the mean share of attacks each law is chosen for with its 95 % t-interval;
    per gain of ``pp``, ``pn`` and ``mixed`` the mean of each run's median *interior* fit with
    its t-interval (biased towards the range's middle where fits sit at a bound), and the
    median that counts the censored fits (:func:`censored_median`) over every fit of the runs
    pooled (``"censored"``) and per run (``"censored_per_run"``)."""
    grouped: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for result in per_run:
        for kind, predators in result["kinds"].items():
            # one value per run: the predators of a run pooled
            grouped.setdefault((result["condition"], kind), []).append(predators)
    summary: dict[str, Any] = {}
    for (condition, kind), runs in sorted(grouped.items()):
        entry: dict[str, Any] = {"runs": len(runs)}
        for phase in PHASES:
            phase_entry: dict[str, Any] = {"share": {}, "gains": {}}
            chosen = [[c for fits in run.values() for c in fits[phase]["chosen"]] for run in runs]
            phase_entry["attacks"] = sum(len(c) for c in chosen)
            usable = [c for c in chosen if c]
            for law in guidance.LAWS:
                shares = np.array([c.count(law) / len(c) for c in usable])
                phase_entry["share"][law] = {
                    "mean": float(shares.mean()) if len(shares) else None,
                    "ci": stats.t_interval(shares),
                }
            means = {law: v["mean"] or 0.0 for law, v in phase_entry["share"].items()}
            phase_entry["winner"] = max(means, key=lambda law: means[law]) if usable else None
            for law in ("pp", "pn", "mixed"):
                for gain in guidance.LAW_GAINS[law]:
                    medians, every, every_side, run_medians = [], [], [], []
                    for run in runs:
                        fitted = [
                            (v, c.get(gain))
                            for fits in run.values()
                            for v, c in zip(
                                fits[phase]["laws"][law]["gains"][gain],
                                fits[phase]["laws"][law]["censored"],
                                strict=True,
                            )
                        ]
                        values = [v for v, side in fitted if side is None]
                        if values:
                            medians.append(float(np.median(values)))
                        every += [v for v, _ in fitted]
                        every_side += [side for _, side in fitted]
                        if fitted:
                            run_medians.append(censored_median([v for v, _ in fitted], [side for _, side in fitted]))
                    phase_entry["gains"][f"{law}.{gain}"] = {
                        "mean": float(np.mean(medians)) if medians else None,
                        "ci": stats.t_interval(np.array(medians)),
                        "runs": len(medians),
                        "censored": censored_median(every, every_side),
                        "censored_per_run": run_medians,
                    }
            entry[phase] = phase_entry
        summary.setdefault(condition, {})[kind] = entry
    return summary
