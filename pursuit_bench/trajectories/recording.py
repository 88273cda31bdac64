"""Rerun recordings: every trajectory, mode switch and reward in an ``.rrd`` file that opens
ready to read. The one module that knows Rerun; loops hand it arrays per episode.

Timelines: ``episode`` (sequence), ``step`` (sequence within the episode) and ``sim_time``
(duration, dt = 0.1 s per step): a playback clock that runs on across the recorded episodes, so
that scrubbing it plays them one after another (the file opens on it).

Entities (``recordings/README.md`` says the same for users):

- ``arena/walls``: the arena's square (static); ``arena/obstacles``: the episode's obstacles as
  grey disks (logged at its first step; they stand still); ``arena/agents/<agent>``: each disk at its true
  radius, each predator its own warm colour (bright and larger while it chases, dark while it stalks),
  the prey blue; ``arena/trails/<agent>``: the last 15 positions.
- ``modes/<predator>``: the mode as a state (stalk/chase), logged at every switch.
- ``rewards/<agent>``: the reward of each step; ``returns/<agent>``: the return so far.
- ``events``: captures, agents leaving the area, truncations and mode switches, as a text log.
- ``values/<predator>/q_stalk``, ``q_chase`` and ``v``: a trained predator's Q-values and V(s).
- ``training/…``: per-episode training metrics on the ``episode`` timeline.
- ``config``: the condition and the resolved configuration (static text).

Recording is opt-in: a loop without a :class:`Recorder` makes no Rerun call at all. The
PettingZoo env records through the :class:`RecordEpisodes` wrapper.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import pyarrow as pa
import rerun as rr
import rerun.blueprint as rrb
from pettingzoo.utils.wrappers import BaseParallelWrapper

from pursuit_bench.env.render import agent_rgb, dimmed
from pursuit_bench.env.task import MODE_NAMES
from pursuit_bench.env.world import DT, HALF_SIZE, RADIUS

#: Default folder for ad-hoc recordings.
RECORDINGS_DIR = Path("recordings")
TRAIL_LENGTH = 15
#: A chasing predator's disk is drawn this much larger than its true radius (and bright).
CHASE_RADIUS = 1.6 * RADIUS
#: Walls in light grey: the viewer's background is dark (the paper's black square would vanish).
WALL_RGB = (200, 200, 200)
OBSTACLE_RGB = (140, 140, 140)
#: The reward, mode and value views show this much time up to the cursor: about one episode.
WINDOW_SECONDS = 30.0
APPLICATION_ID = "pursuit_bench"
_METRICS_FLUSH_EVERY = 50
#: Recorded episodes are queued and sent together (Rerun's cost is per call, not per row).
EPISODES_PER_SEND = 200
#: Trails go out in chunks of this many rows. Rerun's cost of a nested-list column grows with
#: rows × chunk rows: one 5,000-row chunk per send made `rerun rrd verify` of a 1000-episode
#: evaluation take 28 s here; 64-row chunks take 0.5 s (and the file grows ~20 %).
TRAIL_ROWS_PER_CHUNK = 64


@dataclass
class EpisodeTrace:
    """One arena's episode, step by step. T steps; index 0 is the start state."""

    positions: np.ndarray
    """(T + 1, n_agents, 2) world positions, start included."""
    modes: np.ndarray
    """(T, n_predators) the mode chosen at each step."""
    rewards: np.ndarray
    """(T, n_agents) the reward received after each step."""
    wall: np.ndarray
    """(T, n_agents) bool: touching a wall at the end of the step."""
    captured: np.ndarray
    """(T, n_predators) bool: overlapping the prey at the end of the step."""
    truncated: bool
    """The episode ended at the step limit."""
    q_values: np.ndarray | None = None
    """(T, n_predators, 2) the predators' Q-values for (stalk, chase); NaN for a predator that
    is not a hierarchical learner."""
    values: np.ndarray | None = None
    """(T, n_predators) the predators' V(s); NaN likewise."""
    obstacles: np.ndarray | None = None
    """(K, 3) the episode's obstacles (x, y, radius), or None in a task without them."""

    @property
    def length(self) -> int:
        return len(self.modes)

    def returns(self) -> np.ndarray:
        """(n_agents,) the episode's cumulative rewards."""
        return self.rewards.sum(axis=0)


