"""``pursuit-bench score``: one agent, filling every slot of its role, played against each member
of a shipped population of held-out opponents (:mod:`pursuit_bench.benchmark.populations`), on
the same episodes for every member, beside the reference agents on those same episodes; a
normalized score per condition and an aggregate over conditions (docs/leaderboard.md).

The statistics (docs/leaderboard.md says why):

- per condition, the agent's mean return over members × episodes with a 95 % interval for a
  **crossed design with both members and episodes random** (:func:`crossed_interval`): the
  two-way ANOVA's variance of the grand mean, ``(MS_members + MS_episodes − MS_residual) / (M E)``,
  and Satterthwaite's degrees of freedom;
- a normalized score, ``(agent − random) / (reference − random)``: 0 is the uniformly random
  agent, 1 the hierarchical reference (the condition's shipped agents) on the same episodes;
- the aggregate: the interquartile mean of the normalized scores over conditions, as rliable
  defines it (Agarwal et al., NeurIPS 2021: ``scipy.stats.trim_mean(scores, 0.25)`` over runs ×
  tasks; here one scored agent, so over conditions), with a percentile interval from a
  stratified bootstrap: within each condition the members and the episodes resampled (the
  sources of this score's randomness, as a run is rliable's), the normalized score recomputed.
"""

from __future__ import annotations

import inspect
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from pursuit_bench import pretrained
from pursuit_bench.agents import external, sb3_model, team_file
from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent
from pursuit_bench.benchmark import populations
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.task import obs_size
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey, PurePursuitPredator
from pursuit_bench.training import runs
from pursuit_bench.training.evaluate import PROTOCOL, play_variants

CONFIDENCE = 0.95
#: The fewest degrees of freedom :func:`crossed_interval` gives its t quantile (docs/leaderboard.md says why).
DF_FLOOR = 1.0
RESAMPLES = 2000
#: The ε the paper's evaluation protocol gives a learned prey (section 3.4); predators act greedily.
PREY_EPSILON = 0.1
SCORE_FORMAT = "pursuit-bench-score-1"
#: The leaderboard's settings (docs/leaderboard.md, "How to submit a result"): episodes per member
#: (a row with fewer, or fewer conditions than all, is partial, †) and the seed every row shares.
LEADERBOARD_EPISODES = 20
LEADERBOARD_SEED = 12345
#: The leaderboard's rows as ``score`` places a result among them (:func:`standing`): written with
#: docs/leaderboard.md by docs/gen/leaderboard.py, shipped in the package.
LEADERBOARD = Path(__file__).with_name("leaderboard.json")


class UniformRandom:
    """Uniformly random actions: a predator's (mode, direction), the prey's direction; seeded."""

    def __init__(self, predator: bool, seed: int) -> None:
        self.predator, self.rng = predator, np.random.default_rng(seed)

    def act_batch(self, observations: np.ndarray) -> np.ndarray:
        n = len(observations)
        if self.predator:
            return np.stack([self.rng.integers(0, 2, n), self.rng.integers(0, 12, n)], axis=-1)
        return self.rng.integers(0, 12, n)

    def act(self, observation: np.ndarray) -> Any:
        return self.act_batch(np.asarray(observation)[None])[0]


#: The reference agents by name: (role, what they are, policy(seed)).
REFERENCES: dict[str, tuple[str, str, Callable[[int], Any]]] = {
    "random": ("both", "uniformly random actions", lambda seed: None),
    "always-chase": ("predator", "chase mode always, parallel navigation", lambda seed: AlwaysChase()),
    "always-stalk": ("predator", "stalk mode always, parallel navigation", lambda seed: AlwaysStalk()),
    "pure-pursuit": ("predator", "chase mode always, straight at the prey", lambda seed: PurePursuitPredator()),
    "FleeingPrey": ("prey", "flees the nearest predator, keeps off the walls", lambda seed: FleeingPrey()),
}
#: The name of the hierarchical reference (the condition's shipped agents).
SHIPPED = "pretrained"
#: What score.json reports beside the agent, per role (the reference a score is normalized by last).
REFERENCE_ROWS = {
    "predator": ("random", "always-chase", "always-stalk", "pure-pursuit", SHIPPED),
    "prey": ("random", "FleeingPrey", SHIPPED),
}


def slots(condition: str, role: str) -> list[str]:
    """The agent names of ``role`` in ``condition``."""
    names = list(CONDITIONS[condition].agent_names)
    return names[:-1] if role == "predator" else names[-1:]


