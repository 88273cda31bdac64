"""Open every page of the built documentation site in headless Chromium and say what is wrong.

    .venv/bin/mkdocs build --strict && .venv/bin/python scripts/site_check.py site --shots /tmp/site-shots

Serves the site on 127.0.0.1 (a port of the system's choosing), opens each page in Debian's
Chromium (``/usr/bin/chromium``) driven over the Chrome DevTools Protocol on a pipe
(``--remote-debugging-pipe``: JSON messages on file descriptors 3 and 4, so the standard library
is all it needs: no WebDriver, no Node, no websocket package), and reports per page: console
errors, uncaught exceptions and failed loads (the console's and the browser log's ``error``
entries) and ``<img>`` elements that did not load (``naturalWidth == 0``). On the episode page it
waits for Rerun's web viewer to say it is ready and for the arena to be drawn (pixels of the
prey's blue), and measures how many colours the viewer's screenshot holds. ``--shots DIR`` saves
a screenshot of every page. Exits 1 if any page has a problem. ``tests/test_docs_site.py``
imports it.
"""

from __future__ import annotations

import argparse
import base64
import contextlib
import fcntl
import functools
import http.server
import io
import json
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

#: Debian's package; elsewhere whatever ``chromium`` is on the PATH.
CHROMIUM_PATHS = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
VIEWPORT = (1280, 1000)
#: The prey's colour in the recordings (``pursuit_bench.env.render.PREY_RGB``).
PREY_RGB = (40, 80, 220)
EPISODE_PAGE = "episode/"


def find_chromium() -> str | None:
    """Chromium's path, or None where it is not installed."""
    for path in CHROMIUM_PATHS:
        if os.access(path, os.X_OK):
            return path
    return shutil.which("chromium") or shutil.which("chromium-browser")


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


# ---------------------------------------------------------------- Chromium over the DevTools protocol


class ProtocolError(RuntimeError):
    """Chromium answered a command with an error, or not in time."""


def _above_stdio(fd: int) -> int:
    """``fd`` moved to 10 or above (close-on-exec), so that it can be put on 3 or 4 in the child."""
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
    os.close(fd)
    return moved


