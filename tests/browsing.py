"""What every browser test module shares: ``pytestmark = BROWSER_MARKS`` marks it ``browser`` and
skips it without Debian's chromium or without Playwright. Its ``browser`` fixture (one headless
Chromium per module) is in tests/conftest.py."""

from __future__ import annotations

import os

import pytest

from sandbox.commands.live_bench import CHROMIUM_ARGS, chromium_path

CHROMIUM = chromium_path()
TEST_CHROMIUM_ARGS = [*CHROMIUM_ARGS, "--webgl-antialiasing-mode=none"]
"""The tests' Chromium draws the floor without WebGL's antialiasing. Chromium draws it in software
(SwiftShader), in one GPU process for all of a module's pages, and the tests wait on what it draws:
without the 4x multisampling, the class lesson took 50.6 s instead of 61.6-64.1 s and test_browser_app
114 s instead of 130 s (alone, one run each). What the tests check (where things are, what text says,
what a click does) does not depend on smoothed edges; ``bench --live`` and ``--teacher-browser``
keep Chromium's default, since they measure what a real page costs."""
BROWSER_MARKS = [pytest.mark.browser,
                 pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (apt-get install chromium)")]
playwright_api = pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install -e '.[test]')")


PATIENCE_MS = 120_000
"""How long a page may take to show something or to answer a click before a test gives up.
Playwright's default is 30 s; with two full suites at once on two cores (load average 20-26), pages
took longer than that to answer, and tests failed on nothing but the wait (issue 23's stress runs).
These waits are not what the tests measure: the bars on time (the first visit, the drift, a notice
that must vanish) keep their own bounds."""


#: Set to keep pictures: then the floor is drawn at full resolution.
PICTURES = ("PHOTOTAXIS_SHOTS", "PHOTOTAXIS_SCREENSHOTS", "ROOM_SHOTS")

HALF_RESOLUTION_JS = """(() => {
    const url = new URL(location.href);
    if (url.protocol.startsWith('http') && !url.searchParams.has('fixedDpr')) {
        url.searchParams.set('fixedDpr', '0.5');
        history.replaceState(history.state, '', url);
    }
})()"""
"""Run before the page's own scripts: viser's client reads ``?fixedDpr=`` for the canvas's pixel ratio,
so the floor is drawn at half resolution in the same layout (CSS px). The page is software-drawn and
every Playwright action waits on its main thread: with one page at 1280 x 800, a bounding box took
0.12-0.16 s instead of 0.24-0.32 s, a hover 0.18-0.25 s instead of 0.37-0.46 s, and frames came every
17 ms instead of 33-67 ms."""


class PatientBrowser:
    """A Playwright browser whose contexts and pages wait up to PATIENCE_MS by default, and draw the floor
    at half resolution (see HALF_RESOLUTION_JS) unless pictures are kept or ``in_full``: a module that
    measures what is drawn in pixels (letters read from the back of a room) says
    ``DRAWN_IN_FULL = True``."""

    def __init__(self, browser, in_full: bool = False) -> None:
        self._browser = browser
        self._half_resolution = not in_full and not any(os.environ.get(name) for name in PICTURES)

    def new_context(self, **options):
        context = self._browser.new_context(**options)
        context.set_default_timeout(PATIENCE_MS)
        if self._half_resolution:
            context.add_init_script(HALF_RESOLUTION_JS)
        return context

    def new_page(self, **options):
        page = self._browser.new_page(**options)  # in a context of its own, which closes with the page
        page.set_default_timeout(PATIENCE_MS)
        if self._half_resolution:
            page.add_init_script(HALF_RESOLUTION_JS)
        return page

    def __getattr__(self, name):
        return getattr(self._browser, name)


def small_app():
    """The small live world the browser modules drive (40 robots, 80 boxes, 4 steps a frame at 15 frames
    a second: quick to build and to draw on a loaded machine), started; the caller stops it.
    PHOTOTAXIS_TEST_WORLD=default gives the default world instead (`serve`'s), to measure a bar set for
    it (the one-minute designer's loop, docs/testing.md)."""
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    if os.environ.get("PHOTOTAXIS_TEST_WORLD") == "default":
        return App(Config(), port=free_port()).start()
    config = Config(robots=40, boxes=80, update_every=20, hold_steps=5)
    return App(config, port=free_port(), steps_per_frame=4, fps=15).start()


#: Each canvas of the page: its box (CSS px, from the viewport's top left, as Playwright's bounding_box).
CANVAS_BOXES_JS = """() => [...document.querySelectorAll('canvas')].map((c) => {
    const r = c.getBoundingClientRect();
    return {x: r.x, y: r.y, width: r.width, height: r.height};
})"""


def canvas_boxes(page) -> list[dict]:
    """Every canvas's box, asked in one round trip: a busy page (software WebGL, four pages on two cores)
    answered each of the six bounding_box calls a scene's canvas took in 1.3-2.2 s."""
    return page.evaluate(CANVAS_BOXES_JS)


def largest_canvas(page) -> tuple[int, dict]:
    """The scene's canvas (the page's largest): its index among the page's canvases, and its box."""
    boxes = canvas_boxes(page)
    best = max(range(len(boxes)), key=lambda i: boxes[i]["width"] * boxes[i]["height"])
    return best, boxes[best]
