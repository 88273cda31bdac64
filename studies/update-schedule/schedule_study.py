"""The update-schedule study of docs/learning.md (section 7): which schedule learns most per
CPU-second. Each variant is the ``reproduction`` preset with some fields changed; three seeds of
it are trained stacked in one process (one torch thread), and every ``--eval-every`` episodes
each seed's agents are evaluated by the paper's protocol (training paused, its clock stopped):

- predator quality: its mean return minus the better of always-chase and always-stalk in its
  place, the other agents fixed, prey ε = 0.1 (mean over predators);
- prey quality: its return, greedy, minus ``FleeingPrey``'s in its place against the same
  predators on the same seeds, with both their wall exits.

CPU-seconds are the stack's training CPU time divided by its runs: what one run costs stacked
with its seeds. Results go to ``STUDY/results.jsonl``, a row per evaluation; a variant and
condition already in it is skipped, so the command resumes.

    python studies/update-schedule/schedule_study.py run STUDY [--conditions ...] [--variants ...]
    python studies/update-schedule/schedule_study.py figure STUDY docs/figures/schedule.png   # and the table
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch

from pursuit_bench import stats
from pursuit_bench.agents.config import REPRODUCTION
from pursuit_bench.training.evaluate import evaluate_agents
from pursuit_bench.training.train import TrainConfig, Trainer

#: name -> (changes to the reproduction preset, arenas per run[, episodes]); one hypothesis per
#: step away from the reproduction preset (replay ratio alone, then the step size with it, then
#: arenas); the cheapest also trained for longer (the same CPU time buys them more episodes).
VARIANTS: dict[str, tuple[Any, ...]] = {
    "reproduction": ({}, 8),
    "ratio1/4": ({"replay_ratio": 0.25}, 8),
    "ratio1/8": ({"replay_ratio": 0.125}, 8),
    "ratio1/4-lr1e-4": ({"replay_ratio": 0.25, "learning_rate": 1e-4}, 8),
    "ratio1/8-lr1e-4": ({"replay_ratio": 0.125, "learning_rate": 1e-4}, 8),
    "ratio1/8-lr1e-4-b128": ({"replay_ratio": 0.125, "learning_rate": 1e-4, "batch_size": 128}, 8),
    "ratio1/32-lr1e-4-32arenas": ({"replay_ratio": 1 / 32, "learning_rate": 1e-4}, 32),
    "ratio1/8-lr1e-4, 6000 episodes": ({"replay_ratio": 0.125, "learning_rate": 1e-4}, 8, 6000),
    "ratio1/32-lr1e-4-32arenas, 6000 episodes": ({"replay_ratio": 1 / 32, "learning_rate": 1e-4}, 32, 6000),
}
CONDITIONS = ("1p-high", "2p-high-shared", "1p-low")
EVAL_SEED = 54321


def quality(result: dict[str, Any]) -> dict[str, float]:
    panels = result["panels"]
    margin = [p["trained"] - max(p["always_chase"], p["always_stalk"]) for p in panels]
    check = result["prey_check"]
    return {
        "predator_margin": float(np.mean(margin)),
        "predator_return": float(np.mean([p["trained"] for p in panels])),
        "prey_margin": check["learned_greedy"]["return"] - check["fleeing_prey"]["return"],
        "prey_walls": check["learned_greedy"]["left_area"],
        "fleeing_walls": check["fleeing_prey"]["left_area"],
        "capture_rate": result["capture_rate"],
    }


def run_variant(
    out: Path, name: str, condition: str, seeds: int, episodes: int, every: int, eval_episodes: int
) -> None:
    changes, arenas, *longer = VARIANTS[name]
    episodes = longer[0] if longer else episodes
    every = every * episodes // 1500 if longer else every
    agent = REPRODUCTION.replace(**changes)
    configs = [
        TrainConfig(condition=condition, agent=agent, episodes=episodes, num_envs=arenas, seed=s) for s in range(seeds)
    ]
    trainer = Trainer(configs)
    cpu = 0.0
    next_eval = every
    rows = []
    while not trainer.finished:
        start = time.process_time()
        while not trainer.finished and min(r.episodes_done for r in trainer.runs) < next_eval:
            trainer.step()
        cpu += time.process_time() - start
        for seed, run in enumerate(trainer.runs):
            result = evaluate_agents(condition, run.agents, episodes=eval_episodes, seed=EVAL_SEED)  # type: ignore[arg-type]
            rows.append(
                {
                    "variant": name,
                    "condition": condition,
                    "seed": seed,
                    "episodes": run.episodes_done,
                    "transitions": run.env_steps * arenas,
                    "cpu_s": cpu / seeds,
                    **quality(result),
                }
            )
        episodes_done = min(r.episodes_done for r in trainer.runs)
        print(f"{name} {condition}: {episodes_done} episodes, {cpu / seeds:.0f} CPU-s per run", flush=True)
        next_eval += every
    with (out / "results.jsonl").open("a") as f:  # a variant and condition lands whole, or not at all
        f.write("".join(json.dumps(row) + "\n" for row in rows))


def done(out: Path) -> set[tuple[str, str]]:
    path = out / "results.jsonl"
    if not path.exists():
        return set()
    return {(r["variant"], r["condition"]) for r in map(json.loads, path.read_text().splitlines())}


def figure(out: Path, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    conditions = [c for c in CONDITIONS if any(r["condition"] == c for r in rows)]
    fig, axes = plt.subplots(2, len(conditions), figsize=(4.2 * len(conditions), 6.4), squeeze=False)
    print(
        "| condition | variant | CPU-s per run (final) | predator margin, final [95 % t-interval, 3 seeds] |"
        " prey margin, final [95 % t-interval] | CPU-s to the reproduction preset's final quality |"
    )
    print("|---|---|---:|---:|---:|---:|")
    for c, condition in enumerate(conditions):
        ref = _final(rows, "reproduction", condition)
        for v, name in enumerate(VARIANTS):
            mine = [r for r in rows if r["variant"] == name and r["condition"] == condition]
            if not mine:
                continue
            seeds = sorted({r["seed"] for r in mine})
            for row_ax, key in enumerate(("predator_margin", "prey_margin")):
                x, y = _curve(mine, seeds, key)
                ax = axes[row_ax][c]
                ax.plot(x, y.mean(axis=0), color=f"C{v}", label=name)
                ax.fill_between(x, y.min(axis=0), y.max(axis=0), color=f"C{v}", alpha=0.15, linewidth=0)
                ax.set_xscale("log")
                ax.set_title(f"{condition}: {key.replace('_', ' ')}", fontsize=9)
                ax.set_xlabel("training CPU-seconds per run (one thread)")
                ax.axhline(0, color="grey", linewidth=0.5)
            final = _final(rows, name, condition)
            reached = _time_to(mine, seeds, ref) if ref is not None else None
            spans = {k: _span(_final_values(rows, name, condition, k)) for k in ("predator_margin", "prey_margin")}
            predator = f"{final['predator_margin']:+.3f}{spans['predator_margin']}"
            prey = f"{final['prey_margin']:+.3f}{spans['prey_margin']}"
            reached_text = reached if reached is not None else "not reached"
            print(f"| {condition} | {name} | {final['cpu_s']:.0f} | {predator} | {prey} | {reached_text} |")
    shown: dict[str, Any] = {}
    for ax in axes.ravel():
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            shown.setdefault(label, handle)
    fig.legend(list(shown.values()), list(shown), fontsize=7, loc="lower center", ncol=4)
    fig.suptitle("Quality against CPU time: mean of 3 seeds, band = their range", fontsize=10)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(png, dpi=110)


def _curve(rows: list[dict[str, Any]], seeds: list[int], key: str) -> tuple[np.ndarray, np.ndarray]:
    per_seed = [sorted((r for r in rows if r["seed"] == s), key=lambda r: r["episodes"]) for s in seeds]
    n = min(len(p) for p in per_seed)
    x = np.array([p["cpu_s"] for p in per_seed[0][:n]])
    return x, np.array([[p[key] for p in s[:n]] for s in per_seed])


def _final(rows: list[dict[str, Any]], name: str, condition: str) -> dict[str, float] | None:
    mine = [r for r in rows if r["variant"] == name and r["condition"] == condition]
    if not mine:
        return None
    last = max(r["episodes"] for r in mine)
    at_end = [r for r in mine if r["episodes"] == last]
    return {k: float(np.mean([r[k] for r in at_end])) for k in ("cpu_s", "predator_margin", "prey_margin")}


def _final_values(rows: list[dict[str, Any]], name: str, condition: str, key: str) -> list[float]:
    """Each seed's ``key`` at the variant's last evaluation."""
    mine = [r for r in rows if r["variant"] == name and r["condition"] == condition]
    last = max(r["episodes"] for r in mine)
    return [r[key] for r in mine if r["episodes"] == last]


def _span(values: list[float]) -> str:
    """The seeds' t-interval (pursuit_bench.stats), as the table prints it."""
    ci = stats.t_interval(values)
    return f" [{ci[0]:+.2f}, {ci[1]:+.2f}]" if ci else ""


