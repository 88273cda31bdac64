"""``pursuit-bench score``: the shipped populations (format, size, safety), the score against a
direct evaluation of the same episodes, the scored run kept out of its population, the
interval's coverage, the aggregate, the refusals, and the leaderboard page regenerated."""

import dataclasses
import json
import pickle
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from cli_helpers import load_script, run_cli
from scipy import stats
from scipy.special import expit

from pursuit_bench import pretrained
from pursuit_bench.agents.kinds import LearningAgent, ScriptedAgent
from pursuit_bench.benchmark import populations, score
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.env.task import obs_size
from pursuit_bench.reports import rule_study
from pursuit_bench.rules.policies import AlwaysChase
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.train import build_agents

ROOT = Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------ the populations


def test_the_shipped_populations_fit_the_size_budget() -> None:
    size = populations.size_bytes()
    assert 0 < size <= populations.SIZE_BUDGET_BYTES == 20 * 1024 * 1024, f"{size / 2**20:.1f} MiB"


def test_every_condition_has_a_population_of_each_role_and_none_holds_its_reference() -> None:
    shipped = populations.available()
    for role, name in populations.PROVISIONAL.items():
        assert shipped[name] == list(CONDITIONS)
        for condition in CONDITIONS:
            population = populations.load(name, condition)
            assert (population.role, population.provisional) == (role, True)
            reference = score._agent_weights(pretrained.load(condition))
            for member in population.members:
                assert not member.digests() & reference, f"{name}/{condition}: {member.name} is the reference's"
            assert {m.policy for m in population.members if not m.learned} == {
                p for p, (r, _) in populations.SCRIPTED.items() if r == role
            }


