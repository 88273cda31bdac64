"""``run_episodes`` plays the first episodes to start, each to its end: not the first to finish,
which favour short episodes (an arena that ends a short one starts another, which may end before
a long one elsewhere)."""

import numpy as np
import pytest

from pursuit_bench.agents.kinds import ScriptedAgent
from pursuit_bench.env.vector import VectorPursuitEnv, put_actions
from pursuit_bench.rules.policies import AlwaysStalk, FleeingPrey
from pursuit_bench.training.evaluate import run_episodes

CONDITION, SEED, ARENAS = "1p-high", 3, 8


def actors() -> dict[str, ScriptedAgent]:
    return {"predator_0": ScriptedAgent("predator_0", AlwaysStalk()), "prey_0": ScriptedAgent("prey_0", FleeingPrey())}


def first_to_start(episodes: int) -> list[tuple[float, int]]:
    """The naive reference: step the env, numbering episodes as they start (the arenas' first at
    the reset, then one each time an arena ends one, in arena order), until the first
    ``episodes`` have ended; those as sorted (predator's return, length)."""
    env, playing = VectorPursuitEnv(ARENAS, CONDITION), actors()
    obs, _ = env.reset(seed=SEED)
    number, started = list(range(ARENAS)), ARENAS
    ended: dict[int, tuple[float, int]] = {}
    while len(ended) < episodes:
        actions = np.zeros((ARENAS, env.n_agents, 2), dtype=np.int64)
        for i, name in enumerate(env.agents):
            put_actions(actions, i, np.asarray(playing[name].act_batch(obs[:, i], explore=False, epsilon=None)))
        obs, _, _, _, info = env.step(actions)
        for arena in np.flatnonzero(info["done"]):
            if number[arena] < episodes:
                ended[number[arena]] = (float(info["episode_return"][arena][0]), int(info["episode_length"][arena]))
            number[arena], started = started, started + 1
    return sorted(ended.values())


@pytest.mark.parametrize("episodes", [ARENAS, 2 * ARENAS + 3])
def test_the_episodes_played_are_the_first_to_start_each_to_its_end(episodes: int) -> None:
    reference = first_to_start(episodes)
    lengths = [length for _, length in reference]
    assert max(lengths) > 2 * min(lengths)  # arenas end at different times: the first to *finish* differ
    played = run_episodes(CONDITION, actors(), episodes, seed=SEED, num_envs=ARENAS, epsilons={})
    assert sorted(zip(played.returns[:, 0].tolist(), played.lengths.tolist(), strict=True)) == reference