class Chromium:
    """Headless Chromium in a session of its own, driven over ``--remote-debugging-pipe``.

    ``close()`` (or leaving the ``with`` block) ends it and every process it started, whatever
    happened; its profile lives in a temporary folder removed then."""

    def __init__(self, binary: str, *, log: Path | None = None) -> None:
        to_child, self._to_browser = map(_above_stdio, os.pipe())
        self._from_browser, from_child = map(_above_stdio, os.pipe())
        self.profile = tempfile.mkdtemp(prefix="site-check-chromium-")
        width, height = VIEWPORT
        args = [
            binary,
            "--headless",
            "--remote-debugging-pipe",
            f"--user-data-dir={self.profile}",
            f"--window-size={width},{height}",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--mute-audio",
            "--hide-scrollbars",
            # WebGL in software, for Rerun's viewer: no GPU here
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
        ]
        if os.geteuid() == 0:
            args.append("--no-sandbox")  # Chromium refuses to run as root with its sandbox
        args.append("about:blank")
        log_path = str(log) if log is not None else os.devnull
        actions = [
            (os.POSIX_SPAWN_DUP2, to_child, 3),
            (os.POSIX_SPAWN_DUP2, from_child, 4),
            (os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0),
            (os.POSIX_SPAWN_OPEN, 1, log_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644),
            (os.POSIX_SPAWN_OPEN, 2, log_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644),
        ]
        try:
            self.pid = os.posix_spawn(binary, args, dict(os.environ), file_actions=actions, setsid=True)
        finally:
            os.close(to_child)
            os.close(from_child)
        self._next_id = 0
        self._responses: dict[int, dict[str, Any]] = {}
        self.events: list[dict[str, Any]] = []
        self._condition = threading.Condition()
        self._closed = False
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        buffer = b""
        while True:
            try:
                chunk = os.read(self._from_browser, 1 << 16)
            except OSError:
                chunk = b""
            if not chunk:
                with self._condition:
                    self._closed = True
                    self._condition.notify_all()
                return
            buffer += chunk
            *messages, buffer = buffer.split(b"\0")
            with self._condition:
                for raw in messages:
                    message = json.loads(raw)
                    if "id" in message:
                        self._responses[message["id"]] = message
                    else:
                        self.events.append(message)
                self._condition.notify_all()

    def send(
        self, method: str, params: dict[str, Any] | None = None, *, session: str | None = None, timeout: float = 30
    ) -> Any:
        """Send one command; its result (ProtocolError on an error or after ``timeout`` seconds)."""
        with self._condition:
            self._next_id += 1
            number = self._next_id
        message: dict[str, Any] = {"id": number, "method": method, "params": params or {}}
        if session is not None:
            message["sessionId"] = session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout
        with self._condition:
            while number not in self._responses:
                left = deadline - time.monotonic()
                if left <= 0 or self._closed:
                    raise ProtocolError(f"{method}: no answer from Chromium in {timeout} s")
                self._condition.wait(left)
            response = self._responses.pop(number)
        if "error" in response:
            raise ProtocolError(f"{method}: {response['error']}")
        return response.get("result", {})

    def wait_for(self, found: Callable[[], Any], what: str, timeout: float) -> Any:
        """Poll ``found()`` (after every message from Chromium, at least every 0.2 s) until it
        returns something true; TimeoutError naming ``what`` after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while True:
            value = found()
            if value:
                return value
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"{what}: not within {timeout} s")
            with self._condition:
                self._condition.wait(min(left, 0.2))

    def close(self) -> None:
        """End Chromium and every process of its session; remove its profile."""
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, signal.SIGKILL)
        with contextlib.suppress(ChildProcessError):
            os.waitpid(self.pid, 0)
        for fd in (self._to_browser, self._from_browser):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._reader.join(timeout=5)
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self) -> Chromium:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ---------------------------------------------------------------- one page


@dataclass
class PageReport:
    """What one page did in the browser."""

    url: str
    errors: list[str] = field(default_factory=list)
    broken_images: list[str] = field(default_factory=list)
    images: int = 0
    viewer_colours: int | None = None
    prey_pixels: int | None = None
    screenshot: bytes | None = None

    @property
    def problems(self) -> list[str]:
        out = [f"console: {e}" for e in self.errors] + [f"image did not load: {i}" for i in self.broken_images]
        if self.viewer_colours is not None and not self.prey_pixels:
            out.append(f"the viewer drew no arena ({self.viewer_colours} colours, no pixel of the prey's blue)")
        return out


def _error_text(event: dict[str, Any]) -> str | None:
    """The text of an event that is an error on the page, else None."""
    method, params = event.get("method"), event.get("params", {})
    if method == "Runtime.exceptionThrown":
        details = params.get("exceptionDetails", {})
        return f"uncaught {details.get('exception', {}).get('description') or details.get('text')}"
    if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
        parts = [str(arg.get("value", arg.get("description", ""))) for arg in params.get("args", [])]
        return "console.error: " + " ".join(parts)
    if method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
        entry = params["entry"]
        return f"{entry.get('source')}: {entry.get('text')} {entry.get('url', '')}".strip()
    return None


def colours(png: bytes) -> tuple[int, int]:
    """(distinct colours, pixels within 40 of the prey's blue) of a PNG screenshot."""
    pixels = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16).reshape(-1, 3)
    distinct = len(np.unique(pixels, axis=0))
    near = int((np.abs(pixels - np.array(PREY_RGB)).max(axis=1) <= 40).sum())
    return distinct, near


