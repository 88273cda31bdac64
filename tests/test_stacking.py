"""Many runs trained as one: a run's result does not depend on its companions."""

import numpy as np
import pytest
import torch

from pursuit_bench.agents.config import QUICK
from pursuit_bench.training.train import EpisodeRecord, TrainConfig, Trainer

AGENT = QUICK.replace(learning_starts=64, batch_size=16, target_update_every=100)


def config(condition: str, seed: int, episodes: int = 24, **options) -> TrainConfig:
    return TrainConfig(condition=condition, agent=AGENT, episodes=episodes, num_envs=4, seed=seed, **options)


def train(configs: list[TrainConfig]) -> tuple[Trainer, list[list[dict]]]:
    rows: list[list[dict]] = [[] for _ in configs]

    def recorder_of(r: int):
        return lambda record: rows[r].append(record.as_row())

    trainer = Trainer(configs, [recorder_of(r) for r in range(len(configs))])
    trainer.run()
    return trainer, rows


def weights(trainer: Trainer, run: int) -> dict[str, dict[str, torch.Tensor]]:
    return {name: agent["learner"]["online"] for name, agent in trainer.state_dict(run)["agents"].items()}


pytestmark = pytest.mark.usefixtures("one_thread")


@pytest.mark.parametrize("condition", ["1p-high", "2p-low-individual"])
def test_a_run_alone_equals_the_same_run_in_a_stack(condition: str) -> None:
    other = "1p-low" if condition.startswith("1p") else "2p-high-shared"
    alone, (alone_rows,) = train([config(condition, 3)])
    configs = [config(condition, 7, episodes=30), config(other, 1), config(condition, 3)]
    fresh = Trainer(configs)
    assert len(fresh.groups) == 2 and fresh.groups[0].learner.members == 3 * (len(fresh.runs[0].names) - 1)
    stack, stack_rows = train(configs)
    assert alone_rows == stack_rows[2] and len(alone_rows) == 24
    assert alone.agents["predator_0"].learner.updates > 0
    mine, theirs = weights(alone, 0), weights(stack, 2)
    for name in mine:
        for key, value in mine[name].items():
            assert torch.equal(value, theirs[name][key]), (name, key)
    assert stack_rows[0] != stack_rows[2][: len(stack_rows[0])]  # other seeds learn otherwise


def test_separate_learners_give_the_same_run_as_stacked_ones() -> None:
    _, (stacked,) = train([config("3p-high-shared", 2)])
    _, (separate,) = train([config("3p-high-shared", 2, batched_learners=False)])
    assert stacked == separate


def test_a_finished_run_stops_while_its_companions_go_on() -> None:
    short, long = config("1p-low", 0, episodes=5), config("1p-low", 1, episodes=20)
    counts = {0: 0, 1: 0}

    def count(r: int):
        def on_episode(record: EpisodeRecord) -> None:
            counts[r] += 1

        return on_episode

    trainer = Trainer([short, long], [count(0), count(1)])
    while not trainer.runs[0].finished:
        trainer.step()
    frozen = trainer.state_dict(0)
    trainer.run()
    assert counts == {0: 5, 1: 20} and trainer.runs[0].episodes_done == 5
    after = trainer.state_dict(0)
    assert after["episodes_done"] == frozen["episodes_done"] and after["env_steps"] == frozen["env_steps"]
    for name, agent in frozen["agents"].items():
        for key, value in agent["learner"]["online"].items():
            assert torch.equal(value, after["agents"][name]["learner"]["online"][key])


def test_runs_resumed_at_different_steps_cannot_share_a_stack() -> None:
    a = Trainer(config("1p-low", 0, episodes=3))
    a.run()
    stack = Trainer([config("1p-low", 0, episodes=30), config("1p-low", 1, episodes=30)])
    stack.load_state_dict(a.state_dict(), run=0)
    with pytest.raises(ValueError, match="same env step"):
        stack.check_lockstep()
    assert np.isfinite(a.runs[0].obs).all()