class EpisodeTraces:
    """Collects per-step arrays of B arenas and hands out one arena's episode when it ends.

    Steps live in a ring of ``max_steps`` rows per field: no episode is longer, so an arena's
    running episode is always in it."""

    FIELDS = ("positions", "modes", "rewards", "wall", "captured", "q_values", "values")

    def __init__(self, start_positions: np.ndarray, max_steps: int, obstacles: np.ndarray | None = None) -> None:
        self._ring: dict[str, np.ndarray] = {}
        self._size = max_steps
        self._now = 0  # steps added so far
        self._start = np.zeros(len(start_positions), dtype=np.int64)  # step each running episode began
        self._initial = start_positions.copy()
        self._obstacles = None if obstacles is None else obstacles.copy()  # (B, K, 3) of the running episodes

    def add(
        self,
        positions: np.ndarray,
        modes: np.ndarray,
        rewards: np.ndarray,
        wall: np.ndarray,
        captured: np.ndarray,
        q_values: np.ndarray | None = None,
        values: np.ndarray | None = None,
    ) -> None:
        """One step of every arena: positions at the end of the step (before any autoreset)."""
        row = self._now % self._size
        for name, array in zip(self.FIELDS, (positions, modes, rewards, wall, captured, q_values, values), strict=True):
            if array is None:
                continue
            if name not in self._ring:
                self._ring[name] = np.zeros((self._size, *array.shape), dtype=array.dtype)
            self._ring[name][row] = array
        self._now += 1

    def add_step(
        self,
        actions: np.ndarray,
        rewards: np.ndarray,
        info: dict[str, Any],
        q_values: np.ndarray | None = None,
        values: np.ndarray | None = None,
    ) -> None:
        """One step of a :class:`~pursuit_bench.env.vector.VectorPursuitEnv`, from what went in
        (``actions``) and came out (``rewards``, ``info``)."""
        self.add(
            info["positions"], actions[:, :-1, 0], rewards, info["left_area"], info["touching_prey"], q_values, values
        )

    def finish(
        self, arena: int, truncated: bool, next_start: np.ndarray, next_obstacles: np.ndarray | None = None
    ) -> EpisodeTrace:
        """The episode that arena ``arena`` just ended; its next episode starts at ``next_start``
        (among ``next_obstacles`` (K, 3), in a task with obstacles)."""
        rows = np.arange(self._start[arena], self._now) % self._size
        taken = {name: ring[rows, arena] for name, ring in self._ring.items()}
        trace = EpisodeTrace(
            positions=np.concatenate([self._initial[arena][None], taken["positions"]]),
            modes=taken["modes"],
            rewards=taken["rewards"],
            wall=taken["wall"],
            captured=taken["captured"],
            truncated=truncated,
            q_values=taken.get("q_values"),
            values=taken.get("values"),
            obstacles=None if self._obstacles is None else self._obstacles[arena].copy(),
        )
        self._start[arena] = self._now
        self._initial[arena] = next_start
        if self._obstacles is not None and next_obstacles is not None:
            self._obstacles[arena] = next_obstacles
        return trace


