"""Open every page of the built documentation site in headless Chromium and say what is wrong.

    .venv/bin/mkdocs build --strict && .venv/bin/python scripts/site_check.py site --shots SHOTS

Serves the site on 127.0.0.1 (a port of the system's choosing) and opens each page in Debian's
Chromium (``/usr/bin/chromium``) driven by Playwright (``playwright`` on PyPI, in the ``docs``
extra; its own browser is never downloaded: Playwright launches the system's). It reports per
page: console errors, uncaught exceptions, requests that failed or were answered with an error
status, ``<img>`` elements that did not load (``naturalWidth == 0``), and names in a table that
the browser broke across lines (a ``<code>`` without spaces drawn on two lines). On the episode
page it waits for Rerun's web viewer to say it is ready and for the arena to be drawn (pixels of
the prey's blue), and counts the colours of the viewer's screenshot. ``--shots DIR`` saves a
screenshot of every page (the episode page's once its viewer has drawn). Exits 1 if any page
has a problem, 2 if Chromium or Playwright is missing. ``tests/test_docs_site.py`` imports it.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import http.server
import importlib.util
import io
import os
import shutil
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

#: Debian's package; elsewhere whatever ``chromium`` is on the PATH.
CHROMIUM_PATHS = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
#: Chromium's flags beside Playwright's own: no connection but to the served site (this machine's
#: network is closed: Chromium's background requests would fail, many at a time), no sandbox where
#: it runs as root (Chromium refuses otherwise), WebGL in software for Rerun's viewer (no GPU).
CHROMIUM_ARGS = (
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
    "--no-first-run",
    "--no-default-browser-check",
    "--mute-audio",
    "--hide-scrollbars",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
)
VIEWPORT: Any = {"width": 1280, "height": 1000}  # Playwright's ViewportSize (a TypedDict)
#: The prey's colour in the recordings (``pursuit_bench.env.render.PREY_RGB``).
PREY_RGB = (40, 80, 220)
EPISODE_PAGE = "episode/"
#: Where the episode page's viewer is paused for its screenshot, on the recording's sim_time (ns).
VIEWER_AT_NS = 9_000_000_000
#: Where the viewer draws the arena: the top-left part of its screenshot (width, height), beside
#: the panels on the right and above the time panel (whose selected timeline is highlighted blue).
ARENA_PART = (0.55, 0.75)
#: Settled: two frames drawn and the main thread idle (the search index, late scripts).
SETTLED = (
    "() => new Promise(done => requestAnimationFrame(() => requestAnimationFrame("
    "() => requestIdleCallback(done, {timeout: 5000}))))"
)
#: Every ``<img>``: (its address, whether it loaded).
IMAGES = "() => Array.from(document.images).map(i => [i.currentSrc || i.src, i.complete && i.naturalWidth > 0])"
#: The names in table cells (``<code>`` without whitespace) that the browser drew on more than one line.
WRAPPED = (
    "() => Array.from(document.querySelectorAll('td code, th code'))"
    ".filter(c => !/\\s/.test(c.textContent) && c.getClientRects().length > 1).map(c => c.textContent)"
)


def find_chromium() -> str | None:
    """Chromium's path, or None where it is not installed."""
    for path in CHROMIUM_PATHS:
        if os.access(path, os.X_OK):
            return path
    return shutil.which("chromium") or shutil.which("chromium-browser")


def missing() -> str | None:
    """Why the browser checks cannot run here (what to install), or None."""
    if importlib.util.find_spec("playwright") is None:
        return "Playwright is not installed (pip install -e '.[docs]', or bash scripts/install.sh test,docs)"
    if find_chromium() is None:
        return "Chromium is not installed (Debian: apt-get install chromium; scripts/install.sh does it as root)"
    return None


def pages(site: Path) -> list[str]:
    """Every page of a built site as a path from its root ('' for the home page, 'env/', …)."""
    found = []
    for html in sorted(site.rglob("*.html")):
        relative = html.relative_to(site).as_posix()
        found.append(relative.removesuffix("index.html"))
    return found


# ---------------------------------------------------------------- a local http server


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {  # noqa: RUF012  (the base class's attribute, extended)
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".wasm": "application/wasm",
        ".js": "text/javascript",
        ".rrd": "application/octet-stream",
    }

    def log_message(self, format: str, *args: Any) -> None:
        pass


