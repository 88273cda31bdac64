"""The documentation site (mkdocs.yml, docs/site.md): built strictly, every page opened in headless
Chromium (driven by Playwright), and every tutorial run as written.

The build and the browser's visit are made once per test session (across pytest-xdist's
workers: a file lock, the first worker builds) and shared by every test that needs them.
Without the docs extra the site's tests are skipped, saying so; without Chromium or Playwright,
the browser's.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fcntl
import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from cli_helpers import load_script

import pursuit_bench

docs_site = load_script("docs/hooks.py")
site_check = load_script("scripts/site_check.py")

ROOT = docs_site.ROOT

BIN = Path(sys.executable).parent
MKDOCS = BIN / "mkdocs"
DOCS_EXTRA = ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_include_markdown_plugin", "rerun_notebook")
MISSING = [name for name in DOCS_EXTRA if importlib.util.find_spec(name.split(".")[0]) is None]
needs_docs = pytest.mark.skipif(
    bool(MISSING) or not MKDOCS.exists(),
    reason=f"the docs extra is not installed ({', '.join(MISSING) or 'mkdocs'}): bash scripts/install.sh test,docs",
)
CHROMIUM = site_check.find_chromium()
NO_BROWSER = site_check.missing()
needs_chromium = pytest.mark.skipif(NO_BROWSER is not None, reason=f"no browser checks: {NO_BROWSER}")
TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("*.md"))
#: The longest tutorials to run (Ray's cluster, SB3's training): marked long.
LONG_TUTORIALS = {"ray-sweep", "sb3"}
#: Each Python or bash block of a tutorial may take this long (a training run, a Ray sweep).
BLOCK_TIMEOUT = 600


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """An exclusive lock on ``path`` for the ``with`` block (xdist's workers share the build)."""
    with path.open("a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@pytest.fixture(scope="session")
def shared_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder every xdist worker of this session sees (the workers' common base)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@pytest.fixture(scope="session")
def built_site(shared_dir: Path) -> tuple[Path, dict[str, object]]:
    """``mkdocs build --strict`` into a temporary folder, once: (site, {returncode, output})."""
    site, result = shared_dir / "docs-site", shared_dir / "docs-site.json"
    with locked(shared_dir / "docs-site.lock"):
        if not result.exists():
            env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
            done = subprocess.run(
                [str(MKDOCS), "build", "--strict", "--site-dir", str(site)],
                cwd=ROOT,
                capture_output=True,
                text=True,
                env=env,
                timeout=900,
            )
            result.write_text(json.dumps({"returncode": done.returncode, "output": done.stdout + done.stderr}))
    return site, json.loads(result.read_text())


@pytest.fixture(scope="session")
def browser_visit(built_site: tuple[Path, dict[str, object]], shared_dir: Path) -> list[site_check.PageReport]:
    """Every built page opened in headless Chromium, once (across xdist's workers: the first one
    visits, the others read its reports); the viewer's screenshot in ``shared_dir/episode.png``."""
    site, build = built_site
    assert build["returncode"] == 0, build["output"]
    assert CHROMIUM is not None
    saved, shot = shared_dir / "browser-visit.json", shared_dir / "episode.png"
    with locked(shared_dir / "browser-visit.lock"):
        if not saved.exists():
            reports = site_check.check_site(site, chromium=CHROMIUM, timeout=180)
            for report in reports:
                if report.viewer_colours is not None and report.screenshot is not None:
                    shot.write_bytes(report.screenshot)
                report.screenshot = None
            saved.write_text(json.dumps([dataclasses.asdict(report) for report in reports]))
    reports = [site_check.PageReport(**fields) for fields in json.loads(saved.read_text())]
    for report in reports:
        if report.viewer_colours is not None and shot.exists():
            report.screenshot = shot.read_bytes()
    return reports


# ---------------------------------------------------------------- fast: the hooks alone


def test_links_between_included_files_point_at_the_pages_that_include_them() -> None:
    relink = docs_site.relink
    assert relink("see [it](../REPRODUCTION.md#what-was-run)", "index.md") == "see [it](reproduction.md#what-was-run)"
    assert relink("[r](../recordings/README.md)", "getting-started.md") == "[r](recordings.md)"
    assert relink("[c](../../CHANGELOG.md)", "tutorials/x.md") == "[c](../changelog.md)"
    unchanged = "[s](spec.md) [w](https://example.org/REPRODUCTION.md) [a](#top) [f](figures/episode.png)"
    assert relink(unchanged, "index.md") == unchanged


def test_the_docstrings_sphinx_roles_show_as_code() -> None:
    html = "one of :data:<code>pursuit_bench.CONDITIONS</code>, a :class:<code>~pursuit_bench.env.single.Env</code>"
    assert docs_site.sphinx_roles(html) == "one of <code>pursuit_bench.CONDITIONS</code>, a <code>Env</code>"


def test_the_env_cards_tables_are_made_from_the_code() -> None:
    from pursuit_bench.env import world

    conditions = docs_site.conditions_table()
    assert conditions.count("\n") == len(pursuit_bench.CONDITIONS) + 1  # header, rule, one row each
    for name, config in pursuit_bench.CONDITIONS.items():
        env = pursuit_bench.parallel_env(name)
        row = next(line for line in conditions.splitlines() if line.startswith(f"| `{name}` |"))
        assert f"| `{env.observation_space('prey_0').shape}` |" in row and ", ".join(env.possible_agents) in row
        assert f"| {config.chase_cost} |" in row
    dynamics = docs_site.dynamics_table()
    assert f"| `DT` | `{world.DT}` | Time step in seconds (paper 3.1). |" in dynamics
    assert "`ACCEL_CHASE` | `3.6` | Predator acceleration in chase mode: 120 % of the prey's (paper 3.1)." in dynamics
    assert "| `CHASE_COSTS` | `{'low': 0.01, 'high': 0.1}` | Cost of one step in chase mode, by name" in dynamics
    filled = docs_site.fill("a\n<!-- docs_site: versions -->\nb")
    assert "`pursuit_bench/Pursuit-v0` (version 0)" in filled and "<!--" not in filled
    with pytest.raises(ValueError, match="unknown generated block 'nope'"):
        docs_site.fill("<!-- docs_site: nope -->")


# ---------------------------------------------------------------- the strict build


@needs_docs
@pytest.mark.slow
def test_the_site_builds_strictly_with_every_page_and_the_viewer(built_site: tuple[Path, dict[str, object]]) -> None:
    site, build = built_site
    assert build["returncode"] == 0, build["output"]
    assert "WARNING" not in str(build["output"]), build["output"]
    config = (ROOT / "mkdocs.yml").read_text()
    assert re.search(r"^strict: true$", config, flags=re.M)
    for source in re.findall(r":\s+([\w/-]+\.md)$", config, flags=re.M):  # every page of the navigation
        folder = source.removesuffix("index.md") if source.endswith("index.md") else source.removesuffix(".md") + "/"
        built = site / folder / "index.html"
        assert built.exists(), source
    home = (site / "index.html").read_text()
    assert '<a href="reproduction/">REPRODUCTION.md</a>' in home and "What the project found" in home
    card = (site / "env" / "index.html").read_text()
    assert all(f"<code>{name}</code>" in card for name in pursuit_bench.CONDITIONS)
    assert "Version History" in card and "<!-- docs_site" not in card
    api = (site / "api" / "env" / "index.html").read_text()
    assert "PursuitParallelEnv" in api and "resolve_condition" in api and ":class:<code>" not in api
    # the recording and the viewer: one version
    assets = site / docs_site.RERUN_ASSETS
    header = (assets / "episode.rrd").read_bytes()[:8]
    assert header[:4] == b"RRF2"
    written = ".".join(str(b) for b in header[4:7])
    writer, viewer = docs_site.viewer_versions()
    assert written == writer == viewer, (written, writer, viewer)
    assert (assets / "re_viewer_bg.wasm").stat().st_size > 10_000_000 and (assets / "widget.js").exists()
    # the recording holds every step's Q-values, and each predator chose the mode of the larger one
    rows = recorded(assets / "episode.rrd")
    for predator in ("predator_0", "predator_1"):
        stalk, chase = rows[f"/values/{predator}/q_stalk"], rows[f"/values/{predator}/q_chase"]
        assert len(stalk) == len(chase) == len(rows[f"/rewards/{predator}"]) > 10
        switches = dict(rows[f"/modes/{predator}"])
        mode, chose = "stalk", []
        for (step, s), (_, c) in zip(stalk, chase, strict=True):
            mode = switches.get(step, mode)
            chose.append((mode == "chase") == (c > s))
        assert all(chose), predator


def recorded(path: Path) -> dict[str, list[tuple[int, object]]]:
    """A recording's rows per entity, in file order: (step, first value) of every non-static row."""
    import rerun.chunk as rc

    rows: dict[str, list[tuple[int, object]]] = {}
    for chunk in rc.RrdReader(path).store().stream():
        if chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        column = next(name for name in batch.schema.names if ":" in name)
        values = [v[0] if isinstance(v, list) and v else v for v in batch.column(column).to_pylist()]
        rows.setdefault(str(chunk.entity_path), []).extend(zip(batch.column("step").to_pylist(), values, strict=True))
    return rows


# ---------------------------------------------------------------- in the browser


@needs_docs
@needs_chromium
@pytest.mark.slow
def test_every_page_loads_in_chromium_without_errors_and_with_its_images(
    built_site: tuple[Path, dict[str, object]], browser_visit: list[site_check.PageReport]
) -> None:
    site, _ = built_site
    assert len(browser_visit) == len(site_check.pages(site)) >= 30
    problems = {report.url: report.problems for report in browser_visit if report.problems}
    assert not problems, json.dumps(problems, indent=1)
    images = {report.url.split("/", 3)[-1]: report.images for report in browser_visit}
    assert images[""] >= 1 and images["env/"] >= 1 and images["reproduction/"] >= 5


@needs_docs
@needs_chromium
@pytest.mark.slow
def test_the_episode_page_draws_the_arena(browser_visit: list[site_check.PageReport], shared_dir: Path) -> None:
    (episode,) = [r for r in browser_visit if r.url.endswith("/" + site_check.EPISODE_PAGE)]
    assert episode.screenshot is not None
    shot = shared_dir / "episode.png"
    assert episode.prey_pixels and episode.prey_pixels > 50, f"no prey drawn: {shot}"
    assert episode.viewer_colours and episode.viewer_colours > 100, f"a blank viewer: {shot}"


@needs_chromium
@pytest.mark.slow
def test_the_browser_check_catches_errors_broken_images_and_a_blank_viewer(tmp_path: Path) -> None:
    """The checker itself, on a site of three pages made here: a clean one, one with a console
    error, an uncaught exception, a missing image, a request refused and a name broken across
    lines in a narrow table, and an episode page whose viewer draws nothing."""
    (tmp_path / "ok").mkdir()
    (tmp_path / "ok" / "index.html").write_text(
        "<!doctype html><title>ok</title><p>fine</p><table><tr><td><code>2p-low-individual</code></td></tr></table>"
    )
    (tmp_path / "index.html").write_text(
        "<!doctype html><title>bad</title><img src='missing.png'>"
        "<table style='width: 60px'><tr><td><code>2p-low-individual</code></td><td>wide text</td></tr></table>"
        "<script>console.error('boom'); setTimeout(() => { throw new Error('late'); });"
        " fetch('http://127.0.0.1:9/refused').catch(() => {});</script>"
    )
    (tmp_path / "episode").mkdir()
    (tmp_path / "episode" / "index.html").write_text(
        "<!doctype html><title>blank</title><div id='rerun-viewer' style='width:300px;height:200px'></div>"
        "<script>document.body.dataset.rerunViewer = 'ready';</script>"
    )
    assert CHROMIUM is not None
    reports = {r.url.split("/", 3)[-1]: r for r in site_check.check_site(tmp_path, chromium=CHROMIUM, timeout=6)}
    assert reports["ok/"].problems == []
    bad = reports[""].problems
    assert any("boom" in p for p in bad) and any("late" in p for p in bad), bad
    assert any(p.startswith("image did not load") and "missing.png" in p for p in bad), bad
    assert any("404" in p and "missing.png" in p for p in bad), bad  # the failed load itself
    assert any(p.startswith("console: request failed") and "/refused" in p for p in bad), bad
    assert "a name in a table is broken across lines: 2p-low-individual" in bad, bad
    assert any("drew no arena" in p for p in reports["episode/"].problems), reports["episode/"].problems


# ---------------------------------------------------------------- the tutorials, as written


def blocks(page: Path) -> list[tuple[str, str, str | None]]:
    """A page's fenced blocks in order: (language, code dedented, title or None)."""
    found = re.findall(r"^( *)```(\w+)([^\n]*)\n(.*?)^\1```", page.read_text(), flags=re.S | re.M)
    out = []
    for indent, language, attributes, body in found:
        code = textwrap.dedent("\n".join(line[len(indent) :] for line in body.splitlines()))
        title = re.search(r'title="([^"]+)"', attributes)
        out.append((language, code, title.group(1) if title else None))
    return out


def namespace_command() -> list[str] | None:
    """``unshare -n`` (root) or ``unshare -rn``: a network namespace with only loopback; None if refused."""
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return None
    for command in (["unshare", "-n"], ["unshare", "-rn"]):
        with contextlib.suppress(OSError, subprocess.TimeoutExpired):
            if subprocess.run([*command, "true"], capture_output=True, timeout=30).returncode == 0:
                return command
    return None


def kill_namespace(marker: Path) -> None:
    """Kill every process left in the network namespace named in ``marker`` (Ray's daemons)."""
    if not marker.exists():
        return
    namespace = marker.read_text().strip()
    for process in Path("/proc").iterdir():
        if process.name.isdigit():
            with contextlib.suppress(OSError):
                if os.readlink(process / "ns" / "net") == namespace:
                    os.kill(int(process.name), signal.SIGKILL)


@pytest.fixture
def run_block(tmp_path: Path) -> Iterator[Callable[..., subprocess.CompletedProcess[str]]]:
    """``run(command, isolated)`` in the tutorial's empty folder, the venv's commands first on the
    PATH; ``isolated``: inside a network namespace of its own holding only loopback, whose
    processes are all killed at the end whatever happens."""
    marker = tmp_path.parent / f"{tmp_path.name}-netns"
    env = {
        **os.environ,
        "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
        "MPLBACKEND": "Agg",
        "RAY_USAGE_STATS_ENABLED": "0",
    }

    def run(command: list[str], isolated: bool, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
        if isolated:
            namespace = namespace_command()
            assert namespace is not None
            script = f'set -e\nip link set lo up\nreadlink /proc/self/ns/net > {marker}\nexec "$@"'
            command = [*namespace, "bash", "-c", script, "block", *command]
        return subprocess.run(
            command,
            cwd=tmp_path,
            env=env,
            input=stdin,
            capture_output=True,
            text=True,
            timeout=BLOCK_TIMEOUT,
            start_new_session=True,
        )

    yield run
    kill_namespace(marker)


def tutorial_skip(page: Path) -> str | None:
    """Why a tutorial cannot run here, or None."""
    text = page.read_text()
    if "stable_baselines3" in text and importlib.util.find_spec("stable_baselines3") is None:
        return "Stable-Baselines3 is not installed (pip install stable-baselines3; the test extra brings it)"
    if "pursuit-bench marl" in text and importlib.util.find_spec("benchmarl") is None:
        return "BenchMARL is not installed (the marl extra: pip install -e '.[marl]'; the test extra brings it)"
    if "from movement" in text and importlib.util.find_spec("movement") is None:
        return "movement is not installed (the animals extra: pip install -e '.[animals]'; the test extra brings it)"
    if "--backend ray" in text:
        if importlib.util.find_spec("ray") is None:
            return "Ray is not installed (pip install 'pursuit-bench[ray]'; the test extra brings it)"
        if namespace_command() is None:
            return "no network namespace allowed here (unshare -n and -rn refused): Ray would advertise this machine"
    return None


#: Runs the Python blocks it reads (a JSON list) one after another in one interpreter, each in a
#: namespace of its own as if in a fresh one: a block still cannot lean on another's names, and
#: the imports are paid once.
BLOCKS_RUNNER = """
import json, sys
for number, code in enumerate(json.load(sys.stdin), 1):
    exec(compile(code, f"<python block {number} of this run>", "exec"), {"__name__": "__main__"})
"""


def runs(page: Path) -> list[tuple[str, list[str], str | None]]:
    """What running a tutorial as written takes, in order: ("python", consecutive Python blocks,
    None), ("bash", [block], None) or ("file", [block], its title) for a block saved under its name."""
    out: list[tuple[str, list[str], str | None]] = []
    for language, code, title in blocks(page):
        if language not in ("python", "bash"):
            continue
        if title is not None:
            out.append(("file", [code], title))
        elif language == "python" and out and out[-1][0] == "python":
            out[-1][1].append(code)
        else:
            out.append((language, [code], None))
    return out


def test_a_tutorial_s_consecutive_python_blocks_share_an_interpreter_and_nothing_else(tmp_path: Path) -> None:
    page = tmp_path / "t.md"
    page.write_text(
        "```python\nx = 1\n```\n\n```python\nprint(x)\n```\n\n```bash\ntrue\n```\n\n"
        '```python title="m.py"\ny = 2\n```\n\n```python\nimport m\n```\n'
    )
    assert runs(page) == [
        ("python", ["x = 1", "print(x)"], None),
        ("bash", ["true"], None),
        ("file", ["y = 2"], "m.py"),
        ("python", ["import m"], None),
    ]
    done = subprocess.run(
        [sys.executable, "-c", BLOCKS_RUNNER], input=json.dumps(["x = 1", "print(x)"]), capture_output=True, text=True
    )
    assert done.returncode == 1 and "NameError" in done.stderr and "<python block 2 of this run>" in done.stderr


@pytest.mark.slow
@pytest.mark.parametrize(
    "page", [pytest.param(p, id=p.stem, marks=pytest.mark.long if p.stem in LONG_TUTORIALS else ()) for p in TUTORIALS]
)
def test_the_tutorial_runs_as_written(
    page: Path, tmp_path: Path, run_block: Callable[..., subprocess.CompletedProcess[str]]
) -> None:
    reason = tutorial_skip(page)
    if reason:
        pytest.skip(reason)
    isolated = "--backend ray" in page.read_text()
    steps = runs(page)
    assert any(kind != "file" for kind, _, _ in steps), f"{page.name}: no block to run"
    for kind, codes, title in steps:
        if kind == "file":
            assert title is not None
            (tmp_path / title).write_text(codes[0])
            continue
        if kind == "python":
            done = run_block([sys.executable, "-c", BLOCKS_RUNNER], isolated, json.dumps(codes))
        else:
            done = run_block(["bash", "-euo", "pipefail", "-c", codes[0]], isolated)
        shown = "\n\n".join(codes)
        assert done.returncode == 0, (
            f"{page.name}, this {kind} run failed:\n{shown}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
        )


def test_every_tutorial_is_in_the_navigation() -> None:
    config = (ROOT / "mkdocs.yml").read_text()
    assert TUTORIALS and all(f"tutorials/{page.name}" in config for page in TUTORIALS)
