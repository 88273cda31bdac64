"""The paper's Fig. 2: each predator's mean cumulative reward, hierarchical against the baselines."""

from __future__ import annotations

import io
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt

BASELINES = (("always_chase", "always chase", "#dd8452"), ("always_stalk", "always stalk", "#55a868"))
TRAINED_COLOR = "#4c72b0"


def reward_bars_png(result: dict[str, Any]) -> bytes:
    """PNG bytes of one panel per predator: three bars (the trained predator, labelled by its
    kind; always chase; always stalk)."""
    panels = result["panels"]
    bars = (("trained", result.get("predator_kind", "trained"), TRAINED_COLOR), *BASELINES)
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels) + 0.8, 3.4), squeeze=False, sharey=True)
    for ax, panel in zip(axes[0], panels, strict=True):
        values = [panel[key] for key, _, _ in bars]
        ax.bar([label for _, label, _ in bars], values, color=[color for _, _, color in bars])
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_title(panel["predator"])
        ax.tick_params(axis="x", labelrotation=20)
        for x, v in enumerate(values):
            ax.annotate(f"{v:.2f}", (x, v), ha="center", va="bottom" if v >= 0 else "top", fontsize=8)
    axes[0][0].set_ylabel("mean cumulative reward")
    fig.suptitle(f"{result['condition']}: {result['episodes']} episodes, seed {result['seed']}")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()