@dataclass
class Contestant:
    """An agent that fills every slot of a role: ``make(condition, seed)`` gives fresh agents by
    slot (so that every play starts from the same state)."""

    label: str
    """As given on the command line."""
    description: str
    role: str
    make: Callable[[str, int], dict[str, Any]]
    can_play: Callable[[str], bool] = lambda condition: True
    digests: Callable[[str], set[str]] = lambda condition: set()
    """Fingerprints of every learned agent of the run it comes from (both roles): a population
    member with one of these is the scored run's own and is excluded."""
    runs: Callable[[str], set[tuple[str, int]]] = lambda condition: set()
    """(condition, seed) of the runs it comes from: a member trained in the same is excluded."""
    copies: bool = True
    """One agent copied into every slot (a module, a reference), not a trained team."""
    trained_in: str | None = None
    """The condition its agents were trained in (a run, one condition's shipped agents): their
    observations have that condition's size, so it plays only conditions with as many agents."""
    observes: int | None = None
    """The observation size it takes, where that is all that is known of where it was trained
    (a Stable-Baselines3 model)."""


def _agent_weights(agents: dict[str, Any]) -> set[str]:
    return {
        populations.weights_digest(agent.learner.member_weights(agent.member))
        for agent in agents.values()
        if isinstance(agent, LearningAgent)
    }


def _renamed(agents: dict[str, Any], names: list[str]) -> dict[str, Any]:
    for name in names:
        agents[name].name = name
    return {name: agents[name] for name in names}


def reference(name: str, role: str) -> Contestant:
    """A reference agent by name (:data:`REFERENCES`, or :data:`SHIPPED`: the hierarchical reference)."""
    if name == SHIPPED:
        return _shipped_each(role)
    plays, description, policy = REFERENCES[name]
    if plays not in ("both", role):
        raise ValueError(f"{name} is a {plays}: it cannot play --role {role}")

    def make(condition: str, seed: int) -> dict[str, Any]:
        names = slots(condition, role)
        if name == "random":
            return {n: ScriptedAgent(n, UniformRandom(role == "predator", seed + i)) for i, n in enumerate(names)}
        return {n: ScriptedAgent(n, policy(seed)) for n in names}

    return Contestant(name, f"{name} ({description})", role, make)


def _shipped_each(role: str) -> Contestant:
    """In each condition, that condition's shipped agents (the hierarchical reference)."""

    def make(condition: str, seed: int) -> dict[str, Any]:
        return _renamed(pretrained.load(condition), slots(condition, role))

    def digests(condition: str) -> set[str]:
        return _agent_weights(pretrained.load(condition))

    return Contestant(
        SHIPPED,
        "the shipped agents of each condition (hierarchical predators and the prey trained with them)",
        role,
        make,
        can_play=lambda condition: condition in pretrained.available(),
        digests=digests,
        runs=lambda condition: {(condition, int(next(iter(pretrained.info(condition).values()))["seed"]))},
        copies=False,
    )


def _team_size_matches(trained_in: str) -> Callable[[str], bool]:
    n = len(CONDITIONS[trained_in].agent_names)
    return lambda condition: len(CONDITIONS[condition].agent_names) == n


def resolve(spec: str, role: str) -> Contestant:
    """The contestant ``spec`` names: a reference name, ``pretrained`` / ``pretrained:CONDITION``,
    a run folder or ``MODULE:FACTORY``; ValueError in one line if it cannot be played."""
    by_lower = {k.lower(): k for k in REFERENCES}
    if spec.lower() in by_lower:
        return reference(by_lower[spec.lower()], role)
    if spec == SHIPPED:
        return _shipped_each(role)
    if spec.startswith(f"{SHIPPED}:"):
        source = spec.removeprefix(f"{SHIPPED}:")
        if source not in pretrained.available():
            raise ValueError(
                f"{spec}: no shipped agents for {source!r}; expected one of {', '.join(pretrained.available())}"
            )
        seed = int(next(iter(pretrained.info(source).values()))["seed"])
        return Contestant(
            spec,
            f"the shipped {'predators' if role == 'predator' else 'prey'} of {source}",
            role,
            lambda condition, s: _renamed(pretrained.load(source), slots(condition, role)),
            can_play=_team_size_matches(source),
            digests=lambda condition: _agent_weights(pretrained.load(source)),
            runs=lambda condition: {(source, seed)},
            copies=False,
            trained_in=source,
        )
    if sb3_model.is_model_path(spec):
        return _sb3(spec, role)
    if team_file.is_team_path(spec):
        return _team(spec, role)
    folder = Path(spec)
    if (folder / "config.json").is_file():
        return _run_folder(folder, role)
    if ":" in spec and not folder.exists():
        return _module(spec, role)
    raise ValueError(
        f"{spec}: expected MODULE:FACTORY, a run folder (with config.json), pretrained[:CONDITION] or a reference "
        f"name ({', '.join(REFERENCES)})"
    )


