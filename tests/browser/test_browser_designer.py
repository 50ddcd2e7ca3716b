"""The designer's first minutes in the real page (issue 56, items 1, 2, 3 and 7), at 1280 x 800 (and the
notice, whose room is what a phone changes, at 390 x 844), in a world with the default 500 boxes (where the
goal is moved inside the wall):

- an F from its template, *Close and use*: the "Goal changed" notice is whole (it was cut to 200 px of
  its 242), in the window;
- the drawing gives way: no magenta of the drawn line on the canvas after *Use*, back with *Edit this goal*;
- typed points are drawn on the dashed preview, where the goal is built;
- *Open design* in the Result folder, a design file chosen in the page's file chooser: its world runs, lit
  by its recorded light program.

Set PHOTOTAXIS_SHOTS=DIR to keep a small screenshot of each step there.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest

from sandbox.app.world.snapshot import DESIGN_PROGRAM
from tests.browsing import BROWSER_MARKS
from tests.drawing_page import button, choose, dismiss_notifications
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS

SHOTS = os.environ.get("PHOTOTAXIS_SHOTS")
WORLD = dict(robots=40, update_every=20, hold_steps=5)  # the default 500 boxes
#: The designer's typed shape of issue 56, item 2.
TYPED = "0 0\n2 0\n2 6\n5 6\n5 8\n-3 8\n-3 6\n0 6"
#: A canvas pixel of the drawn line: magenta (sandbox.app.view.sketch.LINE_COLOUR), which nothing else
#: on the floor is (the boxes in the goal are pink: blue under 200).
MAGENTA_AT_LEAST = 40


@pytest.fixture(scope="module")
def app():
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    a = App(Config(**WORLD), port=free_port(), steps_per_frame=4, fps=15).start()
    yield a
    a.stop()


@pytest.fixture(scope="module")
def design_path(tmp_path_factory) -> Path:
    """A star's design in this world's settings (seed 3, 100 steps): what Download design saves."""
    from sandbox import Simulation
    from sandbox.model.config import Config
    from sandbox.model.design import PatternRecorder, file_bytes

    config = Config(**WORLD, shape="star", seed=3)
    sim = Simulation(config, seed=3)
    recorder = PatternRecorder().attach(sim)
    sim.step(100)
    path = tmp_path_factory.mktemp("designs") / "star-seed3-design.npz"
    path.write_bytes(file_bytes(recorder.design(sim, "paper")))
    return path


def shot(page, name: str) -> None:
    """A screenshot kept small: a PNG of 128 colours (about 70 KB on a phone, 280 KB at 1280 x 800)."""
    if SHOTS:
        from PIL import Image

        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        picture = Image.open(io.BytesIO(page.screenshot())).convert("RGB").quantize(128)
        picture.save(Path(SHOTS) / f"{name}.png", optimize=True)


def magenta_pixels(page) -> int:
    """Pixels of the drawn line's magenta on the page (the notices closed first: they cover the floor)."""
    from PIL import Image

    dismiss_notifications(page)
    picture = np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)
    r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
    return int(((r > 200) & (g < 60) & (b > 200)).sum())


def open_folder(page, narrow: bool, title: str, inside: str) -> None:
    """A folder of the panel opened (on a phone, the drawer first, by the page's own script)."""
    if narrow:
        page.wait_for_function("() => !!window.__phototaxisOpenFolder")
        page.evaluate(f"window.__phototaxisOpenFolder({title!r}, [{inside!r}])")
    elif not button(page, inside).is_visible():
        page.get_by_text(title, exact=True).first.click()
    button(page, inside).wait_for()


def notice_box(page, title: str) -> dict:
    """The notice titled ``title``: where it is and whether its text is all shown."""
    return page.evaluate("""(title) => {
        const note = [...document.querySelectorAll('.mantine-Notification-root')].find(
            (n) => n.textContent.includes(title));
        if (!note) return null;
        const r = note.getBoundingClientRect();
        return {top: r.top, bottom: r.bottom, height: r.height, scrollHeight: note.scrollHeight,
                clientHeight: note.clientHeight, overflow: getComputedStyle(note).overflowY,
                window: window.innerHeight};
    }""", title)


