"""The documentation site's MkDocs hooks (``mkdocs.yml``: ``hooks: [docs/hooks.py]``).

What the site generates from the code at build time rather than retyping it:

- links in the files included from the repository's root (README.md, REPRODUCTION.md,
  CHANGELOG.md, recordings/README.md) that point at one another are pointed at the pages that
  include them (``mkdocs-include-markdown-plugin`` has already rewritten links into docs/);
- the environment card's tables (``<!-- docs_site: NAME -->`` markers in a page): the conditions
  from ``pursuit_bench.CONDITIONS``, every agent's spaces from the env itself, the dynamics'
  constants with the ``#:`` comments above them in the source, the versions;
- the episode page's recording: one episode of the shipped agents played now through
  ``RecordEpisodes`` into ``site/assets/rerun/episode.rrd``, beside Rerun's web viewer
  (``widget.js`` and ``re_viewer_bg.wasm`` from the ``rerun-notebook`` package, the version of
  the installed ``rerun-sdk`` that writes the recording; the build fails if they differ);
- in the API reference, the docstrings' Sphinx roles (``:class:`…```) shown as plain code.

    .venv/bin/mkdocs build --strict    # site/
    .venv/bin/mkdocs serve             # http://127.0.0.1:8000
"""

from __future__ import annotations

import ast
import importlib
import importlib.metadata
import importlib.util
import posixpath
import re
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
#: Files of the repository's root included by a page, and that page (under docs/).
INCLUDED: dict[str, str] = {
    "README.md": "index.md",
    "REPRODUCTION.md": "reproduction.md",
    "CHANGELOG.md": "changelog.md",
    "recordings/README.md": "recordings.md",
}
#: The episode in the browser: the shipped agents of this condition, this evaluation seed (the
#: README's picture is the same episode).
EPISODE_CONDITION, EPISODE_SEED = "2p-high-individual", 7
#: Where the viewer and the recording go in the built site.
RERUN_ASSETS = "assets/rerun"
MARKER = re.compile(r"<!-- docs_site: ([a-z-]+) -->")
LINK = re.compile(r"(\]\()([^)\s#]+)(#[^)\s]*)?(\))")
ROLE = re.compile(r":(class|func|meth|attr|data|mod|obj|exc|const):<code>([^<]+)</code>")


# ---------------------------------------------------------------- links of the included files


def page_for(target: str, page_src: str) -> str | None:
    """The link to write for ``target`` (a relative link in page ``page_src``, a path under
    docs/) if it points at a root file that a page includes; None otherwise."""
    resolved = posixpath.normpath(posixpath.join("docs", posixpath.dirname(page_src), target))
    if resolved not in INCLUDED:
        return None
    return posixpath.relpath(INCLUDED[resolved], posixpath.dirname(page_src) or ".")


def relink(markdown: str, page_src: str) -> str:
    """``markdown`` with every link to an included root file pointed at the page that includes it."""

    def swap(match: re.Match[str]) -> str:
        target = match.group(2)
        if "://" in target or target.startswith("mailto:"):
            return match.group(0)
        page = page_for(target, page_src)
        if page is None:
            return match.group(0)
        return f"{match.group(1)}{page}{match.group(3) or ''}{match.group(4)}"

    return LINK.sub(swap, markdown)


# ---------------------------------------------------------------- the environment card


def table(header: Iterable[str], rows: Iterable[Iterable[object]]) -> str:
    """A Markdown table."""
    header = list(header)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def space_text(space: Any) -> str:
    """A space as the card shows it: Box by shape and dtype (its bounds are tabled apart)."""
    from gymnasium import spaces

    if isinstance(space, spaces.Box):
        return f"`Box({space.shape}, {space.dtype})`"
    if isinstance(space, spaces.MultiDiscrete):
        return f"`MultiDiscrete({space.nvec.tolist()})`"
    return f"`{space}`"


def conditions_table() -> str:
    """The paper's ten conditions, each with its agents and observation size as the env builds them."""
    import pursuit_bench
    from pursuit_bench import pretrained

    shipped = set(pretrained.available())
    rows = []
    for name, config in pursuit_bench.CONDITIONS.items():
        env = pursuit_bench.parallel_env(name)
        rows.append(
            [
                f"`{name}`",
                config.n_predators,
                config.chase_cost,
                config.reward_sharing if config.n_predators > 1 else "–",
                ", ".join(env.possible_agents),
                f"`{env.observation_space(env.possible_agents[-1]).shape}`",
                "yes" if name in shipped else "no",
            ]
        )
    header = ["condition", "predators", "chase cost", "reward sharing", "agents", "observation", "shipped agents"]
    return table(header, rows)