def _run_folder(folder: Path, role: str) -> Contestant:
    try:
        config, agents, about = runs.described(folder)
    except (ValueError, OSError) as error:
        raise ValueError(f"{folder}: cannot load its agents ({error})") from None
    if config.obstacles:
        raise ValueError(f"{folder}: trained with obstacles; the populations play the paper's task, without")
    if not all(isinstance(agents[n], LearningAgent) for n in slots(config.condition, role)):
        raise ValueError(f"{folder}: its {role} is scripted, not learned: score the scripted policy by name instead")
    fingerprint = _agent_weights(agents)

    def make(condition: str, seed: int) -> dict[str, Any]:
        return _renamed(runs.described(folder)[1], slots(condition, role))

    return Contestant(
        str(folder),
        f"the {config.predator} run {folder.name} ({config.condition}, seed {config.seed}, "
        f"{about['trained_episodes']} episodes)",
        role,
        make,
        can_play=_team_size_matches(config.condition),
        digests=lambda condition: fingerprint,
        runs=lambda condition: {(config.condition, config.seed)},
        copies=False,
        trained_in=config.condition,
    )


def _module(spec: str, role: str) -> Contestant:
    factory: Callable[..., Any] = external.load_factory(spec)
    takes_condition = "condition" in inspect.signature(factory).parameters

    def make(condition: str, seed: int) -> dict[str, Any]:
        made = {}
        for name in slots(condition, role):
            try:
                agent = factory(condition=condition) if takes_condition else factory()
            except Exception as error:
                raise ValueError(f"{spec}: the factory raised {type(error).__name__}: {error}") from None
            made[name] = external.ExternalAgent(name, agent, spec, predator=role == "predator")
        return made

    return Contestant(spec, f"{spec} (an agent module)", role, make)


def _sb3(spec: str, role: str) -> Contestant:
    """A Stable-Baselines3 model (``PATH.zip``) in every slot of ``role``: one policy, loaded once,
    playing the conditions whose observations have the size it was trained on."""
    policy = sb3_model.SB3Policy(spec)
    policy.check_role(predator=role == "predator")

    def make(condition: str, seed: int) -> dict[str, Any]:
        return {
            name: external.ExternalAgent(name, policy, spec, predator=role == "predator")
            for name in slots(condition, role)
        }

    def can_play(condition: str) -> bool:
        return obs_size(len(CONDITIONS[condition].agent_names)) == policy.observes

    return Contestant(
        spec, f"{spec} (a Stable-Baselines3 model)", role, make, can_play=can_play, observes=policy.observes
    )


def _team(spec: str, role: str) -> Contestant:
    """A team file (``agents/team_file.py``: a MARL library's trained agents): its agent of each
    slot, in the conditions with as many agents as the one it was trained in."""
    team = team_file.Team(spec)
    if team.role != role:
        raise ValueError(f"{spec}: a {team.role} team; it cannot play the {role}")
    if team.condition not in CONDITIONS or len(slots(team.condition, role)) != len(team.agents):
        raise ValueError(
            f"{spec}: trained in {team.condition!r} with {len(team.agents)} {role}(s); not a condition here"
        )

    def make(condition: str, seed: int) -> dict[str, Any]:
        return {
            name: external.ExternalAgent(name, team.member(i), spec, predator=role == "predator")
            for i, name in enumerate(slots(condition, role))
        }

    return Contestant(
        spec,
        team.describe(),
        role,
        make,
        can_play=_team_size_matches(team.condition),
        copies=False,
        trained_in=team.condition,
    )


def _observes(condition: str, role: str) -> str:
    """What an agent of ``role`` observes in ``condition``, in words: how many, of what size."""
    n = len(CONDITIONS[condition].agent_names)
    predators = f"{n - 1} predator{'s' if n > 2 else ''}"
    if role == "predator":
        return f"{predators} observing {obs_size(n)} numbers{' each' if n > 2 else ''}"
    return f"a prey observing {obs_size(n)} numbers against {predators}"


def cannot_play(contestant: Contestant, conditions: list[str] | tuple[str, ...]) -> str:
    """Why ``contestant`` cannot play those of ``conditions`` it cannot, in one line: its agents'
    size as trained, and what each condition expects."""
    cannot = [c for c in conditions if not contestant.can_play(c)]
    text = f"{contestant.label} cannot play {', '.join(cannot)}"
    if contestant.trained_in is None and contestant.observes is None:
        return text
    expected: dict[str, list[str]] = {}
    for condition in cannot:
        expected.setdefault(_observes(condition, contestant.role), []).append(condition)
    if contestant.trained_in is None:
        return f"{text}: it observes {contestant.observes} numbers; expected " + "; ".join(
            f"{what} in {', '.join(where)}" for what, where in expected.items()
        )
    return (
        f"{text}: its {'prey was' if contestant.role == 'prey' else 'predators were'} trained in "
        f"{contestant.trained_in}, as "
        f"{_observes(contestant.trained_in, contestant.role)}; expected "
        + "; ".join(f"{what} in {', '.join(where)}" for what, where in expected.items())
    )