def test_the_populations_load_without_running_code_from_the_files(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every member's agents are built from JSON and safetensors only: unpickling is made to fail."""

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a population file was unpickled")

    monkeypatch.setattr(pickle, "loads", refuse)
    monkeypatch.setattr(pickle, "load", refuse)
    monkeypatch.setattr(torch, "load", refuse)
    for name in populations.PROVISIONAL.values():
        for condition in ("1p-high", "3p-low-shared"):
            population = populations.load(name, condition)
            other = score.slots(condition, population.role)
            for member in population.members:
                for path in member.files.values():
                    header_length = int.from_bytes(path.read_bytes()[:8], "little")  # safetensors: JSON header first
                    json.loads(path.read_bytes()[8 : 8 + header_length])
                agents = member.agents(condition, other)
                assert list(agents) == other
                assert all(isinstance(a, LearningAgent if member.learned else ScriptedAgent) for a in agents.values())


def test_a_population_that_breaks_the_format_is_refused(tmp_path: Path) -> None:
    where = tmp_path / "mine" / "1p-high"
    where.mkdir(parents=True)
    member = {"name": "a", "kind": "hierarchical", "policy": None, "seed": 1000, "trained": None, "files": {}}
    for members, message in (
        ([member], "files for prey_0"),
        ([{**member, "kind": "scripted", "policy": "AlwaysChase"}], "a scripted prey needs"),
        ([{**member, "files": {"prey_0": "../../elsewhere.safetensors"}}], "outside the population's folder"),
        ([], "at least one member"),
    ):
        index = {"population": "mine", "condition": "1p-high", "role": "prey", "provisional": False, "members": members}
        (where / populations.INDEX).write_text(json.dumps(index))
        with pytest.raises(ValueError, match=message):
            populations.load("mine", "1p-high", folder=tmp_path)
    with pytest.raises(ValueError, match="no population 'other'"):
        populations.load("other", "1p-high", folder=tmp_path)


@pytest.mark.parametrize(
    ("source", "agent", "message"),
    [
        ("1p-low", "predator_0", "holds predator_0, a predator, for the slot prey_0; expected a prey"),
        (
            "3p-low-shared",
            "prey_0",
            "a prey trained in 3p-low-shared, observing 22 numbers; a prey of 1p-high observes 10",
        ),
    ],
)
def test_a_member_whose_weights_do_not_fit_its_slot_is_refused_before_play(
    tmp_path: Path, source: str, agent: str, message: str
) -> None:
    """A prey member holding a predator's weights, or a prey of another team size: the file, what
    it holds and what the slot expects, in one line, before anything is played."""
    where = tmp_path / "mine" / "1p-high"
    (where / "m").mkdir(parents=True)
    (where / "m" / "prey_0.safetensors").write_bytes((pretrained.FOLDER / source / f"{agent}.safetensors").read_bytes())
    member = {"name": "m", "kind": "hierarchical", "policy": None, "seed": 5, "trained": None}
    index = {"population": "mine", "condition": "1p-high", "role": "prey", "provisional": False}
    members = [{**member, "files": {"prey_0": "m/prey_0.safetensors"}}]
    (where / populations.INDEX).write_text(json.dumps({**index, "members": members}))
    population = populations.load("mine", "1p-high", folder=tmp_path)
    with pytest.raises(ValueError, match=f"^{where / 'm' / 'prey_0.safetensors'}: {message}$"):
        score.check_members(population)


def test_a_member_trained_with_obstacles_loads_with_its_range_readings(tmp_path: Path) -> None:
    """A prey trained among obstacles observes 12 range readings more: the population's loader
    and the rule study's build it so (they built the plain size, and its weights did not fit)."""
    config = dataclasses.replace(pretrained.training_config("1p-low"), obstacles=4)
    wide = obs_size(2, True)
    assert wide == obs_size(2) + 12
    _, (fresh,) = build_agents([config], [wide])
    paths = pretrained.export(fresh, config, tmp_path / "export", trained_episodes=1, provenance={})
    (path,) = [p for p in paths if p.name == "prey_0.safetensors"]
    where = tmp_path / "mine" / "1p-low"
    (where / "m").mkdir(parents=True)
    path.rename(where / "m" / "prey_0.safetensors")
    member = {"name": "m", "kind": "hierarchical", "policy": None, "seed": 5, "trained": None}
    index = {"population": "mine", "condition": "1p-low", "role": "prey", "provisional": False}
    (where / populations.INDEX).write_text(
        json.dumps({**index, "members": [{**member, "files": {"prey_0": "m/prey_0.safetensors"}}]})
    )
    (prey,) = populations.load("mine", "1p-low", folder=tmp_path).members[0].agents("1p-low", ["prey_0"]).values()
    studied = rule_study.load_member(where / "m" / "prey_0.safetensors")
    obs = np.random.default_rng(0).uniform(-1, 1, (5, wide)).astype(np.float32)
    original = fresh["prey_0"]
    assert isinstance(prey, LearningAgent) and isinstance(original, LearningAgent)
    expected = original.learner.decisive_q(obs, original.member)
    for loaded in (prey, studied):
        np.testing.assert_array_equal(loaded.learner.decisive_q(obs, loaded.member), expected)


def test_a_population_written_as_the_rule_study_writes_it_is_read_as_it_stands(tmp_path: Path) -> None:
    """OWNERS.md's format: members exported by ``pretrained.export`` into ``<member>/<agent>.safetensors``."""
    agents = pretrained.load("1p-low")
    config = pretrained.training_config("1p-low")
    (path,) = [
        p
        for p in pretrained.export(
            agents, config, tmp_path / "export", trained_episodes=15000, provenance={"preset": "reproduction"}
        )
        if p.name == "prey_0.safetensors"
    ]
    where = tmp_path / "populations" / populations.RULE_STUDY / "1p-high"
    (where / "hierarchical-seed1000").mkdir(parents=True)
    path.rename(where / "hierarchical-seed1000" / "prey_0.safetensors")
    trained = {"preset": "reproduction", "episodes": 15000, "predator_kind": "hierarchical", "build": "0123abc"}
    members = [
        {
            "name": "hierarchical-seed1000",
            "kind": "hierarchical",
            "policy": None,
            "seed": 1000,
            "trained": trained,
            "files": {"prey_0": "hierarchical-seed1000/prey_0.safetensors"},
        },
        {
            "name": "FleeingPrey",
            "kind": "scripted",
            "policy": "FleeingPrey",
            "seed": None,
            "trained": None,
            "files": {},
        },
    ]
    index = {
        "population": "rule-study",
        "condition": "1p-high",
        "role": "prey",
        "provisional": False,
        "members": members,
    }
    (where / populations.INDEX).write_text(json.dumps(index))
    folder = tmp_path / "populations"
    assert populations.default("predator", folder) == populations.RULE_STUDY
    assert populations.default("prey", folder) == populations.PROVISIONAL["predator"]
    population = populations.load(populations.RULE_STUDY, "1p-high", folder=folder)
    assert [m.name for m in population.members] == ["hierarchical-seed1000", "FleeingPrey"]
    assert not population.provisional
    (prey,) = population.members[0].agents("1p-high", ["prey_0"]).values()
    assert populations.weights_digest(prey.learner.member_weights(prey.member)) in score._agent_weights(agents)


# ------------------------------------------------------------------ the score


@pytest.mark.slow
def test_a_scripted_agents_score_is_a_direct_evaluation_of_the_same_episodes() -> None:
    condition, episodes, seed = "3p-low-shared", 6, 7
    result = score.score(score.resolve("always-chase", "predator"), [condition], episodes=episodes, seed=seed)
    found = result["conditions"][condition]
    population = populations.load(result["population"], condition)
    assert found["members"] == [m.name for m in population.members]
    for member in population.members:
        prey = member.agents(condition, ["prey_0"])
        team = {name: ScriptedAgent(name, AlwaysChase()) for name in score.slots(condition, "predator")}
        direct = evaluate_agents(
            condition,
            {**team, **prey},
            episodes=episodes,
            seed=seed,
            prey_epsilon=0.1 if member.learned else None,
            num_envs=episodes,
            prey_check=False,
        )
        trained = np.mean([panel["trained"] for panel in direct["panels"]])
        assert found["per_member"][member.name] == pytest.approx(trained, abs=1e-12)
    assert found["references"]["always-chase"]["mean_return"] == found["mean_return"]
    assert result["provisional"] is (result["population"] != populations.RULE_STUDY)


@pytest.mark.slow
def test_the_scored_run_is_kept_out_of_its_population() -> None:
    condition = "3p-low-shared"
    contestant = score.resolve("pretrained:3p-low-individual", "predator")
    name = populations.PROVISIONAL["prey"]  # it holds the shipped prey of the other conditions
    population = populations.load(name, condition)
    assert "shipped-3p-low-individual" in [m.name for m in population.members]
    assert score.excluded_members(contestant, population) == {
        "shipped-3p-low-individual": "holds weights of the scored run"
    }
    result = score.score(contestant, [condition], episodes=2, seed=0, population=name)
    found = result["conditions"][condition]
    assert "shipped-3p-low-individual" not in found["members"] and found["excluded"]
    # the hierarchical reference of each condition is its own run: nothing of another condition is excluded
    assert score.excluded_members(score.resolve("pretrained", "predator"), population) == {}


# ------------------------------------------------------------------ the statistics


def _capture_like(rng: np.random.Generator, m: int, e: int) -> np.ndarray:
    p = expit(rng.normal(0, 1, (m, 1)) + rng.normal(0, 1, (1, e)))
    return (rng.random((m, e)) < p) * 1.0 - 0.3 * rng.random((m, e))


@pytest.mark.parametrize("members", [4, 13])
def test_the_interval_covers_what_it_claims(members: int) -> None:
    """Members and episodes random, returns like the game's (a capture or not, a cost): the 95 %
    interval holds the true mean 0.35 in 95 % ± 2 points of 1500 simulated tables of its own draws."""
    held = score.coverage(_capture_like, 0.5 - 0.15, members, 20, draws=1500, seed=members + 7)
    assert 0.93 <= held <= 0.97, held


def test_the_interval_reduces_to_the_t_interval_for_one_member_and_grows_with_the_members_spread() -> None:
    rng = np.random.default_rng(0)
    y = rng.normal(size=(1, 30))
    mean, sd = y.mean(), y.std(ddof=1) / np.sqrt(30)
    assert score.crossed_interval(y)["ci"] == pytest.approx(list(stats.t.interval(0.95, 29, mean, sd)))
    close = rng.normal(size=(4, 30)) * 0.1
    apart = close + np.array([[-1.0], [0.0], [1.0], [2.0]])
    assert np.diff(score.crossed_interval(apart)["ci"])[0] > 5 * np.diff(score.crossed_interval(close)["ci"])[0]


def test_the_intervals_degrees_of_freedom_have_a_floor_of_one_on_degenerate_tables() -> None:
    """Two members, two episodes: the residual's subtracted term takes Satterthwaite's df below 1
    (1/3 here, by hand: every mean square 1/4), where the t quantile is in the thousands; the
    floor gives the t interval with 1 df. A table whose members' and episodes' means are all
    equal but whose returns differ gets the residual's share, not a zero-width interval."""
    one_cell = score.crossed_interval(np.array([[0.0, 0.0], [0.0, 1.0]]))
    assert one_cell["df"] == 1.0 and one_cell["se"] == pytest.approx(0.25)
    assert one_cell["ci"] == pytest.approx(list(stats.t.interval(0.95, 1, 0.25, 0.25)))
    crossed = score.crossed_interval(np.array([[0.0, 1.0], [1.0, 0.0]]))
    assert crossed["df"] == 1.0 and crossed["ci"] == pytest.approx(list(stats.t.interval(0.95, 1, 0.5, 0.5)))
    rng = np.random.default_rng(2)
    for _ in range(300):  # tiny tables of capture-like returns: every df at least 1, every interval finite
        found = score.crossed_interval(_capture_like(rng, 2, int(rng.integers(2, 5))))
        assert found["df"] is None or found["df"] >= 1.0
        assert found["ci"] is None or np.all(np.isfinite(found["ci"]))
    assert score.crossed_interval(np.full((3, 4), -1.0))["ci"] == [-1.0, -1.0]  # all the same: no spread at all


def test_the_aggregate_is_rliables_interquartile_mean() -> None:
    values = np.array([0.1, 0.9, 0.5, -0.2, 1.3, 0.7, 0.6, 0.2, 0.95, 0.4])
    middle = np.sort(values)[2:8]  # 10 conditions: the lowest and highest two left out
    assert score.iqm(values) == pytest.approx(middle.mean()) == pytest.approx(stats.trim_mean(values, 0.25))
    rng = np.random.default_rng(1)
    cells = {
        f"c{j}": (rng.normal(0.5 + j / 10, 0.1, (3, 8)), rng.normal(0.0, 0.1, (3, 8)), rng.normal(1.0, 0.1, (3, 8)))
        for j in range(5)
    }
    result = score.aggregate(cells, seed=3, resamples=400)
    assert result["ci"][0] < result["iqm"] < result["ci"][1]
    assert score.aggregate(cells, seed=3, resamples=400) == result  # seeded
    flat = np.full((3, 8), -1.0)
    undefined = score.aggregate({**cells, "same": (flat, flat, flat)}, seed=3, resamples=400)
    assert undefined["undefined"] == ["same"] and undefined["iqm"] == result["iqm"]


# ------------------------------------------------------------------ the command


def test_a_hand_written_agent_is_scored_in_one_command(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "pursuer.py").write_text(
        "import numpy as np\n\nclass P:\n    def act_batch(self, obs):\n"
        "        return np.tile([1, 0], (len(obs), 1))\n\ndef make():\n    return P()\n"
    )
    code, output = run_cli(
        "score",
        "pursuer:make",
        "--role",
        "predator",
        "--conditions",
        "3p-low-shared",
        "--episodes",
        "3",
        "--out",
        "out",
    )
    assert code == 0, output
    result = json.loads((tmp_path / "out" / "score.json").read_text())
    provisional = populations.default("predator") != populations.RULE_STUDY  # until the rule study's ships
    assert result["provisional"] is provisional and result["population"] == populations.default("predator")
    assert ("PROVISIONAL" in output) is provisional and "a team of copies" in output
    assert list(result["conditions"]["3p-low-shared"]["per_slot"]) == ["predator_0", "predator_1", "predator_2"]
    assert ("PROVISIONAL" in (tmp_path / "out" / "score.md").read_text()) is provisional
    # 3 episodes in one condition: not the leaderboard's settings, said in one line (issue 67)
    placed = [line for line in output.splitlines() if "leaderboard" in line]
    assert len(placed) == 1 and placed[0].startswith("not comparable with the leaderboard"), output
    assert "3 episodes per member, its rows 20 (partial, †)" in placed[0] and "--episodes 20" in placed[0]
    assert "N" + placed[0][1:] in (tmp_path / "out" / "score.md").read_text()  # the same in score.md
    sys.modules.pop("pursuer", None)


def _committed(name: str) -> dict[str, Any]:
    return json.loads((ROOT / "results" / "score" / name / "score.json").read_text())


def test_a_score_is_placed_among_the_leaderboard_rows_at_its_settings_or_says_why_not() -> None:
    """After the per-condition lines, ``score`` places the aggregate between the nearest leaderboard
    rows at the same settings (role, population, episodes, seed, conditions), or says in one line
    what differs (the page's † rule: fewer conditions or episodes is partial) and what would place it."""
    chase = _committed("predator-always-chase")
    lines = score.standing(chase)
    assert lines[0].startswith("the leaderboard's nearest predator rows at these settings (population rule-study, ")
    assert "20 episodes per member, seed 12345, all 10 conditions)" in lines[0]
    # level with the always-chase row (it is that row), the next row above it the shipped reference
    assert [line[4:].split("  ")[0] for line in lines[1:]] == ["always-chase", "this score", "hierarchical (shipped)"]
    assert lines[2].startswith("  > ") and lines[2].endswith(score.aggregate_text(chase["aggregate"]))
    halfway = {**chase, "aggregate": {**chase["aggregate"], "iqm": 0.6}}  # between pure pursuit and always-stalk
    assert [line[4:].split("  ")[0] for line in score.standing(halfway)[1:]] == [
        "pure pursuit",
        "this score",
        "always-stalk",
    ]
    # the 1-predator rows are partial: a score on the same two conditions is placed among them, marked
    ppo = score.standing(_committed("predator-ppo"))
    assert "2 conditions, partial († like these rows: 2 of 10 conditions (1p-low, 1p-high))" in ppo[0]
    assert all("hierarchical" not in line for line in ppo[1:]) and any("PPO" in line for line in ppo[1:])

    def why(**changed: Any) -> str:
        (line,) = score.standing({**chase, **changed})
        assert line.startswith("not comparable with the leaderboard (docs/leaderboard.md): "), line
        return line

    assert "100 episodes per member, its rows 20; --episodes 20 would place it" in why(episodes=100)
    assert "10 episodes per member, its rows 20 (partial, †)" in why(episodes=10)
    assert "seed 7, its rows 12345" in why(seed=7) and "--seed 12345" in why(seed=7)
    assert "population provisional-prey, where its predator rows play rule-study" in why(population="provisional-prey")
    three = {c: v for c, v in chase["conditions"].items() if c.startswith("3p")}
    assert "4 of 10 conditions, on which no row was scored (partial, †); --conditions all" in why(conditions=three)
    none = {**chase, "aggregate": {**chase["aggregate"], "iqm": None}}
    assert score.standing(none) == ["no aggregate to place on the leaderboard: no condition has a normalized score"]
    text = score.markdown(chase)
    assert "## Against the leaderboard\n\nThe leaderboard's nearest predator rows" in text
    row = f"| always-chase | {score.aggregate_text(chase['aggregate'])} |"  # the row is this score's file
    assert "| **this score** | " in text and row in text


def test_a_prey_s_reference_is_the_learned_prey_and_an_undefined_score_says_why(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    fleeing = _committed("prey-fleeing")  # in 1p-low random and the learned prey both return -1.000
    text = score.markdown(fleeing)
    assert "| shipped (learned prey) |" in text and "shipped (hierarchical)" not in text
    assert "| shipped (hierarchical) |" in score.markdown(_committed("predator-always-chase"))
    why = "random and the reference (learned prey) both return -1.000 on these episodes, so there is no scale"
    assert score.undefined_why(fleeing, "1p-low") == why and score.undefined_why(fleeing, "1p-high") is None
    assert f"No normalized score (–): 1p-low: {why}" in text
    # and in the terminal: the command's own lines, from these results
    monkeypatch.setattr(score, "score", lambda *args, **kwargs: fleeing)
    code, output = run_cli("score", "FleeingPrey", "--role", "prey", "--episodes", "20", "--out", str(tmp_path))
    assert code == 0, output
    low, high = fleeing["conditions"]["1p-low"], fleeing["conditions"]["1p-high"]
    assert f"1p-low: return {low['mean_return']:+.3f}, normalized – ({why})" in output
    assert f"1p-high: return {high['mean_return']:+.3f}, normalized {high['normalized']:.2f}" in output
    assert "the leaderboard's nearest prey rows at these settings" in output and "  > this score" in output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["nowhere_module:make", "--role", "predator"], "cannot import 'nowhere_module'"),
        (["FleeingPrey", "--role", "predator"], "FleeingPrey is a prey: it cannot play --role predator"),
        (
            ["prey_only:make", "--role", "predator"],
            "agent predator_0 (prey_only:make) cannot play --role predator in 1p-low: given 2 observations of 10 "
            "numbers (the predator's there), act returned shape () for one observation; expected (mode, direction), "
            "shape (2,)",
        ),
        (
            ["predator_only:make", "--role", "prey", "--conditions", "3p-low-shared"],
            "agent prey_0 (predator_only:make) cannot play --role prey in 3p-low-shared: given 2 observations of 22 "
            "numbers (the prey's there), act returned shape (2,) for one observation; expected one direction, shape ()",
        ),
        (
            ["pretrained:3p-low-shared", "--role", "prey", "--conditions", "1p-low,2p-high-shared"],
            "pretrained:3p-low-shared cannot play 1p-low, 2p-high-shared: its prey was trained in 3p-low-shared, "
            "as a prey observing 22 numbers against 3 predators; expected a prey observing 10 numbers against "
            "1 predator in 1p-low; a prey observing 16 numbers against 2 predators in 2p-high-shared",
        ),
        (["random", "--role", "predator", "--conditions", "9p-nowhere"], "--conditions '9p-nowhere': expected"),
        (
            ["pretrained:1p-high", "--role", "predator", "--conditions", "2p-low-shared"],
            "cannot play 2p-low-shared: its predators were trained in 1p-high, as 1 predator observing 10 numbers; "
            "expected 2 predators observing 16 numbers each in 2p-low-shared",
        ),
        (["random", "--role", "predator", "--population", "nobody"], "no population 'nobody'"),
    ],
)
def test_bad_input_is_refused_in_one_line_and_writes_nothing(
    args: list[str], message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "prey_only.py").write_text(
        "class R:\n    def act(self, o):\n        return 3\n\ndef make():\n    return R()\n"
    )
    (tmp_path / "predator_only.py").write_text(
        "class P:\n    def act(self, o):\n        return (1, 3)\n\ndef make():\n    return P()\n"
    )
    code, output = run_cli("score", *args, "--episodes", "2", "--out", "out")
    assert code == 2, output
    assert message in output and len(output.strip().splitlines()) == 1, output
    assert not (tmp_path / "out").exists()
    sys.modules.pop("prey_only", None)
    sys.modules.pop("predator_only", None)


