"""``phototaxis bench --live``: simulation speed and frame rate with a real
browser connected.

Starts the app on a free port, opens it in headless Chromium (Playwright),
lets it run, and measures steps per second in the simulation thread and
frames per second actually drawn by the browser (counted in the page with
``requestAnimationFrame`` while scene updates arrive) and sent by the server,
and the bytes each viewer receives per second.

``viewers`` adds plain websocket viewers beside the browser: they receive
exactly what a browser does (the server cannot tell them apart) but draw
nothing, so a classroom's worth can be simulated on one machine without
thirty Chromiums competing with the server for the CPU.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import threading
import time
from typing import Any

from sandbox.commands.serve import App, free_port
from sandbox.cli import UserError
from sandbox.model.config import Config

CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"]


def chromium_path() -> str | None:
    """Debian's chromium, or $PHOTOTAXIS_CHROMIUM, or whatever 'chromium' is on PATH."""
    for candidate in (os.environ.get("PHOTOTAXIS_CHROMIUM"), "/usr/bin/chromium", shutil.which("chromium"),
                      shutil.which("chromium-browser")):
        if candidate and os.path.exists(candidate):
            return candidate
    return None


@contextlib.contextmanager
def _browser_page():
    """A page of a headless Chromium, closed with the browser on the way out."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        raise UserError("the live benchmark needs playwright: pip install -e '.[test]'") from None
    browser_path = chromium_path()
    if browser_path is None:
        raise UserError("the live benchmark needs chromium: apt-get install chromium (or --no-browser)")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=browser_path, args=CHROMIUM_ARGS)
        try:
            yield browser.new_page(viewport={"width": 1280, "height": 800})
        finally:
            browser.close()


class WebsocketViewer:
    """A viewer that receives the scene like a browser and counts the bytes."""

    def __init__(self, port: int):
        import viser

        self.url, self.protocol = f"ws://127.0.0.1:{port}", f"viser-v{viser.__version__}"
        self.received = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._receive, name="websocket-viewer", daemon=True)
        self._thread.start()

    def _receive(self) -> None:
        from websockets.sync.client import connect

        with connect(self.url, subprotocols=[self.protocol], max_size=None, open_timeout=30) as ws:
            while not self._stop.is_set():
                try:
                    self.received += len(ws.recv(timeout=0.5))
                except TimeoutError:
                    continue

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)


def run(config: Config, seconds: float = 20.0, *, steps_per_frame: int = 25, fps: float = 30.0,
        warmup: float = 5.0, viewers: int = 1, compare_with: str | None = None,
        browser: bool = True) -> dict[str, Any]:
    """Measure the live app for ``seconds`` (after ``warmup``) with one
    headless browser (unless ``browser`` is False) and ``viewers`` websocket viewers connected;
    ``compare_with``: in compare mode against this case (sandbox.app.world.lockstep), both worlds measured."""
    if not browser and viewers < 1:
        raise UserError("with no browser, the live benchmark needs a websocket viewer (--viewers 1 or more)")
    compare = None
    if compare_with is not None:
        from sandbox.app.world.lockstep import partner_config

        compare = (partner_config(config, compare_with), compare_with)
    with contextlib.ExitStack() as stack:
        page = stack.enter_context(_browser_page()) if browser else None
        app = App(config, port=free_port(), fps=fps, steps_per_frame=steps_per_frame, compare=compare)
        app.start()
        stack.callback(app.stop)
        if page is not None:
            page.goto(f"http://127.0.0.1:{app.port}/")
            page.wait_for_selector("canvas", timeout=30_000)
        others = [WebsocketViewer(app.port) for _ in range(viewers)]
        for viewer in others:
            stack.callback(viewer.close)
        deadline = time.time() + 30
        while page is not None and not app.server.get_clients() and time.time() < deadline:
            time.sleep(0.1)
        # Measured once every viewer gets the scene (a loaded machine can take seconds to send the first
        # bytes: a window that opens before would count nothing), then after the warm-up.
        while any(v.received == 0 for v in others) and time.time() < deadline:
            time.sleep(0.05)
        time.sleep(warmup)
        if page is not None:
            page.evaluate("""() => { window.__frames = 0; const tick = () => { window.__frames++;
                             requestAnimationFrame(tick); }; requestAnimationFrame(tick); }""")
        partner = app.comparison.runner
        steps0, frames0, t0 = app.runner.latest.step, app.frames_drawn, time.perf_counter()
        other0 = partner.latest.step if partner is not None else 0
        bytes0 = [v.received for v in others]
        time.sleep(seconds)
        steps1, frames1, t1 = app.runner.latest.step, app.frames_drawn, time.perf_counter()
        other1 = partner.latest.step if partner is not None else 0
        bytes1 = [v.received for v in others]
        browser_frames = page.evaluate("() => window.__frames") if page is not None else None
        clients = len(app.server.get_clients())
    wall = t1 - t0
    sps = (steps1 - steps0) / wall
    return {
        "steps_per_second": round(sps, 1),
        "real_time_factor": round(sps * config.dt, 2),
        "frames_per_second": round((frames1 - frames0) / wall, 1),
        "browser_frames_per_second": round(browser_frames / wall, 1) if browser else None,
        "clients": clients,
        "viewers": int(browser) + viewers,
        # The browser's websocket lives in a web worker, out of Playwright's sight: the websocket viewers count.
        "kb_per_second_per_viewer": (round(max(b1 - b0 for b0, b1 in zip(bytes0, bytes1)) / wall / 1000, 1)
                                     if viewers else None),
        "seconds": round(wall, 1),
        "robots": config.robots,
        "boxes": config.boxes,
        "steps_per_frame": steps_per_frame,
        **({} if compare is None else {
            "compared_with": compare_with,
            "compared_steps_per_second": round((other1 - other0) / wall, 1),
            "compared_real_time_factor": round((other1 - other0) / wall * config.dt, 2)}),
    }


if __name__ == "__main__":  # pragma: no cover
    import json
    import sys

    print(json.dumps(run(Config(), float(sys.argv[1]) if len(sys.argv) > 1 else 20.0)))