def check_plays(contestant: Contestant, condition: str) -> None:
    """Refuse at once an agent that cannot act in ``condition``'s role: it is asked for actions for
    a few observations of the right size and must answer them in the role's action space."""
    agents = contestant.make(condition, 0)
    n_obs = obs_size(len(CONDITIONS[condition].agent_names))
    for agent in agents.values():
        if isinstance(agent, external.ExternalAgent):
            try:
                agent.act_batch(np.zeros((2, n_obs), dtype=np.float32))
            except ValueError as error:
                what = str(error).removeprefix(f"agent {agent.name} ({agent.spec}): ")
                raise ValueError(
                    f"agent {agent.name} ({agent.spec}) cannot play --role {contestant.role} in {condition}: "
                    f"given 2 observations of {n_obs} numbers (the {contestant.role}'s there), {what}"
                ) from None


def check_members(population: populations.Population) -> None:
    """Refuse before anything is played a population whose members cannot play its condition
    (weights of the other role, or of another team size): every member's agents are built."""
    for member in population.members:
        member.agents(population.condition, slots(population.condition, population.role))


# ------------------------------------------------------------------ statistics


def crossed_interval(y: np.ndarray, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """The mean of ``y`` (members × episodes) with a ``confidence`` interval treating both the
    members and the episodes as random draws (a crossed two-way random-effects design): the
    variance of the grand mean is ``σ²_m / M + σ²_e / E + σ²_r / (M E)``, estimated without bias by
    ``(MS_m + MS_e − MS_r) / (M E)`` from the two-way ANOVA's mean squares, with Satterthwaite's
    degrees of freedom, at least :data:`DF_FLOOR`. One member: the t-interval over episodes. Its
    coverage, measured by :func:`coverage` (docs/leaderboard.md), is 93–96 % from four members up
    and falls to 87–95 % with two."""
    y = np.asarray(y, dtype=float)
    m, e = y.shape
    grand = float(y.mean())
    if e < 2:
        return {"mean": grand, "ci": None, "df": None, "se": None}
    if m == 1:
        se = float(y[0].std(ddof=1) / np.sqrt(e))
        half = float(stats.t.ppf(0.5 + confidence / 2, e - 1)) * se
        return {"mean": grand, "ci": [grand - half, grand + half], "df": float(e - 1), "se": se}
    rows, cols = y.mean(axis=1), y.mean(axis=0)
    ms_m = e * float(((rows - grand) ** 2).sum()) / (m - 1)
    ms_e = m * float(((cols - grand) ** 2).sum()) / (e - 1)
    residual = y - rows[:, None] - cols[None, :] + grand
    df_r = (m - 1) * (e - 1)
    ms_r = float((residual**2).sum()) / df_r
    # the variance of the grand mean, (MS_m + MS_e − MS_r) / (M E): unbiased; where it comes out not
    # positive, the residual's term is left out (an overestimate, never a zero-width interval)
    terms = [(ms_m, m - 1), (ms_e, e - 1), (-ms_r, df_r)]
    if ms_m + ms_e - ms_r <= 0:
        terms = terms[:2]
    if ms_m + ms_e <= 0 < ms_r:  # every member's and every episode's mean the same, the rest not
        terms = [(ms_r, df_r)]  # the residual's share alone, σ²_r / (M E), which the variance is at least
    total = sum(t for t, _ in terms)
    if total <= 0:  # every return the same
        return {"mean": grand, "ci": [grand, grand], "df": None, "se": 0.0}
    variance = total / (m * e)
    # Satterthwaite's df: never below the fewest of its terms' own when all are added, but the
    # residual's subtracted term can take it towards 0, where the t quantile grows without bound
    df = max(total**2 / sum(t**2 / d for t, d in terms), DF_FLOOR)
    se = float(np.sqrt(variance))
    half = float(stats.t.ppf(0.5 + confidence / 2, df)) * se
    return {"mean": grand, "ci": [grand - half, grand + half], "df": float(df), "se": se}


def coverage(
    draw: Callable[[np.random.Generator, int, int], np.ndarray],
    truth: float,
    members: int,
    episodes: int,
    draws: int,
    seed: int = 0,
) -> float:
    """The fraction of ``draws`` simulated (members × episodes) tables, ``draw(rng, members,
    episodes)``, whose :func:`crossed_interval` holds ``truth``."""
    rng = np.random.default_rng(seed)
    held = 0
    for _ in range(draws):
        ci = crossed_interval(draw(rng, members, episodes))["ci"]
        held += ci is not None and ci[0] <= truth <= ci[1]
    return held / draws


def iqm(scores: np.ndarray) -> float:
    """The interquartile mean (rliable's ``aggregate_iqm``: the 25 % trimmed mean of all scores)."""
    return float(stats.trim_mean(np.asarray(scores, dtype=float), 0.25, axis=None))


def normalized(agent: float, random: float, reference: float) -> float | None:
    """``(agent − random) / (reference − random)``; None where the reference does no better or
    worse than random (no scale)."""
    return None if reference == random else (agent - random) / (reference - random)


def aggregate(
    cells: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]], seed: int, resamples: int = RESAMPLES
) -> dict[str, Any]:
    """The IQM of the normalized scores over conditions and its stratified-bootstrap percentile
    interval. ``cells``: per condition the (members × episodes) returns of the agent, the random
    agent and the reference on the same episodes; each resample draws members and episodes with
    replacement within each condition, the same draws for the three. Conditions where the
    reference does exactly as well as random have no normalized score and are left out (named
    in ``undefined``), as is a condition from a resample where that happens."""
    rng = np.random.default_rng(seed)
    values = {c: normalized(float(a.mean()), float(r.mean()), float(h.mean())) for c, (a, r, h) in cells.items()}
    used = [c for c, v in values.items() if v is not None]
    undefined = [c for c in cells if c not in used]
    if not used:
        return {"iqm": None, "ci": None, "conditions": used, "undefined": undefined, "resamples": resamples}
    draws = np.zeros((resamples, len(used)))
    for j, condition in enumerate(used):
        a, r, h = cells[condition]
        m, e = a.shape
        rows = rng.integers(0, m, (resamples, m))
        cols = rng.integers(0, e, (resamples, e))
        for k in range(resamples):
            pick = np.ix_(rows[k], cols[k])
            ra, rr, rh = a[pick].mean(), r[pick].mean(), h[pick].mean()
            draws[k, j] = (ra - rr) / (rh - rr) if rh != rr else np.nan
    per_draw = np.array([iqm(d[np.isfinite(d)]) if np.isfinite(d).any() else np.nan for d in draws])
    low, high = np.nanquantile(per_draw, [(1 - CONFIDENCE) / 2, (1 + CONFIDENCE) / 2])
    return {
        "iqm": iqm(np.array([values[c] for c in used], dtype=float)),
        "ci": [float(low), float(high)],
        "conditions": used,
        "undefined": undefined,
        "resamples": resamples,
    }


