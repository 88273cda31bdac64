"""Evaluation with common random numbers (issue 47): every variant meets the same prey draws in
the same episode, a variant's result does not depend on what is played beside it, and the
evaluation's result says which protocol made it."""

import numpy as np
import pytest

from pursuit_bench import pretrained
from pursuit_bench.agents.kinds import Prey, ScriptedAgent
from pursuit_bench.env.conditions import CONDITIONS
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk
from pursuit_bench.training.evaluate import PROTOCOL, evaluate_agents, exploration_draws, play_variants


class WatchedPrey(Prey):
    """The shipped prey, keeping the choices (after exploration) of every call: (rows, choices)."""

    def __init__(self, prey: Prey) -> None:
        super().__init__(prey.name, prey.learner, prey.member)
        self.calls: list[np.ndarray] = []

    def to_env(self, choices: np.ndarray, obs: np.ndarray) -> np.ndarray:
        self.calls.append(np.array(choices))
        return super().to_env(choices, obs)


def test_every_variant_meets_the_same_prey_draws_in_the_same_episode() -> None:
    agents = pretrained.load("1p-low")
    prey = WatchedPrey(agents["prey_0"])  # type: ignore[arg-type]
    trained = {"predator_0": agents["predator_0"], "prey_0": prey}
    chase = {**trained, "predator_0": ScriptedAgent("predator_0", AlwaysChase())}
    stalk = {**trained, "predator_0": ScriptedAgent("predator_0", AlwaysStalk())}
    episodes, arenas, seed = 6, 3, 11
    played = play_variants(
        "1p-low", [(v, {"prey_0": 1.0}) for v in (trained, chase, stalk)], episodes, seed=seed, num_envs=arenas
    )
    # with ε = 1 the prey's every choice is a draw: until the first episode ends, call t is step t
    # of episodes 0 … arenas-1 in every variant, and holds exactly those episodes' draws
    shortest = min(int(e.lengths.min()) for e in played)
    assert shortest > 1
    for t in range(shortest):
        rows = prey.calls[t].reshape(3, arenas)  # variants × arenas, one call for all (one actor)
        expected = [
            exploration_draws(seed, a, 1, CONDITIONS["1p-low"].max_steps, Prey.n_actions)[1][t] for a in range(arenas)
        ]
        for variant in rows:
            assert variant.tolist() == expected
    # chasing and stalking make the episodes differ: the test is not one of identical plays
    assert not np.array_equal(played[1].returns, played[2].returns)


def test_a_variant_plays_the_same_alone_as_beside_others() -> None:
    agents = pretrained.load("2p-low-shared")
    chase = {**agents, "predator_1": ScriptedAgent("predator_1", AlwaysChase())}
    eps = {"prey_0": 0.1}
    alone = play_variants("2p-low-shared", [(agents, eps)], 5, seed=4, num_envs=2)[0]
    beside = play_variants("2p-low-shared", [(chase, eps), (agents, eps)], 5, seed=4, num_envs=2)[1]
    for field in ("returns", "lengths", "captured", "chase_fraction"):
        assert np.array_equal(getattr(alone, field), getattr(beside, field)), field
    # numpy's hypot may round the last bit differently in arrays of other lengths (SIMD)
    assert np.allclose(alone.distance, beside.distance, rtol=1e-12, atol=0)
    assert alone.returns.shape == (5, 3)
    other_seed = play_variants("2p-low-shared", [(agents, eps)], 5, seed=5, num_envs=2)[0]
    assert not np.array_equal(alone.returns, other_seed.returns)


def test_the_evaluation_is_labelled_and_repeats_exactly() -> None:
    agents = pretrained.load("1p-low")
    first = evaluate_agents("1p-low", agents, episodes=4, seed=2, num_envs=2)
    again = evaluate_agents("1p-low", pretrained.load("1p-low"), episodes=4, seed=2, num_envs=2)
    assert first["protocol"]["draws"] == PROTOCOL == "crn-1"
    assert first["panels"] == again["panels"] and first["prey_check"] == again["prey_check"]
    # the trained variant's episodes are those of the variant played alone
    alone = play_variants("1p-low", [(agents, {"prey_0": 0.1})], 4, seed=2, num_envs=2)[0]
    assert first["panels"][0]["trained"] == pytest.approx(alone.returns[:, 0].mean(), abs=0)


@pytest.mark.parametrize("obstacles", [0, 3])
def test_a_queued_start_is_the_start_its_seed_draws_and_is_used_once(obstacles: int) -> None:
    """``first_start`` gives what ``reset`` with the episode's seed draws; an arena whose next
    start is queued starts from it at its autoreset, and draws again after that."""
    from pursuit_bench.env.vector import VectorPursuitEnv

    drawn = VectorPursuitEnv(2, "2p-high-shared", obstacles=obstacles)
    drawn.reset(seed=0)
    drawn.reseed(0, 11)
    queued = VectorPursuitEnv(2, "2p-high-shared", obstacles=obstacles)
    queued.reset(seed=0)
    layout, around = queued.core.first_start(np.random.default_rng(11))
    queued.queue_starts(np.array([0]), layout[None], around[None] if obstacles else None)
    # a queued start is not the draw the arena's own generator would make (the test can fail)
    assert not np.array_equal(layout, queued.core.first_start(np.random.default_rng(12))[0])
    ends = 0
    stay = np.zeros((2, drawn.n_agents, 2), dtype=np.int64)  # stalk, direction 0: the walls end it
    while ends < 2:
        a, _, term_a, trunc_a, _ = drawn.step(stay)
        b, *_ = queued.step(stay)
        np.testing.assert_array_equal(a[1], b[1])
        if term_a[0].any() or trunc_a[0].any():
            ends += 1
            if ends == 1:  # the first restart: the seed's draw in one, the queued copy in the other
                np.testing.assert_array_equal(a[0], b[0])
                np.testing.assert_array_equal(drawn.obstacles[0], queued.obstacles[0])
            else:  # the second: the queue was used up, each arena draws from its own generator
                assert not np.array_equal(a[0], b[0])
        else:
            np.testing.assert_array_equal(a[0], b[0])


