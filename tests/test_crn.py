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