# ------------------------------------------------------------------ playing


def _epsilons(agents: dict[str, Any]) -> dict[str, float]:
    """The protocol's ε: a learned prey (ours) explores with ε = 0.1, everyone else acts greedily."""
    return {n: PREY_EPSILON for n, a in agents.items() if isinstance(a, LearningAgent) and a.kind == "prey"}


def play(
    condition: str,
    pairs: list[tuple[Contestant, populations.Member]],
    episodes: int,
    seed: int,
    num_envs: int,
) -> list[np.ndarray]:
    """Each contestant's returns (episodes × its slots) against its member, on the episodes
    ``seed`` fixes: every pair in one batch of arenas (the same returns as each played alone)."""
    variants, slots_of = [], []
    # learned agents act greedily or on the protocol's own draws (no state): made once and shared,
    # so a network's rows are one forward pass; scripted ones (some draw from generators of their
    # own) are made afresh for every pair, as if it were played alone
    made: dict[int, dict[str, Any]] = {}
    met: dict[str, dict[str, Any]] = {}
    for contestant, member in pairs:
        role = contestant.role
        other = "prey" if role == "predator" else "predator"
        mine = made.get(id(contestant)) or contestant.make(condition, seed)
        theirs = met.get(member.name) or member.agents(condition, slots(condition, other))
        if all(isinstance(a, LearningAgent) for a in mine.values()):
            made[id(contestant)] = mine
        if all(isinstance(a, LearningAgent) for a in theirs.values()):
            met[member.name] = theirs
        agents = {**theirs, **mine}
        agents = {name: agents[name] for name in CONDITIONS[condition].agent_names}
        variants.append((agents, _epsilons(agents)))
        slots_of.append([list(agents).index(name) for name in slots(condition, role)])
    # the evaluation protocol's own player: every episode played to its end, the learned opponents'
    # exploration drawn by (seed, episode, agent), so every contestant meets the same opponent noise
    played = play_variants(condition, variants, episodes, seed=seed, num_envs=num_envs, parts=list(range(len(pairs))))
    return [np.asarray(p.returns[:, index], dtype=float) for p, index in zip(played, slots_of, strict=True)]


def excluded_members(contestant: Contestant, population: populations.Population) -> dict[str, str]:
    """The members that come from the scored agent's own run, and why."""
    mine = contestant.digests(population.condition)
    out = {}
    for member in population.members:
        if not member.learned:
            continue
        if member.digests() & mine:
            out[member.name] = "holds weights of the scored run"
        else:
            trained_in = {pretrained.read(p)[1].get("condition") for p in member.files.values()}
            if any((c, member.seed) in contestant.runs(population.condition) for c in trained_in):
                out[member.name] = f"trained in the scored run's condition with its seed ({member.seed})"
    return out


