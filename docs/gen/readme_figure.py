"""The README's picture: one episode of the shipped 2p-high-individual agents, as the env plays it
(PettingZoo's parallel env, the agents greedy), each predator's path dark where it stalks and
bright where it chases, beside the paper's question.

    python docs/gen/readme_figure.py    # docs/figures/episode.png
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import pursuit_bench
from pursuit_bench import pretrained
from pursuit_bench.env.render import agent_rgb, dimmed
from pursuit_bench.env.world import HALF_SIZE
from pursuit_bench.io.files import atomic_write_bytes

ROOT = Path(__file__).resolve().parents[2]
FIGURE = ROOT / "docs" / "figures" / "episode.png"
CONDITION, SEED = "2p-high-individual", 7


def play() -> tuple[np.ndarray, dict[str, list[int]], bool]:
    """Positions (steps + 1, agents, 2), each predator's mode per step, and whether it ended in a capture."""
    agents = pretrained.load(CONDITION)
    env = pursuit_bench.parallel_env(CONDITION)
    obs, _ = env.reset(seed=SEED)
    positions = [env.state()[: 4 * env.max_num_agents].reshape(-1, 4)[:, :2].copy()]
    modes: dict[str, list[int]] = {a: [] for a in env.possible_agents if a != "prey_0"}
    captured = False
    while env.agents:
        actions = {a: agents[a].act(obs[a]) for a in env.agents}
        for a in modes:
            modes[a].append(int(actions[a][0]))
        obs, _, _, _, infos = env.step(actions)
        positions.append(env.state()[: 4 * env.max_num_agents].reshape(-1, 4)[:, :2].copy())
        captured = captured or any(i.get("captured", False) for i in infos.values())
    return np.array(positions), modes, captured


def main() -> None:
    positions, modes, captured = play()
    names = [*modes, "prey_0"]
    fig, ax = plt.subplots(figsize=(5.2, 5.6))
    ax.add_patch(plt.Rectangle((-HALF_SIZE, -HALF_SIZE), 2 * HALF_SIZE, 2 * HALF_SIZE, fill=False, lw=2))
    for i, name in enumerate(names):
        path = positions[:, i]
        if name == "prey_0":
            ax.plot(*path.T, color=np.array(agent_rgb(name)) / 255, lw=1.5, label="prey (learned)")
        else:
            for t, mode in enumerate(modes[name]):
                rgb = agent_rgb(name) if mode == 1 else dimmed(agent_rgb(name))
                ax.plot(*path[t : t + 2].T, color=np.array(rgb) / 255, lw=3.0 if mode == 1 else 1.5)
            ax.plot([], [], color=np.array(agent_rgb(name)) / 255, lw=3, label=f"{name}: bright chase, dark stalk")
        ax.scatter(*path[0], color=np.array(agent_rgb(name)) / 255, marker="o", s=30, zorder=3)
        ax.scatter(*path[-1], color=np.array(agent_rgb(name)) / 255, marker="X", s=60, zorder=3)
    ax.set_xlim(-HALF_SIZE * 1.05, HALF_SIZE * 1.05)
    ax.set_ylim(-HALF_SIZE * 1.05, HALF_SIZE * 1.05)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.02), ncol=1, frameon=False)
    end = "caught" if captured else "not caught"
    ax.set_title(
        f"{CONDITION}, shipped agents, one episode ({len(positions) - 1} steps, prey {end})\n"
        "the network picks how hard (stalk or chase), parallel navigation where;\n"
        "o start, x end",
        fontsize=8,
    )
    fig.tight_layout()
    import io

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    atomic_write_bytes(FIGURE, buffer.getvalue())
    print(f"{FIGURE}: {len(positions) - 1} steps, {end}")


if __name__ == "__main__":
    main()