def variants_table() -> str:
    """How the options change a predator's and the prey's spaces (2p-high-shared)."""
    import pursuit_bench

    variants: list[tuple[str, dict[str, Any]]] = [
        ("the paper's task", {}),
        ("`continuous=True`", {"continuous": True}),
        ("`obstacles=3`", {"obstacles": 3}),
    ]
    rows = []
    for label, options in variants:
        env = pursuit_bench.parallel_env("2p-high-shared", **options)
        predator, prey = env.possible_agents[0], env.possible_agents[-1]
        rows.append(
            [
                label,
                space_text(env.observation_space(predator)),
                space_text(env.action_space(predator)),
                space_text(env.action_space(prey)),
            ]
        )
    return table(["2p-high-shared with", "observation", "predator action", "prey action"], rows)


def bounds_table() -> str:
    """The observation space's bounds (1p-high), consecutive indices with equal bounds together."""
    from gymnasium import spaces

    import pursuit_bench

    space = pursuit_bench.parallel_env("1p-high").observation_space("predator_0")
    assert isinstance(space, spaces.Box)
    groups: list[list[Any]] = []
    for i, bounds in enumerate(zip(space.low.tolist(), space.high.tolist(), strict=True)):
        if groups and groups[-1][1] == bounds:
            groups[-1][0].append(i)
        else:
            groups.append([[i], bounds])
    rows = [[f"{i[0]}–{i[-1]}" if len(i) > 1 else i[0], f"{lo:g}", f"{hi:g}"] for i, (lo, hi) in groups]
    return table(["indices", "low", "high"], rows)


def documented_constants(module_name: str, names: Iterable[str]) -> list[tuple[str, object, str]]:
    """(name, value, comment) of module-level constants, the comment being the ``#:`` lines
    just above the assignment in the module's source."""
    module = importlib.import_module(module_name)
    source = Path(module.__file__ or "").read_text()
    lines = source.splitlines()
    comments: dict[str, str] = {}
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            target = node.targets[0]
        elif isinstance(node, ast.AnnAssign):
            target = node.target
        else:
            continue
        if not isinstance(target, ast.Name):
            continue
        above: list[str] = []
        row = node.lineno - 2
        while row >= 0 and lines[row].lstrip().startswith("#:"):
            above.insert(0, lines[row].lstrip()[2:].strip())
            row -= 1
        comments[target.id] = " ".join(above)
    return [(name, getattr(module, name), comments.get(name, "")) for name in names]


def dynamics_table() -> str:
    """The physics and the task's numbers, read from the modules that set them."""
    rows = documented_constants("pursuit_bench.env.world", ["DT", "DAMPING", "RADIUS", "MASS", "HALF_SIZE"])
    rows += documented_constants(
        "pursuit_bench.env.task", ["N_DIRECTIONS", "ACCEL_PREY", "ACCEL_CHASE", "ACCEL_STALK", "START_HALF_SIZE"]
    )
    rows += documented_constants("pursuit_bench.env.conditions", ["CHASE_COSTS", "MAX_STEPS"])
    module_of = {"DT": "world", "N_DIRECTIONS": "task", "CHASE_COSTS": "conditions"}
    out, module = [], "world"
    for name, value, comment in rows:
        module = module_of.get(name, module)
        out.append([f"`{name}`", f"`{value}`", comment.replace("|", "\\|"), f"`pursuit_bench.env.{module}`"])
    return table(["constant", "value", "meaning", "set in"], out)


def versions_table() -> str:
    """The ids a result names, and the versions of what it ran on."""
    import gymnasium

    import pursuit_bench
    from pursuit_bench.env.pettingzoo_env import PursuitParallelEnv

    spec = gymnasium.spec("pursuit_bench/Pursuit-v0")
    rows = [
        ["Gymnasium id", f"`{spec.id}` (version {spec.version})"],
        [
            "PettingZoo module",
            f"`pursuit_bench.{PursuitParallelEnv.metadata['name']}` (`env()`, `parallel_env()`, `raw_env`)",
        ],
        ["render modes", ", ".join(f"`{m}`" for m in PursuitParallelEnv.metadata["render_modes"])],
        ["frames per second", PursuitParallelEnv.metadata["render_fps"]],
        ["package", f"pursuit-bench {pursuit_bench.__version__}"],
    ]
    rows += [[name, importlib.metadata.version(name)] for name in ("gymnasium", "pettingzoo", "pymunk", "rerun-sdk")]
    return table(["what", "version"], rows)