def score(
    contestant: Contestant,
    conditions: list[str],
    *,
    episodes: int,
    seed: int,
    population: str | None = None,
    num_envs: int = 64,
    on_episodes: Callable[[int], None] = lambda n: None,
    references: dict[str, Contestant] | None = None,
) -> dict[str, Any]:
    """Score ``contestant`` in ``conditions`` against the population (``population``, or the
    role's default); returns what score.json holds. ``on_episodes(n)`` hears every n episodes
    finished. ``references``: the reference contestants (by default :data:`REFERENCE_ROWS`)."""
    role = contestant.role
    name = population or populations.default(role)
    refs = references or {r: reference(r, role) for r in REFERENCE_ROWS[role]}
    per_condition = {}
    cells = {}
    for condition in conditions:
        pop = populations.load(name, condition)
        if pop.role == role:
            raise ValueError(f"population {name} holds {pop.role}s: a {role} is scored against the other role")
        excluded = excluded_members(contestant, pop)
        pop = pop.without(set(excluded))
        if not pop.members:
            raise ValueError(f"{condition}: every member of population {name} comes from the scored run")
        # every contestant against every member, in one batch (the agent is a reference: the same plays)
        everyone = {"agent": contestant, **refs}
        playing = {key: who for key, who in everyone.items() if key == "agent" or key != contestant.label}
        pairs = [(who, m) for who in playing.values() for m in pop.members]
        played = iter(play(condition, pairs, episodes, seed, min(num_envs, episodes)))
        by_key = {key: np.stack([next(played) for _ in pop.members]) for key in playing}
        returns = {key: by_key.get(key, by_key["agent"]) for key in everyone}  # (members, episodes, slots)
        on_episodes(episodes * len(pairs))
        averaged = {key: r.mean(axis=2) for key, r in returns.items()}
        agent = crossed_interval(averaged["agent"])
        random, shipped = float(averaged["random"].mean()), float(averaged[SHIPPED].mean())
        per_condition[condition] = {
            "mean_return": agent["mean"],
            "ci": agent["ci"],
            "df": agent["df"],
            "per_slot": dict(zip(slots(condition, role), returns["agent"].mean(axis=(0, 1)).tolist(), strict=True)),
            "per_member": dict(
                zip([m.name for m in pop.members], averaged["agent"].mean(axis=1).tolist(), strict=True)
            ),
            "normalized": normalized(agent["mean"], random, shipped),
            # the table every statistic above comes from (members × episodes, averaged over the slots)
            "returns": averaged["agent"].tolist(),
            "references": {
                key: {"mean_return": float(r.mean()), "ci": crossed_interval(r)["ci"], "returns": r.tolist()}
                for key, r in averaged.items()
                if key != "agent"
            },
            "members": [m.name for m in pop.members],
            "excluded": excluded,
            "provisional": pop.provisional,
        }
        cells[condition] = (averaged["agent"], averaged["random"], averaged[SHIPPED])
    return {
        "format": SCORE_FORMAT,
        "agent": contestant.label,
        "description": contestant.description,
        "role": role,
        "fills": f"every {role} slot (a team of copies where a condition has several predators)"
        if role == "predator"
        else "the prey's slot",
        "population": name,
        "provisional": any(c["provisional"] for c in per_condition.values()),
        "episodes": episodes,
        "seed": seed,
        "protocol": "predators greedy; a learned prey of ours ε-greedy with ε = 0.1 (the paper's section 3.4); "
        "agent modules act as they are; every member and every agent plays the episodes the seed fixes, each to its "
        "end, with common random numbers",
        "draws": PROTOCOL,
        "interval": "95 % crossed random-effects interval (members and episodes random; ANOVA components, "
        "Satterthwaite df); docs/leaderboard.md",
        "normalization": "(agent − random) / (reference − random): 0 = uniformly random agent, 1 = the condition's "
        "shipped agents (hierarchical predators, or the prey trained with them), same members and episodes",
        "aggregate": {
            **aggregate(cells, seed),
            "statistic": "interquartile mean over conditions (rliable, Agarwal et al. 2021), stratified bootstrap "
            "(members and episodes resampled within each condition), percentile interval",
        },
        "conditions": per_condition,
    }


# ------------------------------------------------------------------ the report


def fixed(value: float, spec: str) -> str:
    """``value`` in the format ``spec`` ("+.3f", ".2f"), with no minus sign on a value that
    rounds to zero ("0.00", not "-0.00")."""
    text = format(value, spec)
    return format(0.0, spec) if float(text) == 0 else text


def _interval(ci: list[float] | None) -> str:
    return "–" if ci is None else f"[{fixed(ci[0], '+.3f')}, {fixed(ci[1], '+.3f')}]"


def _number(value: float | None) -> str:
    return "–" if value is None else fixed(value, ".2f")


def leaderboard_row(result: dict[str, Any], how: str = "", budget: str = "") -> str:
    """One leaderboard row: who, how trained, budget, aggregate with its interval, per-condition normalized scores."""
    agg = result["aggregate"]
    cells = [_number(c["normalized"]) for c in result["conditions"].values()]
    aggregate_cell = aggregate_text(agg)
    return (
        f"| {result['agent']} | {how or result['description']} | {budget or '–'} | {aggregate_cell} | "
        + " | ".join(cells)
        + " |"
    )