def test_finished_runs_leave_the_stack_without_changing_anyone() -> None:
    """A run's metrics and weights are the same alone, beside companions that finish before it
    and beside ones that finish after it; finished runs' members leave the stacked learners."""
    alone, (alone_rows,) = train([config("2p-low-individual", 5, episodes=20)])
    early = [config("2p-low-individual", 8, episodes=6), config("2p-low-individual", 5, episodes=20)]
    late = [config("2p-low-individual", 5, episodes=20), config("2p-low-individual", 9, episodes=40)]
    trainer = Trainer(early)
    sizes = set()
    while not trainer.finished:
        trainer.step()
        sizes.add(tuple(g.learner.members for g in trainer.groups))
    assert (4, 2) in sizes and (2, 1) in sizes  # 2 predators + a prey per run, then one run left
    assert trainer.groups == [] and trainer.runs[0].episodes_done == 6
    for stack, place in ((early, 1), (late, 0)):
        finished, rows = train(stack)
        assert rows[place] == alone_rows
        mine, theirs = weights(alone, 0), weights(finished, place)
        for name in mine:
            for key, value in mine[name].items():
                assert torch.equal(value, theirs[name][key]), (stack, name, key)
        obs = finished.runs[place].obs[:, 0]  # a finished run's agents still act, from their final weights
        np.testing.assert_array_equal(
            finished.runs[place].agents["predator_0"].act_batch(obs), alone.agents["predator_0"].act_batch(obs)
        )


def test_rows_of_different_shapes_or_types_are_not_stacked() -> None:
    from pursuit_bench.training.train import _stacked

    rows = np.arange(6.0).reshape(3, 2)
    np.testing.assert_array_equal(_stacked([rows, rows + 1]), np.stack([rows, rows + 1]))
    assert np.shares_memory(_stacked([rows]), rows)  # a run alone: a view, no copy
    for other in (rows[:1], rows.astype(np.float32)):
        with pytest.raises(ValueError, match="one shape and type"):
            _stacked([rows, other])


def test_a_groups_rows_are_the_members_rows_stacked() -> None:
    """``Group.rows``: one slice of a run's agents as a view, other members through ``_stacked``;
    the values of ``np.stack`` of each member's rows either way."""
    from pursuit_bench.training.train import Group

    arrays = [np.arange(5 * 4 * 3.0).reshape(5, 4, 3), -np.arange(5 * 4 * 3.0).reshape(5, 4, 3)]
    for runs, indices, sliced in (([0, 0, 0], [0, 1, 2], True), ([1], [3], True), ([0, 1], [2, 2], False)):
        group = Group(None, [], indices, runs)  # type: ignore[arg-type]  # rows needs no learner
        expected = np.stack([arrays[r][:, i] for r, i in zip(runs, indices, strict=True)])
        np.testing.assert_array_equal(group.rows(arrays), expected)
        assert (group.span is not None) == sliced == np.shares_memory(group.rows(arrays), arrays[runs[0]])
    assert Group(None, [], [2, 1], [0, 0]).span is None  # type: ignore[arg-type]  # not in order: stacked


def test_a_groups_actions_go_to_each_members_place() -> None:
    """``Group.put``: members' (mode, direction) pairs or directions land at their run and agent,
    in one assignment for a slice of a run's agents, one by one otherwise."""
    from pursuit_bench.training.train import Group

    rng = np.random.default_rng(0)
    for runs, indices in (([0, 0, 0], [0, 1, 2]), ([1], [3]), ([0, 1], [2, 2])):
        group = Group(None, [], indices, runs)  # type: ignore[arg-type]  # put needs no learner
        for pairs in (True, False):
            shape = (len(runs), 5, 2) if pairs else (len(runs), 5)
            env_actions = rng.integers(0, 12, shape)
            actions = {0: np.full((5, 4, 2), -1), 1: np.full((5, 4, 2), -1)}
            expected = {r: a.copy() for r, a in actions.items()}
            for m, (r, i) in enumerate(zip(runs, indices, strict=True)):
                expected[r][:, i, slice(None) if pairs else 1] = env_actions[m]
            group.put(actions, env_actions)
            for r in actions:
                np.testing.assert_array_equal(actions[r], expected[r])
            group.put(actions, list(env_actions))  # a list of members' actions: one by one, the same
            for r in actions:
                np.testing.assert_array_equal(actions[r], expected[r])
