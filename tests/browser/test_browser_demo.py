"""What a class sees, measured in the real page (headless Chromium): issue 24.

Each test reads the page's own three.js scene (tests/scene_probe.py), not a
screenshot, where it can.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from sandbox.app.view.hexagons import ANGLE_TOLERANCE
from tests import scene_probe
from tests.browsing import BROWSER_MARKS
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS


def open_page(browser, app, size=(1280, 800)):
    context = browser.new_context(viewport={"width": size[0], "height": size[1]})
    page = context.new_page()
    page.add_init_script(scene_probe.INIT_SCRIPT)
    page.goto(f"http://127.0.0.1:{app.port}/")
    return context, page


# ------------------------------------------------------------------ drift
class SentFrames:
    """Every snapshot the app publishes, found by the robots the page draws for it: its step, the
    light cells lit then, the centres of those cells and the boxes (positions as the page gets them,
    about the arena's centre, sorted; and their angles)."""

    def __init__(self, app):
        from sandbox.app.view.scene import SceneView

        self._points = SceneView._points
        self.by_robots: dict[bytes, dict] = {}
        self._lock = threading.Lock()
        app.runner.subscribe(self.take)

    def take(self, snap) -> None:
        cfg = snap.world_config
        c = cfg.arena_size / 2.0
        key = self._points(len(snap.robot_positions), snap.robot_positions - c)[:, :2].tobytes()
        cells = np.argwhere(snap.intensities > 0)
        boxes = self._points(len(snap.box_positions), snap.box_positions - c)[:, :2].astype(float)
        order = np.lexsort(boxes.T[::-1])
        with self._lock:
            self.by_robots[key] = dict(step=snap.step, lit=frozenset(map(tuple, cells)),
                                       lit_centres=(cells + 0.5) * cfg.light_pitch - c, boxes=boxes[order],
                                       angles=snap.box_angles[order])

    def find(self, robots: np.ndarray) -> dict | None:
        with self._lock:
            return self.by_robots.get(robots.astype(np.float16).tobytes())


def sorted_rows(rows: np.ndarray) -> np.ndarray:
    return rows[np.lexsort(rows[:, :2].T[::-1])] if len(rows) else rows


def lit_cells(lit: np.ndarray, config) -> frozenset:
    """The light cells of the page's lit points (local coordinates, about the arena's centre)."""
    cells = np.floor((lit[:, :2] + config.arena_size / 2.0) / config.light_pitch).astype(int)
    return frozenset(map(tuple, cells))


def cell_centres(lit: np.ndarray, config) -> np.ndarray:
    """The centres of the cells of the page's lit points (each is drawn a little off its centre, on
    the part of the cell the grid's seam leaves)."""
    c = config.arena_size / 2.0
    return (np.floor((lit[:, :2] + c) / config.light_pitch) + 0.5) * config.light_pitch - c


def hexagons_turned(drawn: np.ndarray, angles: np.ndarray) -> float:
    from sandbox.app.view.hexagons import turned_each

    return float(turned_each(np.asarray(drawn, float), angles).max()) if len(drawn) else 0.0


def band_offset(lit: np.ndarray, robots: np.ndarray, centre: np.ndarray, pitch: float) -> float | None:
    """How far the robots riding the lit band sit from it (m, + outside), about the circle's centre:
    the median over the robots within two cells of the band's radius. None with fewer than ten."""
    if len(lit) < 8 or len(robots) == 0:
        return None
    band = float(np.median(np.hypot(*(lit[:, :2] - centre).T)))
    r = np.hypot(*(robots[:, :2] - centre).T)
    riding = r[np.abs(r - band) <= 2 * pitch]
    return float(np.median(riding - band)) if len(riding) >= 10 else None


def test_the_lights_are_drawn_with_the_robots_of_the_same_step(browser):
    """Issue 24, item 1: at the top speed, every frame the page draws shows the lights of its robots'
    step, so the lit band and the robots on it are where the simulation had them: the band's distance
    to the robots riding it, as drawn, is never more than one light cell from what it was (the drift).
    The page once showed an older light pattern, 2-5 cells away."""
    from sandbox.app.world.runner import FASTEST
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    config = Config()  # the default world: circle, 200 robots, 500 boxes
    app = App(config, port=free_port(), steps_per_frame=FASTEST)
    sent = SentFrames(app)
    app.start()
    context = None
    try:
        context, page = open_page(browser, app)
        wait_until(lambda: scene_probe.now(page) is not None, 60, "the robots to be drawn")
        # From the band's first sweep over the robots to well into the first contraction.
        wait_until(lambda: app.runner.latest.step >= 1500, 120, "the band to reach the robots")
        step0, t0 = app.runner.latest.step, time.time()
        scene_probe.start(page)
        # and 25 frames drawn: a page on a loaded machine drew 17 in the first 10 s (the test needs 20).
        # Under two full suites at once, 180 s were once not enough for both; a failure says which lagged.
        seen = {}

        def enough() -> bool:
            seen.update(steps=app.runner.latest.step - step0, drawn=scene_probe.samples_taken(page))
            return seen["steps"] >= 6000 and seen["drawn"] >= 25 and time.time() > t0 + 10

        try:
            wait_until(enough, 300, "6,000 more steps and 25 frames drawn", poll=0.25)
        except AssertionError as exc:
            raise AssertionError(f"{exc}; had {seen}") from None
        samples = scene_probe.stop(page)
        step1 = app.runner.latest.step
        frames = app.runner.frames_published
    finally:
        if context is not None:
            context.close()
        app.stop()

    centre = np.full(2, config.centre - config.arena_size / 2.0)
    mismatched, drifts, offsets, boxes_elsewhere, turned = [], [], [], [], 0.0
    for sample in samples:
        robots, lit = scene_probe.array(sample, "robots"), scene_probe.array(sample, "lit")
        sent_then = sent.find(robots[:, :2])
        if sent_then is None:
            continue
        if lit_cells(lit, config) != sent_then["lit"]:
            mismatched.append(sent_then["step"])
        boxes = sorted_rows(scene_probe.array(sample, "boxes"))
        if len(boxes) != len(sent_then["boxes"]) or not np.array_equal(boxes[:, :2], sent_then["boxes"]):
            boxes_elsewhere.append(sent_then["step"])
        else:
            turned = max(turned, hexagons_turned(boxes[:, 2], sent_then["angles"]))
        drawn = band_offset(cell_centres(lit, config), robots, centre, config.light_pitch)
        true = band_offset(sent_then["lit_centres"], robots, centre, config.light_pitch)
        if drawn is not None and true is not None:
            drifts.append(abs(drawn - true))
            offsets.append(drawn)
    worst = max(drifts, default=float("nan"))
    print(f"\n{len(samples)} frames drawn over steps {step0:,}-{step1:,} ({frames} frames sent in all, "
          f"{(step1 - step0) / max(len(samples), 1):.0f} steps per frame drawn); drift measured in {len(drifts)} "
          f"frames: worst {worst:.2f} m; robots riding the band sit {np.mean(offsets):+.2f} m from it on "
          f"average (worst {np.max(np.abs(offsets)):.2f} m); hexagons turned at most {turned:.1f} degrees off")
    assert not boxes_elsewhere, f"boxes of another step drawn with the robots of steps {boxes_elsewhere[:10]}"
    assert turned <= ANGLE_TOLERANCE + 0.01
    assert len(drifts) >= max(20, 0.8 * len(samples)), "most drawn frames should be of a step the app sent"
    assert not mismatched, f"lights of another step drawn with the robots of steps {mismatched[:10]}"
    assert worst <= config.light_pitch, f"the band drawn is {worst:.2f} m from where it was"