@pytest.mark.parametrize("width, height", [(1280, 800), (390, 844)])
def test_the_designers_first_minutes(app, browser, design_path, width, height):
    narrow = width < 576
    size = f"{width}x{height}"
    draw = app.panel.shape.draw
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    try:
        page.goto(f"http://127.0.0.1:{app.port}/")
        page.get_by_text("Goal shape", exact=True).wait_for()
        dismiss_notifications(page)
        open_folder(page, narrow, "Draw", "Start drawing")

        # Item 1: an F, Close and use, and the whole notice.
        if draw.points:
            button(page, "Clear").click()
            wait_until(lambda: not draw.points, what="cleared")
        choose(page, "Template", "letter F")
        wait_until(lambda: len(draw.points) == 10 and not draw.close.disabled, what="the F, ready")
        wait_until(lambda: magenta_pixels(page) >= MAGENTA_AT_LEAST, what="the F drawn on the floor")
        key = app.runner.latest.goal_key
        button(page, "Close and use").click()
        page.locator(".mantine-Notification-root", has_text="Goal changed").wait_for()
        page.get_by_text("so that it lies inside the wall").first.wait_for()
        box = wait_until(lambda: notice_box(page, "Goal changed"), what="the notice laid out")
        shot(page, f"1-notice-{size}")
        print(f"\n{size}: the Goal changed notice is {box['height']:.0f} px tall, its text {box['scrollHeight']} px")
        assert box["scrollHeight"] <= box["clientHeight"] + 1 or box["overflow"] in ("auto", "scroll"), box
        assert box["top"] >= 0 and box["bottom"] <= box["window"], box  # in the window, nothing cut off
        if narrow:
            return  # on a phone only the notice's room differs: the rest is the same server's work, asked the same way


        # Item 3: the drawing gives way to the goal built, and comes back with Edit this goal.
        wait_until(lambda: app.runner.latest.goal_key != key and draw.given_way, what="the F in use")
        wait_until(lambda: magenta_pixels(page) < MAGENTA_AT_LEAST, 30, what="the drawing off the floor")
        shot(page, f"3-given-way-{size}")
        button(page, "Edit this goal").click()
        wait_until(lambda: magenta_pixels(page) >= MAGENTA_AT_LEAST, what="the running goal back as points")
        shot(page, f"3-edit-this-goal-{size}")

        # Item 2: typed points drawn on the dashed preview, where the goal is built.
        points = page.locator("xpath=//*[normalize-space(text())='Points']/following::textarea"
                              "[contains(@class, 'mantine-Textarea-input')][1]")
        points.fill(TYPED)
        wait_until(lambda: draw.typed.value == TYPED, what="the typed text at the server")
        button(page, "Apply points").click()
        # The preview is made by a worker: the F's (10 points) may still stand for a while on a busy machine.
        wait_until(lambda: len(draw.points) == 8 and draw._preview is not None and len(draw._preview.goal) == 8,
                   what="the typed points and their preview")
        np.testing.assert_allclose(draw._preview.goal, draw.points, atol=2e-3)
        dismiss_notifications(page)
        shot(page, f"2-typed-{size}")

        # Item 7: a design file opened from the page.
        open_folder(page, narrow, "Result", "Explain the result")
        with page.expect_file_chooser() as chooser:
            button(page, "Open design").click()
        chooser.value.set_files(str(design_path))
        page.locator(".mantine-Notification-root", has_text="Design opened").wait_for()
        snap = wait_until(lambda: app.runner.latest if app.runner.latest.program == DESIGN_PROGRAM else None,
                          what="the design's world")
        assert snap.seed == 3 and snap.shape_name == "star"
        shot(page, f"7-design-opened-{size}")
    finally:
        context.close()