def test_setups_evaluated_together_give_what_each_gives_alone() -> None:
    """``evaluate_together`` (a study's members in one batch: parts of their own in the physics
    and in torch's passes) returns ``evaluate_agents``' result for every setup."""
    from pursuit_bench.rules.policies import FleeingPrey
    from pursuit_bench.training.evaluate import evaluate_together

    agents = pretrained.load("2p-low-shared")
    fleeing = {**agents, "prey_0": ScriptedAgent("prey_0", FleeingPrey())}
    setups = [(agents, 0.1), (fleeing, None), (agents, None)]
    together = evaluate_together("2p-low-shared", setups, episodes=6, seed=3, num_envs=4, prey_check=False)
    for (actors, eps), batched in zip(setups, together, strict=True):
        alone = evaluate_agents(
            "2p-low-shared", actors, episodes=6, seed=3, num_envs=4, prey_epsilon=eps, prey_check=False
        )
        # numpy's hypot may round the last bit differently in arrays of other lengths (SIMD)
        far, near = alone.pop("distance_travelled"), batched.pop("distance_travelled")
        assert far == pytest.approx(near, rel=1e-12)
        assert batched == alone
    assert together[0]["panels"] != together[1]["panels"]  # the setups differ: the test can fail


def test_torch_passes_are_made_per_part() -> None:
    """Rows labelled as parts get, where torch's pass decides, the Q-values each part gets alone."""
    from pursuit_bench.agents import dqn

    learner = pretrained.load("2p-low-shared")["predator_0"].learner  # type: ignore[attr-defined]
    rng = np.random.default_rng(0)
    obs = rng.normal(0, 0.5, (90, learner.n_obs)).astype(np.float32)
    parts = np.repeat([0, 1, 2], [20, 45, 25])
    gap = dqn.DECISIVE_GAP
    try:
        dqn.DECISIVE_GAP = 1e9  # every row undecided: every part goes to torch
        per_part = np.concatenate([learner.decisive_q(obs[parts == p], 0) for p in range(3)])
        np.testing.assert_array_equal(learner.decisive_q(obs, 0, parts), per_part)
        torch_q = learner._torch_q(obs[parts == 1], 0)
        np.testing.assert_array_equal(per_part[parts == 1], torch_q)
    finally:
        dqn.DECISIVE_GAP = gap
    with_parts = learner.decisive_q(obs, 0, parts)  # decided rows: the compiled pass, as without parts
    np.testing.assert_array_equal(with_parts.argmax(-1), learner.decisive_q(obs, 0).argmax(-1))


def test_more_parts_than_a_world_keeps_apart_are_played_in_worlds_of_their_own() -> None:
    """With walls to keep apart (``contain``) a world holds at most MAX_BLOCKS parts: more are
    split across worlds, and each part still plays as it does alone."""
    from pursuit_bench.env.world import MAX_BLOCKS
    from pursuit_bench.rules.policies import FleeingPrey

    def team(rule: type) -> dict:
        return {"predator_0": ScriptedAgent("predator_0", rule()), "prey_0": ScriptedAgent("prey_0", FleeingPrey())}

    options = {"wall_rule": "contain"}
    variants = [(team(AlwaysChase if k % 2 else AlwaysStalk), {}) for k in range(MAX_BLOCKS + 3)]
    played = play_variants(
        "1p-high", variants, 3, seed=8, num_envs=2, task_options=options, parts=list(range(len(variants)))
    )
    for k in (0, 1, MAX_BLOCKS + 1, MAX_BLOCKS + 2):
        alone = play_variants("1p-high", [variants[k]], 3, seed=8, num_envs=2, task_options=options)[0]
        np.testing.assert_array_equal(played[k].returns, alone.returns)
        np.testing.assert_array_equal(played[k].lengths, alone.lengths)
    assert not np.array_equal(played[0].returns, played[1].returns)


def test_the_prey_s_outcomes_are_those_of_the_trained_variant_s_episodes() -> None:
    """``outcomes=True`` (the budget study's secondary 6) adds the prey's return, wall exits,
    captures and survival in the trained variant's episodes and changes nothing else; its return
    and captures are the result's own prey return and capture rate, computed apart; together and
    alone give the same."""
    from pursuit_bench.training.evaluate import evaluate_together

    agents = pretrained.load("1p-high")
    plain = evaluate_agents("1p-high", agents, episodes=12, seed=5, num_envs=4, prey_check=False)
    with_outcomes = evaluate_agents("1p-high", agents, episodes=12, seed=5, num_envs=4, prey_check=False, outcomes=True)
    outcomes = with_outcomes.pop("prey_outcomes")
    assert with_outcomes == plain
    assert outcomes["return"] == pytest.approx(plain["mean_return"]["prey_0"], abs=1e-12)
    assert outcomes["captured"] == plain["capture_rate"]
    assert 0 <= outcomes["left_area"] and outcomes["left_area"] + outcomes["captured"] + outcomes["survived"] <= 1
    (together,) = evaluate_together(
        "1p-high", [(agents, 0.1)], episodes=12, seed=5, num_envs=4, prey_check=False, outcomes=True
    )
    assert together["prey_outcomes"] == outcomes
