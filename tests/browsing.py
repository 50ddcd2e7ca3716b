"""What every browser test module shares: ``pytestmark = BROWSER_MARKS`` marks it ``browser`` and
skips it without Debian's chromium or without Playwright. Its ``browser`` fixture (one headless
Chromium per module) is in tests/conftest.py."""

from __future__ import annotations

import os

import pytest

from sandbox.commands.live_bench import chromium_path

CHROMIUM = chromium_path()
BROWSER_MARKS = [pytest.mark.browser,
                 pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (apt-get install chromium)")]
playwright_api = pytest.importorskip("playwright.sync_api", reason="needs playwright (pip install -e '.[test]')")


PATIENCE_MS = 120_000
"""How long a page may take to show something or to answer a click before a test gives up.
Playwright's default is 30 s; with two full suites at once on two cores (load average 20-26), pages
took longer than that to answer, and tests failed on nothing but the wait (issue 23's stress runs).
These waits are not what the tests measure: the bars on time (the first visit, the drift, a notice
that must vanish) keep their own bounds."""


class PatientBrowser:
    """A Playwright browser whose contexts and pages wait up to PATIENCE_MS by default."""

    def __init__(self, browser) -> None:
        self._browser = browser

    def new_context(self, **options):
        context = self._browser.new_context(**options)
        context.set_default_timeout(PATIENCE_MS)
        return context

    def new_page(self, **options):
        page = self._browser.new_page(**options)  # in a context of its own, which closes with the page
        page.set_default_timeout(PATIENCE_MS)
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