def _rows(counts: np.ndarray, first: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(queue position, step) of ``counts[q]`` rows per queued episode q, steps from ``first``."""
    queued = np.repeat(np.arange(len(counts)), counts)
    steps = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + first
    return queued, steps


def _trail_strips(paths: list[np.ndarray]) -> pa.Array:
    """One line strip per step of each path: its last ``TRAIL_LENGTH`` positions. Built as one
    Arrow array (Rerun would otherwise convert the strips one by one)."""
    counts = np.array([len(p) for p in paths])
    _, ends = _rows(counts, first=1)  # strip t of a path ends after its position t
    lengths = np.minimum(ends, TRAIL_LENGTH)
    starts = np.repeat(np.cumsum(counts) - counts, counts) + ends - lengths  # in the concatenated paths
    index = np.repeat(starts - np.cumsum(lengths) + lengths, lengths) + np.arange(lengths.sum())
    offsets = pa.array(np.concatenate([[0], np.cumsum(lengths)]).astype(np.int32))
    vectors = pa.FixedSizeListArray.from_arrays(pa.array(np.concatenate(paths).astype(np.float32)[index].ravel()), 2)
    return pa.ListArray.from_arrays(offsets, vectors).cast(_STRIP_TYPE)


_STRIP_TYPE = rr.components.LineStrip2DBatch([np.zeros((2, 2), np.float32)]).as_arrow_array().type


def _rgba(rgb: tuple[int, int, int]) -> int:
    r, g, b = rgb
    return (r << 24) | (g << 16) | (b << 8) | 0xFF


def _log_arena(stream: rr.RecordingStream, groups: tuple[str, ...]) -> None:
    """The arena's walls, and a y flip on ``arena/<group>`` (the viewer's 2D y axis points
    down, the world's up)."""
    h = HALF_SIZE
    square = [[-h, -h], [h, -h], [h, h], [-h, h], [-h, -h]]
    stream.log("arena/walls", rr.LineStrips2D([square], colors=[WALL_RGB], radii=0.012), static=True)
    for group in groups:
        stream.log(f"arena/{group}", rr.Transform3D(scale=[1.0, -1.0, 1.0]), static=True)


def default_blueprint() -> rrb.Blueprint:
    """The layout a file opens with: the arena left; rewards and returns, modes and events right,
    over the last 30 s up to the time cursor; Q-values, training curves and the configuration in
    tabs; the time panel on ``sim_time``; side panels collapsed."""
    bound = HALF_SIZE + 0.1
    window = rrb.VisibleTimeRange(
        "sim_time",
        start=rrb.TimeRangeBoundary.cursor_relative(seconds=-WINDOW_SECONDS),
        end=rrb.TimeRangeBoundary.cursor_relative(),
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(
                name="Arena",
                origin="/arena",
                visual_bounds=rrb.VisualBounds2D(x_range=[-bound, bound], y_range=[-bound, bound]),
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(
                    name="Reward per step and return", contents=["/rewards/**", "/returns/**"], time_ranges=window
                ),
                rrb.StateTimelineView(name="Modes (stalk / chase)", origin="/modes", time_ranges=window),
                rrb.TextLogView(name="Events", origin="/events"),
                rrb.Tabs(
                    rrb.TimeSeriesView(name="Q-values and V(s)", origin="/values", time_ranges=window),
                    rrb.TimeSeriesView(name="Training", origin="/training"),
                    rrb.TextDocumentView(name="Config", origin="/config"),
                ),
                row_shares=[3, 2, 2, 3],
            ),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline="sim_time", state="expanded"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )


class EpisodeSink(Protocol):
    """What hears an evaluation's episodes: a :class:`Recorder`, a trajectory file
    (``trajectories/trajectory_csv.py``) or several (:class:`Sinks`)."""

    def log_episode(self, episode: int, trace: EpisodeTrace) -> None: ...

    def close(self) -> None: ...


class Sinks:
    """Several sinks heard as one: each episode goes to every one, in order."""

    def __init__(self, *sinks: EpisodeSink) -> None:
        self.sinks = sinks

    def log_episode(self, episode: int, trace: EpisodeTrace) -> None:
        for sink in self.sinks:
            sink.log_episode(episode, trace)

    def close(self) -> None:
        for sink in self.sinks:
            sink.close()


class Recorder:
    """Writes one ``.rrd`` file, offline (no viewer, no network).

    Args:
        path: the file to write (its folder is created).
        agent_names: ``predator_0`` … ``prey_0``, in the env's order.
        config: what the file is a recording of (condition, options); stored as a static text
            document so that the file explains itself.
        episodes_per_send: recorded episodes queued before they are sent (Rerun's cost is per
            call); a process killed outright loses the queued ones, a closed recorder none.
        recording_id: Rerun's recording id. Files written with the same id open as one
            recording (a resumed training run's pieces); by default the file's stem.

    ``clock`` is where the next episode starts on ``sim_time``, in steps: a resumed piece sets
    it to where the previous piece ended, so the pieces play one after the other.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        agent_names: list[str],
        config: dict[str, Any],
        *,
        episodes_per_send: int = EPISODES_PER_SEND,
        recording_id: str | None = None,
    ) -> None:
        self.episodes_per_send = episodes_per_send
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.names = list(agent_names)
        self.predators = self.names[:-1]
        self._stream = rr.RecordingStream(APPLICATION_ID, recording_id=recording_id or self.path.stem)
        self._stream.save(self.path, default_blueprint=default_blueprint())
        self.clock = 0
        self._queued: list[tuple[int, int, EpisodeTrace]] = []  # (episode, clock, trace) not yet sent
        self._episode_ids = np.zeros(0, dtype=np.int64)  # of the episodes being sent
        self._clocks = np.zeros(0, dtype=np.int64)
        self._metrics: list[tuple[int, dict[str, float]]] = []
        self._closed = False
        self._log_static(config)

    def _log_static(self, config: dict[str, Any]) -> None:
        s = self._stream
        _log_arena(s, ("agents", "trails", "obstacles"))
        s.log("arena/obstacles", rr.Points2D.from_fields(colors=[_rgba(OBSTACLE_RGB)]), static=True)
        for name in self.names:
            color = _rgba(agent_rgb(name))
            if name in self.predators:  # colour and size go with each row (mode): static ones would override them
                fields = rr.Points2D.from_fields(labels=[name], show_labels=False)
            else:
                fields = rr.Points2D.from_fields(radii=RADIUS, colors=[color], labels=[name], show_labels=False)
            s.log(f"arena/agents/{name}", fields, static=True)
            s.log(f"arena/trails/{name}", rr.LineStrips2D.from_fields(colors=[color], radii=0.004), static=True)
            for kind in ("rewards", "returns"):
                s.log(f"{kind}/{name}", rr.SeriesLines(colors=[color], names=[f"{kind[:-1]} {name}"]), static=True)
        resolved = json.dumps(config, indent=2, default=str)
        text = f"# {config.get('condition', 'pursuit-bench')}\n\n```json\n{resolved}\n```\n"
        s.log("config", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)

    def log_episode(self, episode: int, trace: EpisodeTrace) -> None:
        """Queue one episode; queued episodes go out together, one ``send_columns`` call per
        entity, every ``episodes_per_send`` episodes and on :meth:`close`."""
        self._queued.append((episode, self.clock, trace))
        self.clock += trace.length + 1
        if len(self._queued) >= self.episodes_per_send:
            self._send_episodes()

    def _send(self, entity: str, rows: tuple[np.ndarray, np.ndarray], columns: Any) -> None:
        """Send rows given as (queue position, step) arrays with their values in ``columns``."""
        queued, steps = rows
        indexes = [
            rr.TimeColumn("episode", sequence=self._episode_ids[queued]),
            rr.TimeColumn("step", sequence=steps),
            rr.TimeColumn("sim_time", duration=(self._clocks[queued] + steps) * DT),
        ]
        self._stream.send_columns(entity, indexes=indexes, columns=columns)

    def _send_episodes(self) -> None:
        if not self._queued:
            return
        traces = [trace for _, _, trace in self._queued]
        self._episode_ids = np.array([episode for episode, _, _ in self._queued])
        self._clocks = np.array([clock for _, clock, _ in self._queued])
        lengths = np.array([t.length for t in traces])
        every = _rows(lengths + 1)
        after = _rows(lengths, first=1)  # rewards arrive after each step
        before = _rows(lengths)  # decisions are taken before it
        placed = [t.obstacles for t in traces if t.obstacles is not None]
        if placed:  # each episode's obstacles at its first step: they stand until the next episode's
            starts = (np.arange(len(traces)), np.zeros(len(traces), dtype=np.int64))
            disks = np.concatenate(placed)
            columns = rr.Points2D.columns(positions=disks[:, :2], radii=disks[:, 2].astype(np.float32))
            self._send("arena/obstacles", starts, columns.partition([len(p) for p in placed]))
        for i, name in enumerate(self.names):
            paths = [t.positions[:, i] for t in traces]
            if i < len(self.predators):  # a predator is drawn bright and larger while it chases
                chasing = np.concatenate([np.append(t.modes[:, i], t.modes[-1:, i]) for t in traces]).astype(bool)
                bright, dark = _rgba(agent_rgb(name)), _rgba(dimmed(agent_rgb(name)))
                columns = rr.Points2D.columns(
                    positions=np.concatenate(paths),
                    colors=np.where(chasing, bright, dark).astype(np.uint32),
                    radii=np.where(chasing, CHASE_RADIUS, RADIUS).astype(np.float32),
                )
            else:
                columns = rr.Points2D.columns(positions=np.concatenate(paths))
            self._send(f"arena/agents/{name}", every, columns)
            strips = _trail_strips(paths)
            n = len(every[0])
            for lo in range(0, n, TRAIL_ROWS_PER_CHUNK):
                hi = min(lo + TRAIL_ROWS_PER_CHUNK, n)
                part = rr.LineStrips2D.columns(strips=strips[lo:hi]).partition(np.ones(hi - lo, dtype=np.int64))
                self._send(f"arena/trails/{name}", (every[0][lo:hi], every[1][lo:hi]), part)
            rewards = np.concatenate([t.rewards[:, i] for t in traces])
            self._send(f"rewards/{name}", after, rr.Scalars.columns(scalars=rewards))
            returns = np.concatenate([np.concatenate([[0.0], np.cumsum(t.rewards[:, i])]) for t in traces])
            self._send(f"returns/{name}", every, rr.Scalars.columns(scalars=returns))
        for j, name in enumerate(self.predators):
            modes = np.concatenate([t.modes[:, j] for t in traces])
            queued, steps = before
            switch = (steps == 0) | (np.diff(modes, prepend=-1) != 0)
            states = [MODE_NAMES[m] for m in modes[switch]]
            self._send(f"modes/{name}", (queued[switch], steps[switch]), rr.StateChange.columns(state=states))
            values = np.concatenate(
                [t.values[:, j] if t.values is not None else np.full(t.length, np.nan) for t in traces]
            )
            known = ~np.isnan(values)
            if known.any():
                rows = (queued[known], steps[known])
                q_values = np.concatenate([t.q_values[:, j] for t in traces if t.q_values is not None])
                for k, mode in enumerate(MODE_NAMES):
                    self._send(
                        f"values/{name}/q_{mode}", rows, rr.Scalars.columns(scalars=q_values[known[: len(q_values)], k])
                    )
                self._send(f"values/{name}/v", rows, rr.Scalars.columns(scalars=values[known]))
        events = [self._events(episode, trace) for episode, _, trace in self._queued]
        queued = np.repeat(np.arange(len(events)), [len(e) for e in events])
        steps = np.array([e[0] for evs in events for e in evs])
        texts = [e[2] for evs in events for e in evs]
        levels = [e[1] for evs in events for e in evs]
        self._send("events", (queued, steps), rr.TextLog.columns(text=texts, level=levels))
        self._queued.clear()

    def _events(self, episode: int, trace: EpisodeTrace) -> list[tuple[int, str, str]]:
        """``(step, level, text)``: the start, mode switches, captures, wall contacts, truncation."""
        events: list[tuple[int, str, str]] = [(0, "INFO", f"episode {episode} starts")]
        for j, name in enumerate(self.predators):
            modes = trace.modes[:, j]
            events += [
                (int(t), "INFO", f"{name} switches to {MODE_NAMES[modes[t]]}")
                for t in np.flatnonzero(np.diff(modes)) + 1
            ]
        end = trace.length
        events += [
            (end, "INFO", f"capture by {name}") for j, name in enumerate(self.predators) if trace.captured[-1, j]
        ]
        for i, name in enumerate(self.names):
            for t in np.flatnonzero(trace.wall[:, i]):
                events.append((int(t) + 1, "WARN", f"{name} touches the wall (leaves the area)"))
        if trace.truncated:
            events.append((end, "INFO", f"truncated after {end} steps"))
        return sorted(events, key=lambda e: e[0])

    def log_metrics(self, episode: int, metrics: dict[str, float]) -> None:
        """Per-episode training metrics, sent in bulk every few episodes (and on close)."""
        self._metrics.append((episode, metrics))
        if len(self._metrics) >= _METRICS_FLUSH_EVERY:
            self._flush_metrics()

    def _flush_metrics(self) -> None:
        if not self._metrics:
            return
        names = sorted({k for _, m in self._metrics for k in m})
        for key in names:
            rows = [(e, m[key]) for e, m in self._metrics if key in m]
            self._stream.send_columns(
                f"training/{key}",
                indexes=[rr.TimeColumn("episode", sequence=[e for e, _ in rows])],
                columns=rr.Scalars.columns(scalars=np.array([float(v) for _, v in rows])),
            )
        self._metrics.clear()

    def close(self) -> None:
        """Flush everything and finish the file (its footer is written here)."""
        if self._closed:
            return
        self._send_episodes()
        self._flush_metrics()
        self._stream.flush()
        self._stream.disconnect()
        self._closed = True

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class RecordEpisodes(BaseParallelWrapper):
    """Records every episode of a :class:`~pursuit_bench.env.pettingzoo_env.PursuitParallelEnv` (opt-in)::

        env = RecordEpisodes(pursuit_bench.parallel_env("2p-high-shared"))
        ...  # reset and step as usual
        env.close()  # finishes the file

    Args:
        env: the env to record.
        path: the ``.rrd`` file; by default a new file in ``recordings/``.
    """

    def __init__(self, env: Any, path: str | os.PathLike[str] | None = None) -> None:
        super().__init__(env)
        base = env.unwrapped
        name = base.condition or "pursuit"
        self.path = Path(path) if path is not None else RECORDINGS_DIR / f"{name}-{time.strftime('%Y%m%d-%H%M%S')}.rrd"
        described = {"condition": name, **dataclasses.asdict(base.config)}
        self.recorder = Recorder(self.path, list(base.possible_agents), described, episodes_per_send=1)
        self._base = base
        self._episodes = 0
        self._traces: EpisodeTraces | None = None

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        result = self.env.reset(seed=seed, options=options)
        self._traces = EpisodeTraces(
            self._base._core.world.positions, self._base.config.max_steps, self._base._core.obstacles
        )
        return result

    def step(
        self, actions: dict[str, Any], *, q_values: np.ndarray | None = None, values: np.ndarray | None = None
    ) -> Any:
        """The env's step; ``q_values`` (n_predators, 2) and ``values`` (n_predators,), if given,
        are the predators' Q-values for (stalk, chase) and V(s) behind ``actions`` (NaN for a
        predator without them), recorded with the step (give them at every step or at none)."""
        obs, rewards, terminated, truncated, infos = self.env.step(actions)
        if self._traces is not None:
            names = self._base.possible_agents
            predators = names[:-1]
            self._traces.add(
                self._base._core.world.positions.copy(),
                np.array([[infos[a]["mode"] for a in predators]]),
                np.array([[rewards[a] for a in names]]),
                np.array([[infos[a]["left_area"] for a in names]]),
                np.array([[infos[a]["captured"] for a in predators]]),
                None if q_values is None else np.asarray(q_values, dtype=np.float64)[None],
                None if values is None else np.asarray(values, dtype=np.float64)[None],
            )
            if not self._base.agents:  # the episode ended
                self._episodes += 1
                trace = self._traces.finish(0, bool(truncated[names[0]]), self._base._core.world.positions[0])
                self.recorder.log_episode(self._episodes, trace)
                self._traces = None
        return obs, rewards, terminated, truncated, infos

    def close(self) -> None:
        self.recorder.close()
        self.env.close()


def record_embedding(
    path: str | os.PathLike[str],
    agent_names: list[str],
    predator: str,
    embedding: np.ndarray,
    values: np.ndarray,
    positions: np.ndarray,
    config: dict[str, Any],
) -> None:
    """``analysis.rrd``: one predator's t-SNE embedding as points coloured by V(s), each
    labelled with its state's number (hover to read it), and on a ``state`` timeline the
    current state enlarged in the embedding beside the arena in that state: scrub the timeline
    (or go to a point's number) to see the situation behind a point.

    Args:
        embedding: (N, 2) the embedded states' coordinates.
        values: (N,) their V(s).
        positions: (N, n_agents, 2) every agent's position in each state.
    """
    stream = rr.RecordingStream(APPLICATION_ID, recording_id=Path(path).stem)
    low, high = embedding.min(axis=0), embedding.max(axis=0)
    margin = 0.05 * (high - low) + 1.0
    bounds = [[float(low[k] - margin[k]), float(high[k] + margin[k])] for k in (0, 1)]
    blueprint = rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial2DView(
                name=f"Embedding of {predator}'s value stream (colour: V(s))",
                origin="/embedding",
                visual_bounds=rrb.VisualBounds2D(x_range=bounds[0], y_range=bounds[1]),
            ),
            rrb.Spatial2DView(name="The state", origin="/arena"),
        ),
        rrb.TimePanel(timeline="state", state="expanded"),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )
    stream.save(Path(path), default_blueprint=blueprint)
    _log_arena(stream, ("agents",))
    span = float(np.ptp(values)) or 1.0
    shade = (values - values.min()) / span
    colors = np.stack([0.2 + 0.8 * shade, 0.3 + 0.5 * (1 - abs(2 * shade - 1)), 1.0 - 0.8 * shade], axis=1) * 255
    index = [rr.TimeColumn("state", sequence=np.arange(len(values)))]
    xy = embedding.astype(np.float32)
    stream.log(
        "embedding/states",
        rr.Points2D(xy, colors=colors.astype(np.uint8), radii=0.4, labels=[f"state {k}" for k in range(len(xy))]),
        static=True,
    )
    current = rr.Points2D.columns(
        positions=xy, radii=np.full(len(xy), 1.5), colors=np.tile([255, 255, 255], (len(xy), 1))
    )
    stream.send_columns("embedding/current", indexes=index, columns=current)
    for i, name in enumerate(agent_names):
        color = agent_rgb(name)
        stream.log(f"arena/agents/{name}", rr.Points2D.from_fields(radii=RADIUS, colors=[_rgba(color)]), static=True)
        stream.send_columns(
            f"arena/agents/{name}",
            indexes=index,
            columns=rr.Points2D.columns(positions=positions[:, i].astype(np.float32)),
        )
    stream.send_columns("values", indexes=index, columns=rr.Scalars.columns(scalars=values.astype(np.float64)))
    text = f"# {config.get('condition', '')}: {predator}\n\n```json\n{json.dumps(config, indent=2, default=str)}\n```\n"
    stream.log("config", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)
    stream.flush()
    stream.disconnect()