def aggregate_text(agg: dict[str, Any]) -> str:
    """The aggregate with its interval, and over how many conditions where some had no normalized score."""
    if agg["iqm"] is None:
        return "–"
    text = f"{fixed(agg['iqm'], '.2f')} [{fixed(agg['ci'][0], '.2f')}, {fixed(agg['ci'][1], '.2f')}]"
    used = len(agg["conditions"])
    return text + (f" ({used} of {used + len(agg['undefined'])} conditions)" if agg["undefined"] else "")


def leaderboard_header(conditions: list[str]) -> str:
    return (
        "| agent | how trained | budget | IQM, normalized [95 % CI] | " + " | ".join(conditions) + " |\n"
        "|---|---|---|---|" + "---:|" * len(conditions)
    )


def markdown(result: dict[str, Any]) -> str:
    """score.md: the leaderboard row and the per-condition table."""
    conditions = list(result["conditions"])
    provisional = " (PROVISIONAL population, built from the shipped agents)" if result["provisional"] else ""
    refs = list(next(iter(result["conditions"].values()))["references"])
    lines = [
        f"# Score of {result['agent']} as {result['role']}",
        "",
        f"Against population `{result['population']}`{provisional}; {result['episodes']} episodes per member, "
        f"seed {result['seed']}; the agent fills {result['fills']}.",
        "",
        leaderboard_header(conditions),
        leaderboard_row(result),
        "",
        "| condition | mean return [95 % CI] | normalized | "
        + " | ".join(reference_heading(r, result["role"]) for r in refs)
        + " | members (excluded) |",
        "|---|---|---:|" + "---:|" * len(refs) + "---|",
    ]
    for condition, c in result["conditions"].items():
        excluded = f" (excluded: {', '.join(c['excluded'])})" if c["excluded"] else ""
        lines.append(
            f"| {condition} | {fixed(c['mean_return'], '+.3f')} {_interval(c['ci'])} | {_number(c['normalized'])} | "
            + " | ".join(fixed(c["references"][r]["mean_return"], "+.3f") for r in refs)
            + f" | {', '.join(c['members'])}{excluded} |"
        )
    lines += ["", f"Interval: {result['interval']}. Normalization: {result['normalization']}.", ""]
    undefined = {c: why for c in result["conditions"] if (why := undefined_why(result, c))}
    if undefined:
        lines += ["No normalized score (–): " + "; ".join(f"{c}: {why}" for c, why in undefined.items()) + ".", ""]
    placed = standing(result)
    lines += ["## Against the leaderboard", "", placed[0][:1].upper() + placed[0][1:]]
    if len(placed) > 1:
        lines += ["", "| row | IQM, normalized [95 % CI] |", "|---|---|"]
        lines += [f"| {'**' + who + '**' if mine else who} | {text} |" for who, text, mine in _placed_rows(result)]
    lines.append("")
    return "\n".join(lines)


def reference_heading(key: str, role: str) -> str:
    """A reference's column heading: the shipped agents are hierarchical predators, or for a prey the
    learned prey trained with them."""
    if key != SHIPPED:
        return key
    return "shipped (hierarchical)" if role == "predator" else "shipped (learned prey)"


def undefined_why(result: dict[str, Any], condition: str) -> str | None:
    """Why ``condition`` has no normalized score, in words (the reference returns what random
    does: no scale), or None where it has one."""
    c = result["conditions"][condition]
    if c["normalized"] is not None:
        return None
    value = fixed(c["references"]["random"]["mean_return"], "+.3f")
    who = reference_heading(SHIPPED, result["role"]).removeprefix("shipped (").removesuffix(")")
    return f"random and the reference ({who}) both return {value} on these episodes, so there is no scale"


# ------------------------------------------------------------------ against the leaderboard


def shortfall(result: dict[str, Any]) -> list[str]:
    """What a score lacks against a full row of the leaderboard: conditions of the paper not
    scored, fewer episodes per member than :data:`LEADERBOARD_EPISODES`; empty for a full row."""
    scored = [c for c in CONDITIONS if c in result["conditions"]]
    out = []
    if len(scored) < len(CONDITIONS):
        out.append(f"{len(scored)} of {len(CONDITIONS)} conditions ({', '.join(scored)})")
    if result["episodes"] < LEADERBOARD_EPISODES:
        out.append(f"{result['episodes']} episodes per member, not {LEADERBOARD_EPISODES}")
    return out


def leaderboard_entry(who: str, result: dict[str, Any]) -> dict[str, Any]:
    """What :data:`LEADERBOARD` keeps of a row: its name, settings and aggregate."""
    agg = result["aggregate"]
    return {
        "who": who,
        "role": result["role"],
        "population": result["population"],
        "episodes": result["episodes"],
        "seed": result["seed"],
        "conditions": [c for c in CONDITIONS if c in result["conditions"]],
        "aggregate": {k: agg[k] for k in ("iqm", "ci", "conditions", "undefined")},
    }