# ------------------------------------------------------------------ the leaderboard


def _leaderboard() -> Any:
    return load_script("docs/gen/leaderboard.py")


def test_the_marl_rows_comparisons_wait_for_a_condition_s_rows_then_are_welch_and_holm(tmp_path: Path) -> None:
    leaderboard = _leaderboard()
    rng = np.random.default_rng(3)
    learners = [*leaderboard.THEIRS, *leaderboard.OURS]
    values = {}
    for learner in learners:
        for condition in leaderboard.MARL_CONDITIONS:
            for seed in leaderboard.MARL_SEEDS:
                value = float(rng.normal(1.0 + 0.1 * learners.index(learner), 0.05))
                values[learner, condition, seed] = value
                result = {"conditions": {condition: {"normalized": value}}, "aggregate": {"ci": [value - 0.1, value]}}
                (tmp_path / f"{condition}-{learner}-seed{seed}.score.json").write_text(json.dumps(result))
    scores = leaderboard.marl_scores(tmp_path)
    rows = leaderboard.marl_comparisons(scores)
    assert len(rows) == 18
    raw = []
    for row in rows:
        a = [values[row["theirs"], row["condition"], s] for s in leaderboard.MARL_SEEDS]
        b = [values[row["ours"], row["condition"], s] for s in leaderboard.MARL_SEEDS]
        reference = stats.ttest_ind(a, b, equal_var=False)
        assert row["mean"] == pytest.approx(np.mean(a) - np.mean(b)) and row["p"] == pytest.approx(reference.pvalue)
        raw.append(reference.pvalue)
    # Holm by hand: the k-th smallest p times (m - k), kept monotone, capped at 1
    order = np.argsort(raw)
    adjusted = np.minimum(1, np.maximum.accumulate([(18 - k) * raw[i] for k, i in enumerate(order)]))
    assert [rows[i]["p_holm"] for i in order] == pytest.approx(adjusted.tolist())
    table = leaderboard.marl_tables(tmp_path)
    assert table.count("\n| 1p-high | IPPO (BenchMARL) | flat DQN (ours) |") == 1
    # one row missing: its condition's six comparisons wait; the others' are made, Holm over all 18
    # with the six counted at p = 1, so each adjusted p is at least the whole family's
    (tmp_path / "1p-high-iql-seed2.score.json").unlink()
    part = leaderboard.marl_comparisons(leaderboard.marl_scores(tmp_path))
    assert len(part) == 12 and {r["condition"] for r in part} == {"2p-low-shared", "3p-high-individual"}
    whole = {(r["theirs"], r["ours"], r["condition"]): r for r in rows}
    for row in part:
        same = whole[row["theirs"], row["ours"], row["condition"]]
        assert row["p"] == same["p"] and row["p_holm"] >= same["p_holm"]
    raw = [r["p"] for r in part] + [1.0] * 6
    order = np.argsort(raw, kind="stable")
    adjusted = np.minimum(1, np.maximum.accumulate([(18 - k) * raw[i] for k, i in enumerate(order)]))
    by_hand = dict(zip(order.tolist(), adjusted.tolist(), strict=True))
    assert [r["p_holm"] for r in part] == pytest.approx([by_hand[i] for i in range(12)])
    table = leaderboard.marl_tables(tmp_path)
    assert "1 of 45 rows still to come" in table and "of 1p-high are made once" in table
    assert table.count("\n| 2p-low-shared | IPPO (BenchMARL) | flat DQN (ours) |") == 1
    assert "| 1p-high | IPPO" not in table