@contextlib.contextmanager
def serve(site: Path) -> Iterator[str]:
    """The site served on 127.0.0.1 for the ``with`` block; yields its root URL."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_QuietHandler, directory=str(site)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


# ---------------------------------------------------------------- one page


@dataclass
class PageReport:
    """What one page did in the browser."""

    url: str
    errors: list[str] = field(default_factory=list)
    broken_images: list[str] = field(default_factory=list)
    wrapped_names: list[str] = field(default_factory=list)
    images: int = 0
    viewer_colours: int | None = None
    prey_pixels: int | None = None
    screenshot: bytes | None = None

    @property
    def problems(self) -> list[str]:
        out = [f"console: {e}" for e in self.errors] + [f"image did not load: {i}" for i in self.broken_images]
        out += [f"a name in a table is broken across lines: {name}" for name in self.wrapped_names]
        if self.viewer_colours is not None and not self.prey_pixels:
            out.append(f"the viewer drew no arena ({self.viewer_colours} colours, no pixel of the prey's blue)")
        return out


def colours(png: bytes, part: tuple[float, float] = (1.0, 1.0)) -> tuple[int, int]:
    """(distinct colours, pixels within 40 of the prey's blue) of a PNG screenshot; the blue is
    counted in its top-left ``part`` alone (fractions of its width and height)."""
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)
    distinct = len(np.unique(image.reshape(-1, 3), axis=0))
    height, width = image.shape[:2]
    corner = image[: round(height * part[1]), : round(width * part[0])].reshape(-1, 3)
    near = int((np.abs(corner - np.array(PREY_RGB)).max(axis=1) <= 40).sum())
    return distinct, near


class Visitor:
    """One Playwright page (a tab) that opens the site's pages one after another, hearing every
    console message, uncaught exception and failed request of the page being opened."""

    def __init__(self, page: Any) -> None:
        self.page = page
        self.heard: list[str] = []
        page.on("console", self._console)
        page.on("pageerror", lambda error: self.heard.append(f"uncaught {error}"))
        page.on("requestfailed", self._request_failed)
        page.on("response", self._response)

    def _console(self, message: Any) -> None:
        if message.type in ("error", "assert"):
            self.heard.append(f"console.{message.type}: {message.text}")

    def _request_failed(self, request: Any) -> None:
        # net::ERR_ABORTED is the browser cancelling a request itself, as it does to the previous
        # page's requests still in flight (the search worker) when the next page is opened; a file
        # the site lacks answers 404, which _response hears.
        if request.failure != "net::ERR_ABORTED":
            self.heard.append(f"request failed: {request.url} ({request.failure})")

    def _response(self, response: Any) -> None:
        if response.status >= 400:
            self.heard.append(f"{response.status} {response.status_text}: {response.url}")

    def open(self, url: str, *, timeout: float = 60, viewer: bool = False, keep_screenshot: bool = False) -> PageReport:
        """Load ``url``, let it settle, and report on it."""
        self.heard = []
        self.page.set_default_timeout(timeout * 1000)
        self.page.goto(url, wait_until="load")
        self.page.evaluate(SETTLED)
        report = PageReport(url)
        images = self.page.evaluate(IMAGES)
        report.images = len(images)
        report.broken_images = [src for src, loaded in images if not loaded]
        report.wrapped_names = self.page.evaluate(WRAPPED)
        if viewer:
            self._watch_viewer(report, timeout)
        elif keep_screenshot:
            report.screenshot = self.page.screenshot()
        report.errors = list(self.heard)
        return report

    def _watch_viewer(self, report: PageReport, timeout: float) -> None:
        """Wait for Rerun's viewer to be ready and to draw the arena, then pause it a few seconds
        into the episode (the time series have something to show up to the time cursor) and wait
        for it to settle; count the colours of its screenshot."""
        self.page.wait_for_function("document.body.dataset.rerunViewer === 'ready'")
        viewer = self.page.locator("#rerun-viewer")
        viewer.scroll_into_view_if_needed()
        deadline = time.monotonic() + timeout

        def look() -> bool:
            report.screenshot = viewer.screenshot()
            report.viewer_colours, report.prey_pixels = colours(report.screenshot, ARENA_PART)
            return time.monotonic() > deadline

        while not look() and not report.prey_pixels:
            self.page.wait_for_timeout(200)  # the viewer draws frame by frame: look again
        if not report.prey_pixels:
            return
        self.page.evaluate(
            "() => window.rerunViewerSend?.({type: 'time_ctrl', timeline: 'sim_time', sequence: null,"
            f" duration_nanos: '{VIEWER_AT_NS}', timestamp_nanos: null, play: false}})"
        )
        before = b""
        while not look() and report.screenshot != before:  # paused: two looks alike
            before = report.screenshot or b""
            self.page.wait_for_timeout(200)


def check_site(site: Path, *, chromium: str, shots: Path | None = None, timeout: float = 60) -> list[PageReport]:
    """Every page of ``site`` opened in one headless Chromium, in one tab, one after another."""
    from playwright.sync_api import sync_playwright

    args = [*CHROMIUM_ARGS, *(["--no-sandbox"] if os.geteuid() == 0 else [])]
    reports = []
    with (
        tempfile.TemporaryDirectory(prefix="site-check-chromium-") as profile,
        serve(site) as root,
        sync_playwright() as playwright,
    ):
        browser = playwright.chromium.launch_persistent_context(
            profile, executable_path=chromium, headless=True, args=args, viewport=VIEWPORT, chromium_sandbox=False
        )
        try:
            visitor = Visitor(browser.pages[0] if browser.pages else browser.new_page())
            for path in pages(site):
                viewer = path == EPISODE_PAGE
                report = visitor.open(root + path, timeout=timeout, viewer=viewer, keep_screenshot=shots is not None)
                if shots is not None and report.screenshot is not None:
                    shots.mkdir(parents=True, exist_ok=True)
                    name = (path.strip("/").replace("/", "-") or "index") + ".png"
                    (shots / name).write_bytes(report.screenshot)
                reports.append(report)
        finally:
            browser.close()
    return reports


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("site", type=Path, help="The built site (mkdocs build's site/).")
    parser.add_argument("--shots", type=Path, default=None, help="Save a screenshot of every page here.")
    parser.add_argument("--timeout", type=float, default=90, help="Seconds a page may take [90].")
    args = parser.parse_args()
    reason = missing()
    chromium = find_chromium()
    if reason is not None or chromium is None:
        print(reason, file=sys.stderr)
        return 2
    reports = check_site(args.site, chromium=chromium, shots=args.shots, timeout=args.timeout)
    bad = 0
    for report in reports:
        extra = (
            f", viewer: {report.viewer_colours} colours, {report.prey_pixels} prey pixels"
            if report.viewer_colours is not None
            else ""
        )
        print(f"{report.url}: {report.images} images{extra}")
        for problem in report.problems:
            print(f"  {problem}")
        bad += bool(report.problems)
    print(f"{len(reports)} pages, {bad} with problems")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