def rerun_versions() -> str:
    """The versions of the recording's writer and of the viewer that shows it (equal)."""
    writer, viewer = viewer_versions()
    return f"The recording is written by `rerun-sdk` {writer} and shown by Rerun's web viewer {viewer}"


GENERATED: dict[str, Callable[[], str]] = {
    "conditions": conditions_table,
    "variants": variants_table,
    "bounds": bounds_table,
    "dynamics": dynamics_table,
    "versions": versions_table,
    "rerun-versions": rerun_versions,
}


def fill(markdown: str) -> str:
    """``markdown`` with every ``<!-- docs_site: NAME -->`` replaced by what ``GENERATED[NAME]`` makes."""

    def made(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in GENERATED:
            raise ValueError(f"unknown generated block {name!r}: expected one of {', '.join(GENERATED)}")
        return GENERATED[name]()

    return MARKER.sub(made, markdown)


# ---------------------------------------------------------------- the episode in the browser


def viewer_versions() -> tuple[str, str]:
    """(rerun-sdk's version, rerun-notebook's): the recording's writer and the web viewer."""
    try:
        viewer = importlib.metadata.version("rerun-notebook")
    except importlib.metadata.PackageNotFoundError:
        raise RuntimeError(
            "Rerun's web viewer is missing: install the docs extra (pip install -e '.[docs]', "
            "or bash scripts/install.sh test,docs)"
        ) from None
    return importlib.metadata.version("rerun-sdk"), viewer


def record_episode(path: Path) -> None:
    """One episode of the shipped agents of ``EPISODE_CONDITION``, greedy, into ``path``, with
    the predators' Q-values for stalk and chase and V(s) at every step (the viewer's Q-values panel)."""
    import numpy as np

    import pursuit_bench
    from pursuit_bench import pretrained
    from pursuit_bench.agents import HierarchicalPredator
    from pursuit_bench.trajectories.recording import RecordEpisodes

    agents = pretrained.load(EPISODE_CONDITION)
    env = RecordEpisodes(pursuit_bench.parallel_env(EPISODE_CONDITION), path)
    predators = [a for a in env.possible_agents if isinstance(agents[a], HierarchicalPredator)]
    assert len(predators) == len(env.possible_agents) - 1, "the episode's predators are hierarchical"
    obs, _ = env.reset(seed=EPISODE_SEED)
    while env.agents:
        q_values, values = np.zeros((len(predators), 2)), np.zeros(len(predators))
        for i, name in enumerate(predators):
            agent = agents[name]
            assert isinstance(agent, HierarchicalPredator)
            _, _, q, v = agent.decide(np.asarray(obs[name])[None], explore=False)
            q_values[i], values[i] = agent.mode_q(q)[0], v[0]
        actions = {a: agents[a].act(obs[a]) for a in env.agents}
        obs, *_ = env.step(actions, q_values=q_values, values=values)
    env.close()


def write_viewer(site: Path) -> None:
    """Rerun's web viewer and the recording into ``site/assets/rerun/``."""
    writer, viewer = viewer_versions()
    if writer != viewer:
        raise RuntimeError(
            f"rerun-sdk {writer} writes the recording but the web viewer is {viewer}: install equal versions"
        )
    spec = importlib.util.find_spec("rerun_notebook")
    assert spec is not None and spec.origin is not None
    static = Path(spec.origin).parent / "static"
    out = site / RERUN_ASSETS
    out.mkdir(parents=True, exist_ok=True)
    for name in ("widget.js", "re_viewer_bg.wasm"):
        shutil.copyfile(static / name, out / name)
    record_episode(out / "episode.rrd")


# ---------------------------------------------------------------- MkDocs events


def sphinx_roles(html: str) -> str:
    """The docstrings' Sphinx roles (``:class:`~a.b.C```, rendered as ``:class:<code>~a.b.C</code>``)
    shown as code alone, a leading ``~`` keeping the last name as Sphinx does."""

    def plain(match: re.Match[str]) -> str:
        name = match.group(2)
        return f"<code>{name[1:].rsplit('.', 1)[-1] if name.startswith('~') else name}</code>"

    return ROLE.sub(plain, html)


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    return fill(relink(markdown, page.file.src_uri))


def on_page_content(html: str, page: Any, config: Any, files: Any) -> str:
    return sphinx_roles(html)


def on_post_build(config: Any) -> None:
    write_viewer(Path(config["site_dir"]))