def test_the_leaderboard_page_regenerates_from_the_committed_scores_byte_for_byte() -> None:
    leaderboard = _leaderboard()
    page = (ROOT / "docs" / "leaderboard.md").read_text()
    assert leaderboard.render(page) == page
    assert score.LEADERBOARD.read_text() == leaderboard.summary()  # the rows score places a result among
    # the tables first, the method after them (issue 67): the first section is the results, and
    # the rows start within the page's first screen
    headings = [line for line in page.splitlines() if line.startswith("## ")]
    assert headings[0] == "## Results" and page.index("| agent |") < page.index("## What a score is")
    assert page[: page.index("| agent |")].count("\n") < 40
    assert f"--episodes {leaderboard.EPISODES} " in page.partition("## How to submit a result")[2]
    rows = json.loads((ROOT / "results" / "score" / "rows.json").read_text())
    for row in rows:
        result = json.loads((ROOT / "results" / "score" / row["file"]).read_text())
        assert row["command"].startswith("pursuit-bench score ") and f"--role {result['role']}" in row["command"]
        assert f"--episodes {result['episodes']} --seed {result['seed']}" in row["command"]


def test_a_partial_score_is_marked_and_listed_after_the_full_ones(tmp_path: Path) -> None:
    """A row scored in fewer conditions, or with fewer episodes per member, than the leaderboard's
    full set is marked, said why under its table, and never placed above or among the full rows,
    whatever its aggregate and its place in rows.json."""
    leaderboard = _leaderboard()

    def result(conditions: list[str], episodes: int, iqm: float) -> dict[str, Any]:
        cells = {c: {"normalized": iqm} for c in conditions}
        aggregate = {"iqm": iqm, "ci": [iqm - 0.1, iqm + 0.1], "conditions": conditions, "undefined": []}
        return {
            "conditions": cells,
            "episodes": episodes,
            "aggregate": aggregate,
            "population": "p",
            "provisional": False,
            "role": "predator",
        }

    scores = {
        "few-conditions": result(["1p-low", "1p-high"], 20, 1.5),
        "few-episodes": result(list(CONDITIONS), 5, 1.4),
        "full-a": result(list(CONDITIONS), 20, 0.5),
        "full-b": result(list(CONDITIONS), 40, 0.9),
    }
    rows = []
    for who, found in scores.items():
        (tmp_path / f"{who}.json").write_text(json.dumps(found))
        rows.append({"who": who, "role": "predator", "how": "h", "budget": "b", "file": f"{who}.json", "command": "c"})
    (tmp_path / "rows.json").write_text(json.dumps(rows))
    text = leaderboard.tables(tmp_path)
    table = [line.split(" | ")[0].removeprefix("| ") for line in text.splitlines() if line.startswith("| ")]
    assert table[1:] == ["full-a", "full-b", "few-conditions †", "few-episodes †"]
    assert "- few-conditions: 2 of 10 conditions (1p-low, 1p-high)\n" in text
    assert "- few-episodes: 5 episodes per member, not 20\n" in text
    assert "† **Partial**" in text and leaderboard.tables(tmp_path) == text


def test_a_score_that_rounds_to_zero_is_printed_without_a_minus_sign() -> None:
    assert [score.fixed(v, ".2f") for v in (-0.001, 0.0, -0.006, 0.004)] == ["0.00", "0.00", "-0.01", "0.00"]
    assert [score.fixed(v, "+.3f") for v in (-0.0001, 0.0004, -0.0006)] == ["+0.000", "+0.000", "-0.001"]