class Page:
    """One tab, its events kept apart from the others' by its session."""

    def __init__(self, browser: Chromium) -> None:
        self.browser = browser
        target = browser.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.send(f"{domain}.enable")
        width, height = VIEWPORT
        self.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
        )

    def send(self, method: str, params: dict[str, Any] | None = None, timeout: float = 30) -> Any:
        return self.browser.send(method, params, session=self.session, timeout=timeout)

    def evaluate(self, expression: str, timeout: float = 30) -> Any:
        """The value of a JavaScript expression (awaited if it is a promise)."""
        result = self.send(
            "Runtime.evaluate", {"expression": expression, "awaitPromise": True, "returnByValue": True}, timeout=timeout
        )
        if "exceptionDetails" in result:
            raise ProtocolError(f"{expression[:60]}…: {result['exceptionDetails'].get('text')}")
        return result.get("result", {}).get("value")

    def _mine(self, start: int) -> list[dict[str, Any]]:
        with self.browser._condition:
            return [e for e in self.browser.events[start:] if e.get("sessionId") == self.session]

    def screenshot(self, clip: dict[str, float] | None = None) -> bytes:
        params: dict[str, Any] = {"format": "png"}
        if clip is not None:
            params["clip"] = {**clip, "scale": 1}
        return base64.b64decode(self.send("Page.captureScreenshot", params, timeout=60)["data"])

    def open(self, url: str, *, timeout: float = 60, viewer: bool = False, keep_screenshot: bool = False) -> PageReport:
        """Load ``url``, let it settle, and report on it."""
        start = len(self.browser.events)
        self.send("Page.navigate", {"url": url})
        self.browser.wait_for(
            lambda: any(e.get("method") == "Page.loadEventFired" for e in self._mine(start)), f"{url} load", timeout
        )
        # settled: two frames drawn and the main thread idle (the search index, late scripts)
        self.evaluate(
            "new Promise(done => requestAnimationFrame(() => requestAnimationFrame("
            "() => requestIdleCallback(done, {timeout: 5000}))))",
            timeout=timeout,
        )
        report = PageReport(url)
        images = self.evaluate(
            "Array.from(document.images).map(i => [i.currentSrc || i.src, i.complete && i.naturalWidth > 0])"
        )
        report.images = len(images)
        report.broken_images = [src for src, loaded in images if not loaded]
        if viewer:
            self._watch_viewer(report, timeout)
        if keep_screenshot:
            report.screenshot = self.screenshot()
        report.errors = [text for e in self._mine(start) if (text := _error_text(e))]
        return report

    def _watch_viewer(self, report: PageReport, timeout: float) -> None:
        """Wait for Rerun's viewer to be ready and to draw the arena; count its colours."""
        self.browser.wait_for(
            lambda: self.evaluate("document.body.dataset.rerunViewer === 'ready'"), "Rerun's viewer ready", timeout
        )
        self.evaluate("document.getElementById('rerun-viewer').scrollIntoView()")
        box = self.evaluate(
            "(() => { const r = document.getElementById('rerun-viewer').getBoundingClientRect();"
            " return {x: r.x + window.scrollX, y: r.y + window.scrollY, width: r.width, height: r.height}; })()"
        )

        def drawn() -> tuple[int, int] | None:
            report.screenshot = self.screenshot(box)
            counted = colours(report.screenshot)
            return counted if counted[1] > 0 else None

        try:
            report.viewer_colours, report.prey_pixels = self.browser.wait_for(drawn, "the arena drawn", timeout)
        except TimeoutError:
            report.viewer_colours, report.prey_pixels = colours(report.screenshot or b"")[0], 0


def check_site(
    site: Path, *, chromium: str, shots: Path | None = None, timeout: float = 60, log: Path | None = None
) -> list[PageReport]:
    """Every page of ``site`` opened in one headless Chromium, in one tab, one after another."""
    reports = []
    with serve(site) as root, Chromium(chromium, log=log) as browser:
        page = Page(browser)
        for path in pages(site):
            viewer = path == EPISODE_PAGE
            report = page.open(root + path, timeout=timeout, viewer=viewer, keep_screenshot=shots is not None)
            if shots is not None and report.screenshot is not None:
                shots.mkdir(parents=True, exist_ok=True)
                name = (path.strip("/").replace("/", "-") or "index") + ".png"
                (shots / name).write_bytes(report.screenshot)
            reports.append(report)
    return reports


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("site", type=Path, help="The built site (mkdocs build's site/).")
    parser.add_argument("--shots", type=Path, default=None, help="Save a screenshot of every page here.")
    parser.add_argument("--timeout", type=float, default=90, help="Seconds a page may take [90].")
    args = parser.parse_args()
    chromium = find_chromium()
    if chromium is None:
        print("Chromium is not installed (Debian: apt-get install chromium)", file=sys.stderr)
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
