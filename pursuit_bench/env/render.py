"""Draw arenas as RGB frames with numpy alone (no window, no pygame)."""

from __future__ import annotations

import numpy as np

from pursuit_bench.env.world import HALF_SIZE, RADIUS

PREDATOR_RGB = (220, 40, 40)
PREY_RGB = (40, 80, 220)
#: One colour per predator (warm hues, told apart from each other and from the blue prey).
PREDATOR_RGBS = ((220, 40, 40), (240, 150, 20), (200, 60, 200))


def agent_rgb(name: str) -> tuple[int, int, int]:
    """An agent's colour: the prey blue, ``predator_k`` the k-th predator colour."""
    if name.startswith("prey"):
        return PREY_RGB
    return PREDATOR_RGBS[int(name.rsplit("_", 1)[-1]) % len(PREDATOR_RGBS)]


def dimmed(rgb: tuple[int, int, int], factor: float = 0.45) -> tuple[int, int, int]:
    """``rgb`` darkened (a predator stalking; bright when it chases)."""
    r, g, b = rgb
    return (int(r * factor), int(g * factor), int(b * factor))


WALL_RGB = (0, 0, 0)
BACKGROUND_RGB = (255, 255, 255)
OBSTACLE_RGB = (120, 120, 120)


def draw_arena(positions: np.ndarray, size: int = 400, obstacles: np.ndarray | None = None) -> np.ndarray:
    """(size, size, 3) uint8 frame of one arena: black square walls, grey obstacles
    (``obstacles`` (K, 3) rows of x, y, radius), predators as red disks and the prey (last agent)
    as a blue disk, drawn at their true radius. ``positions`` (n_agents, 2)."""
    frame = np.empty((size, size, 3), dtype=np.uint8)
    frame[:] = BACKGROUND_RGB
    view = HALF_SIZE * 1.05  # a margin around the walls
    scale = size / (2 * view)
    border = max(2, size // 200)
    lo, hi = round((view - HALF_SIZE) * scale), round((view + HALF_SIZE) * scale)
    frame[lo - border : lo, lo - border : hi + border] = WALL_RGB
    frame[hi : hi + border, lo - border : hi + border] = WALL_RGB
    frame[lo - border : hi + border, lo - border : lo] = WALL_RGB
    frame[lo - border : hi + border, hi : hi + border] = WALL_RGB
    centres = (np.arange(size) + 0.5) / scale - view  # pixel centres in world units
    xs, ys = np.meshgrid(centres, -centres)  # image rows go down, y goes up
    for x, y, radius in np.zeros((0, 3)) if obstacles is None else np.asarray(obstacles):
        frame[(xs - x) ** 2 + (ys - y) ** 2 <= radius**2] = OBSTACLE_RGB
    for i, (x, y) in enumerate(np.asarray(positions)):
        inside = (xs - x) ** 2 + (ys - y) ** 2 <= RADIUS**2
        frame[inside] = PREY_RGB if i == len(positions) - 1 else PREDATOR_RGB
    return frame
