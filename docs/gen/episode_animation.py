"""The environment card's animation: one episode drawn by the env itself (``render_mode="rgb_array"``),
scripted agents, a caption strip under each frame naming the step and each predator's mode.

The predators stalk by parallel navigation until the prey is within ``CHASE_WITHIN``, then
chase (the hierarchical predator's two modes, switched by a fixed distance instead of a
network); the prey is ``FleeingPrey``. The env's seed fixes the start, so the episode repeats.

    python docs/gen/episode_animation.py    # docs/figures/env-episode.gif (about 100 kB)
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

import pursuit_bench
from pursuit_bench.env.render import PREDATOR_RGB, dimmed
from pursuit_bench.env.task import MODE_NAMES
from pursuit_bench.io.files import atomic_write_bytes
from pursuit_bench.rules.policies import AlwaysChase, AlwaysStalk, FleeingPrey

ROOT = Path(__file__).resolve().parents[2]
ANIMATION = ROOT / "docs" / "figures" / "env-episode.gif"
CONDITION, SEED = "2p-high-shared", 2
#: A predator chases once the prey is this close (world units; the arena is 2 across).
CHASE_WITHIN = 0.35
#: Every frame shown, at the env's own rate (render_fps).
SIZE, STRIP = 320, 44


def scripted_action(name: str, observation: np.ndarray) -> np.ndarray | int:
    """Stalk far from the prey, chase near it (predators); flee (the prey)."""
    if name.startswith("prey"):
        return FleeingPrey().act(observation)
    distance = float(np.hypot(observation[6], observation[7]))  # the prey, relative to self
    return (AlwaysChase() if distance < CHASE_WITHIN else AlwaysStalk()).act(observation)


def play() -> tuple[list[np.ndarray], list[dict[str, int]], str]:
    """The env's frames, each predator's mode per frame (-1 at the start) and how it ended."""
    env = pursuit_bench.parallel_env(CONDITION, render_mode="rgb_array")
    obs, infos = env.reset(seed=SEED)
    predators = [a for a in env.possible_agents if a.startswith("predator")]
    frames = [env.render()]
    modes = [{a: -1 for a in predators}]
    ending = "time limit"
    while env.agents:
        obs, _, terminated, _, infos = env.step({a: scripted_action(a, obs[a]) for a in env.agents})
        frames.append(env.render())
        modes.append({a: int(infos[a]["mode"]) for a in predators})
        if any(terminated.values()):
            ending = "caught" if infos["prey_0"]["captured"] else "an agent left the arena"
    env.close()
    return [f for f in frames if f is not None], modes, ending


def captioned(
    frame: np.ndarray, step: int, modes: dict[str, int], font: ImageFont.ImageFont | ImageFont.FreeTypeFont
) -> Image.Image:
    """The env's frame, scaled to SIZE, over a strip: the step, then each predator's mode in the
    env's predator red, bright while it chases and dark while it stalks (the env draws every
    predator alike)."""
    image = Image.new("RGB", (SIZE, SIZE + STRIP), "white")
    image.paste(Image.fromarray(frame).resize((SIZE, SIZE), Image.Resampling.LANCZOS), (0, 0))
    draw = ImageDraw.Draw(image)
    draw.text((8, SIZE + 4), f"{CONDITION}  step {step:3d}", fill=(0, 0, 0), font=font)
    x = 8
    for name, mode in modes.items():
        rgb = PREDATOR_RGB if mode == 1 else dimmed(PREDATOR_RGB)
        label = f"{name}: {MODE_NAMES[mode] if mode >= 0 else 'start'}"
        draw.rectangle((x, SIZE + 26, x + 10, SIZE + 36), fill=rgb)
        draw.text((x + 14, SIZE + 24), label, fill=rgb, font=font)
        x += 14 + int(draw.textlength(label, font=font)) + 16
    return image


def main() -> None:
    frames, modes, ending = play()
    font = ImageFont.load_default(size=13)
    images = [captioned(f, t, m, font) for t, (f, m) in enumerate(zip(frames, modes, strict=True))]
    palette = [im.quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE) for im in images]
    fps = pursuit_bench.PursuitParallelEnv.metadata["render_fps"]
    buffer = io.BytesIO()
    palette[0].save(
        buffer, format="GIF", save_all=True, append_images=palette[1:], duration=1000 // fps, loop=0, optimize=True
    )
    atomic_write_bytes(ANIMATION, buffer.getvalue())
    print(f"{ANIMATION}: {len(frames) - 1} steps, {ending}, {len(buffer.getvalue()) / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