def _comparable(result: dict[str, Any], rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    entry = leaderboard_entry("", result)
    keys = ("role", "population", "episodes", "seed", "conditions")
    return [r for r in rows if all(r[k] == entry[k] for k in keys) and r["aggregate"]["iqm"] is not None]


def _nearest(result: dict[str, Any], rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Of the comparable rows, the nearest at or below the result's aggregate and the nearest above."""
    mine = result["aggregate"]["iqm"]
    same = sorted(_comparable(result, rows), key=lambda r: r["aggregate"]["iqm"])
    below = [r for r in same if r["aggregate"]["iqm"] <= mine][-1:]
    above = [r for r in same if r["aggregate"]["iqm"] > mine][:1]
    return below + above


def _placed_rows(result: dict[str, Any], rows: list[dict[str, Any]] | None = None) -> list[tuple[str, str, bool]]:
    """(who, aggregate text, is it this score) of the nearest rows and this score, by aggregate."""
    rows = leaderboard_rows() if rows is None else rows
    near = _nearest(result, rows)
    placed = [(r["who"], aggregate_text(r["aggregate"]), False, r["aggregate"]["iqm"]) for r in near]
    placed.append(("this score", aggregate_text(result["aggregate"]), True, result["aggregate"]["iqm"]))
    placed.sort(key=lambda p: (p[3], p[2]))  # a row level with this score before it
    return [p[:3] for p in placed]


def leaderboard_rows() -> list[dict[str, Any]]:
    """The leaderboard's rows (:data:`LEADERBOARD`)."""
    rows: list[dict[str, Any]] = json.loads(LEADERBOARD.read_text())["rows"]
    return rows


def standing(result: dict[str, Any], rows: list[dict[str, Any]] | None = None) -> list[str]:
    """Where ``result`` stands on the leaderboard (``rows``, by default :data:`LEADERBOARD`'s):
    a line naming the settings and then the nearest rows at the same settings (role, population,
    episodes, seed, conditions) with this score among them, by aggregate; or one line saying why
    it is not comparable (what differs, and what would make it so)."""
    rows = leaderboard_rows() if rows is None else rows
    role = result["role"]
    if result["aggregate"]["iqm"] is None:
        return ["no aggregate to place on the leaderboard: no condition has a normalized score"]
    mine = _comparable(result, rows)
    lacks = shortfall(result)
    if mine:
        n = len(result["conditions"])
        partial = f", partial († like these rows: {'; '.join(lacks)})" if lacks else ""
        placed = [
            f"the leaderboard's nearest {role} rows at these settings (population {result['population']}, "
            f"{result['episodes']} episodes per member, seed {result['seed']}, "
            f"{'all ' if n == len(CONDITIONS) else ''}{n} conditions{partial}), by aggregate; rows are not ranked "
            "(docs/leaderboard.md):"
        ]
        width = max(len(who) for who, _, _ in _placed_rows(result, rows))
        placed += [f"  {'>' if me else ' '} {who:{width}s}  {text}" for who, text, me in _placed_rows(result, rows)]
        return placed
    theirs = [r for r in rows if r["role"] == role]
    if not theirs:
        return [f"not comparable with the leaderboard: it has no {role} rows"]
    why, flags = [], []
    populations = sorted({r["population"] for r in theirs})
    if result["population"] not in populations:
        why.append(f"population {result['population']}, where its {role} rows play {', '.join(populations)}")
        flags.append(f"--population {populations[0]}")
    if result["episodes"] != LEADERBOARD_EPISODES:
        fewer = " (partial, †)" if result["episodes"] < LEADERBOARD_EPISODES else ""
        why.append(f"{result['episodes']} episodes per member, its rows {LEADERBOARD_EPISODES}{fewer}")
        flags.append(f"--episodes {LEADERBOARD_EPISODES}")
    if result["seed"] != LEADERBOARD_SEED:
        why.append(f"seed {result['seed']}, its rows {LEADERBOARD_SEED} (the same episodes for every row)")
        flags.append(f"--seed {LEADERBOARD_SEED}")
    conditions = leaderboard_entry("", result)["conditions"]
    if conditions not in [r["conditions"] for r in theirs]:
        n = len(conditions)
        why.append(f"{n} of {len(CONDITIONS)} conditions, on which no row was scored (partial, †)")
        flags.append("--conditions all")
    if not why:
        why.append("no row at its settings has an aggregate")
    rerun = f"; {' '.join(flags)} would place it" if flags else ""
    return [f"not comparable with the leaderboard (docs/leaderboard.md): {'; '.join(why)}{rerun}"]


def dumps(result: dict[str, Any]) -> str:
    return json.dumps(result, indent=2) + "\n"