def _time_to(rows: list[dict[str, Any]], seeds: list[int], ref: dict[str, float]) -> str | None:
    """CPU-seconds per run at the first evaluation where the seeds' mean predator margin and
    prey margin both reach the reproduction preset's final means."""
    x, pred = _curve(rows, seeds, "predator_margin")
    _, prey = _curve(rows, seeds, "prey_margin")
    for t, p, q in zip(x, pred.mean(axis=0), prey.mean(axis=0), strict=True):
        if p >= ref["predator_margin"] and q >= ref["prey_margin"]:
            return f"{t:.0f}"
    return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("study", type=Path)
    run.add_argument("--conditions", nargs="+", default=list(CONDITIONS))
    run.add_argument("--variants", nargs="+", default=list(VARIANTS))
    run.add_argument("--seeds", type=int, default=3)
    run.add_argument("--episodes", type=int, default=1500)
    run.add_argument("--eval-every", type=int, default=300)
    run.add_argument("--eval-episodes", type=int, default=100)
    fig = sub.add_parser("figure")
    fig.add_argument("study", type=Path)
    fig.add_argument("png", type=Path)
    args = parser.parse_args()
    if args.command == "figure":
        figure(args.study, args.png)
        return
    torch.set_num_threads(1)
    args.study.mkdir(parents=True, exist_ok=True)
    for condition in args.conditions:
        for name in args.variants:
            if (name, condition) not in done(args.study):
                run_variant(args.study, name, condition, args.seeds, args.episodes, args.eval_every, args.eval_episodes)


if __name__ == "__main__":
    main()
