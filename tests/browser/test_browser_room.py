"""A room can read it (issue 41, items 1-3), in the real page (headless Chromium): the presenter's first
visit (title card, grid, legend, the on-screen bar), Play from the card closing every page's card, the bar
acting on the server, Start over offered to a controlling page that arrives mid-run and not to a watcher.
Screenshots go to $ROOM_SHOTS when it is set (docs/browser.md's pictures were taken so)."""

from __future__ import annotations

import os
import time

import pytest

from tests.browsing import BROWSER_MARKS
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS
DRAWN_IN_FULL = True  # it reads letters and label boxes off screenshots (tests/browsing.py)

TOKEN = "room-token-41"


@pytest.fixture(scope="module")
def app():
    from sandbox.app.web.access import Access
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    config = Config(robots=40, boxes=80, update_every=20, hold_steps=5)
    app = App(config, port=free_port(), steps_per_frame=4, fps=15, playing=False, whole_arena=False,
              access=Access.for_server("127.0.0.1", token=TOKEN))  # serve --classroom, shared: a token to control
    app.start()
    yield app
    app.stop()


def open_page(browser, app, token: bool, size=(1024, 768)):
    context = browser.new_context(viewport={"width": size[0], "height": size[1]})
    page = context.new_page()
    before = set(app.server.get_clients())
    page.goto(f"http://127.0.0.1:{app.port}/" + (f"?token={TOKEN}" if token else ""))
    answered = time.monotonic()
    wait_until(lambda: set(app.server.get_clients()) - before, what="the page to connect")
    client_id = next(iter(set(app.server.get_clients()) - before))
    return context, page, client_id, answered


#: Closes viser's notice that the test browser draws in software: a classroom's machine has a graphics card,
#: and a picture kept for the docs should show the room, not the test browser.
CLOSE_SOFTWARE_NOTICE = """[...document.querySelectorAll('.mantine-Notification-root')]
    .filter(n => n.textContent.includes('Software WebGL'))
    .forEach(n => n.querySelector('.mantine-Notification-closeButton')?.click())"""


def shot(page, name: str) -> None:
    """A screenshot into ``ROOM_SHOTS`` (when set), without the software-drawing notice."""
    folder = os.environ.get("ROOM_SHOTS")
    if folder:
        page.evaluate(CLOSE_SOFTWARE_NOTICE)
        wait_until(lambda: not page.evaluate(f"({CLOSE_SOFTWARE_NOTICE}, [...document.querySelectorAll("
                                             f"'.mantine-Notification-root')].some(n => n.textContent.includes("
                                             f"'Software WebGL')))"), 10, what="the software notice closed")
        page.screenshot(path=os.path.join(folder, name))


def test_a_phones_title_card_says_tap_play_not_space(app, browser):
    """Issue 56, item 14: a phone (390 x 844, touch) has no space bar: its card says "Tap Play to start."
    A desktop page keeps the keyboard's words (the next test)."""
    context = browser.new_context(viewport={"width": 390, "height": 844}, has_touch=True, is_mobile=True)
    try:
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{app.port}/?token={TOKEN}")
        dialog = page.get_by_role("dialog")
        dialog.get_by_text("Tap Play to start.").wait_for()
        assert "Press Play (space)" not in dialog.inner_text()
        assert app.runner.latest.step == 0 and not app.runner.playing  # a card, not a run: nothing was pressed
    finally:
        context.close()


def test_the_presenters_first_visit_and_play_from_the_title_card(app, browser):
    teacher = student = None
    try:
        teacher, page, teacher_id, answered = open_page(browser, app, token=True)
        page.get_by_text("Press Play (space) to start.").wait_for()
        card_after = time.monotonic() - answered
        # The grid is drawn (the lights' texture) and the legend lies on this page's floor; the bar is on screen.
        wait_until(lambda: teacher_id in app.panel.framing._legends, what="the legend on the floor")
        legend_after = time.monotonic() - answered
        bar = page.get_by_role("button", name="Pause", exact=True)
        bar.wait_for()
        print(f"\ntitle card shown {card_after:.1f} s after the page answered, the legend sent at "
              f"{legend_after:.1f} s, the bar at {time.monotonic() - answered:.1f} s")
        student, watching, student_id, _ = open_page(browser, app, token=False)
        watching.get_by_text("The presenter starts it with Play.").wait_for()
        assert watching.get_by_role("button", name="Pause", exact=True).count() == 0  # no bar: it only watches
        shot(page, "room-first-visit.png")
        assert app.runner.latest.step == 0 and not app.runner.playing
        page.get_by_role("dialog").get_by_role("button", name="Play", exact=True).click()
        wait_until(lambda: app.runner.playing, what="the card's Play to play")
        for p in (page, watching):  # every page's card closes
            wait_until(lambda p=p: p.get_by_role("dialog").count() == 0, what="the title cards to close")
    finally:
        for context in (teacher, student):
            if context is not None:
                context.close()


def test_the_on_screen_bar_acts_on_the_server(app, browser):
    context, page, client_id, _ = open_page(browser, app, token=True)
    try:
        runner = app.runner
        wait_until(lambda: client_id in app.panel.presenter.bars, what="the bar")
        if page.get_by_role("dialog").count():
            page.get_by_role("dialog").get_by_role("button", name="Play", exact=True).click()
        page.get_by_role("button", name="Play", exact=True).click()
        wait_until(lambda: runner.playing, what="Play")
        page.get_by_role("button", name="Pause", exact=True).click()
        wait_until(lambda: not runner.playing, what="Pause")
        wait_until(lambda: runner.latest.step == app.lockstep.target or runner.latest.step > 0, what="paused")
        before = runner.latest.step
        wait_until(lambda: runner.latest.step == before, what="a still world")
        page.get_by_role("button", name="Step", exact=True).click()
        wait_until(lambda: runner.latest.step == before + runner.latest.world_config.update_every, what="Step")
        world = runner.latest.world_key
        page.get_by_role("button", name="Reset", exact=True).click()
        wait_until(lambda: runner.latest.world_key != world and runner.latest.step == 0, what="Reset")
        page.get_by_role("button", name="Play", exact=True).click()
        wait_until(lambda: runner.playing and runner.latest.step > 0, what="Play again")
    finally:
        context.close()


def test_start_over_is_offered_to_a_controlling_page_mid_run_not_to_a_watcher(app, browser, monkeypatch):
    from sandbox.app.panel import presenter

    monkeypatch.setattr(presenter, "OFFER_SECONDS", 900.0)  # a loaded machine shows the page late: no expiry here
    monkeypatch.setattr(presenter, "OFFER_FROM_STEP", 1)  # any step is far along here (pages came before)
    runner = app.runner
    if not runner.playing:
        app.events.call(app.lockstep.set_playing, True)
    wait_until(lambda: runner.latest.step > 0, what="a run under way")
    student, watching, student_id, _ = open_page(browser, app, token=False)
    teacher = None
    try:
        wait_until(lambda: student_id in app.panel.presenter.controls, what="the watcher welcomed")
        teacher, page, teacher_id, _ = open_page(browser, app, token=True)
        offer = page.get_by_role("button", name="Start over", exact=True)
        offer.wait_for()
        shot(page, "room-joining.png")
        # The watcher arrived first and was welcomed: it got no offer (its page has the controlling page's
        # offer nowhere either: offers are each page's own).
        assert student_id not in app.panel.presenter.offers and teacher_id in app.panel.presenter.offers
        assert watching.get_by_role("button", name="Start over", exact=True).count() == 0
        world = runner.latest.world_key
        offer.click()
        wait_until(lambda: runner.latest.world_key != world, what="Start over to start the run again")
        assert runner.latest.seed == app.runner.latest.seed
        wait_until(lambda: page.get_by_role("button", name="Start over", exact=True).count() == 0,
                   what="the offer to go")
    finally:
        for context in (teacher, student):
            if context is not None:
                context.close()


def view_height(client) -> float:
    """The floor (m) the page's camera shows from the canvas's top to its bottom, as the page last
    reported it (top-down)."""
    import numpy as np

    return float(2 * client.camera.position[2] * np.tan(client.camera.fov / 2))


def floor_to_page(client, canvas: dict, box) -> dict:
    """A floor box (left, right, bottom, top, m) where the page draws it (CSS px), through the camera the
    page last reported: top-down, so a metre is the same number of pixels across and up."""
    import numpy as np

    look_at = np.asarray(client.camera.look_at)
    per_metre = canvas["height"] / view_height(client)
    x = canvas["x"] + canvas["width"] / 2 + (np.array(box[:2]) - look_at[0]) * per_metre
    y = canvas["y"] + canvas["height"] / 2 - (np.array(box[2:]) - look_at[1]) * per_metre
    return {"x": float(x[0]), "y": float(y[1]), "width": float(x[1] - x[0]), "height": float(y[0] - y[1])}


def within(a: dict, b: dict) -> bool:
    return (b["x"] - 1 <= a["x"] and a["x"] + a["width"] <= b["x"] + b["width"] + 1 and b["y"] - 1 <= a["y"]
            and a["y"] + a["height"] <= b["y"] + b["height"] + 1)


def covers(a: dict, b: dict) -> bool:
    return (a["x"] < b["x"] + b["width"] and b["x"] < a["x"] + a["width"] and a["y"] < b["y"] + b["height"]
            and b["y"] < a["y"] + a["height"])


#: What could cover the floor's labels, as the page lays it out now: its notices and visible buttons.
COVERING = """() => [...document.querySelectorAll('.mantine-Notification-root, button, [role=button]')]
    .filter((e) => getComputedStyle(e).visibility !== 'hidden')
    .map((e) => e.getBoundingClientRect())
    .filter((r) => r.width > 0 && r.height > 0)
    .map((r) => ({x: r.x, y: r.y, width: r.width, height: r.height}))"""


def test_compare_mode_on_a_projector_shows_every_caption_and_readout_uncovered(browser):
    """Issue 41, item 1, at 1024 x 768 in the presenter layout: both worlds framed, each caption, readout and
    the difference in the canvas, none under a notice (viser's own included) or the on-screen panels."""
    import numpy as np

    from sandbox.app.world.lockstep import side_config
    from sandbox.app.view.scene import caption_box, compare_camera, difference_box, readout_box, shifted
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    base = Config(robots=40, boxes=80)
    app = App(side_config("star", base), port=free_port(), steps_per_frame=4, fps=15, whole_arena=False,
              compare=(side_config("star-switch", base), "star-switch"))
    app.start()
    context = None
    try:
        context, page, client_id, _ = open_page(browser, app, token=False)  # this machine's page: it controls
        client = app.server.get_clients()[client_id]
        config, offset = app.runner.latest.world_config, app.panel.framing.offset
        legend = app.panel.framing._legend_aspect

        def framed() -> bool:
            aspect = client.camera.aspect or 1.0
            position, look_at, _ = compare_camera(config, aspect, offset, whole=False, legend_height_per_width=legend)
            return bool(np.allclose(client.camera.look_at, look_at, atol=0.05)
                        and np.allclose(client.camera.position, position, atol=0.05))

        wait_until(framed, what="the page framed on both worlds")
        wait_until(lambda: app.runner.latest.sample.fraction_in_goal > 0, what="a share in the goal to show")
        canvas = max((c.bounding_box() for c in page.locator("canvas").all()), key=lambda b: b["width"] * b["height"])
        height = view_height(client)
        labels = {"left caption": caption_box(config, offset, False, height),
                  "right caption": caption_box(config, offset, True, height),
                  "left readout": readout_box(config), "right readout": shifted(readout_box(config), offset),
                  "difference": difference_box(config, offset)}
        shown = {name: floor_to_page(client, canvas, box) for name, box in labels.items()}

        def drawn(name: str) -> bool:
            """Whether the page draws the label there: viser gives a label a light background."""
            import io

            from PIL import Image

            picture = np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("L"))
            box = shown[name]
            x0, y0 = int(box["x"] + 0.3 * box["width"]), int(box["y"] + 0.2 * box["height"])
            x1, y1 = int(box["x"] + 0.7 * box["width"]), int(box["y"] + 0.5 * box["height"])
            return bool((picture[y0:y1, x0:x1] > 200).mean() > 0.3)

        for name in ("left readout", "right readout", "difference"):
            wait_until(lambda name=name: drawn(name), what=f"the {name} drawn where it was framed")
        shot(page, "room-compare.png")
        covering = page.evaluate(COVERING)  # read at once: a notice may close between a count and a look
        for name, box in shown.items():
            assert within(box, canvas), f"{name} at {box} is not all on the canvas {canvas}"
            for other in filter(None, covering):
                assert not covers(box, other), f"{name} at {box} lies under {other}"
    finally:
        if context is not None:
            context.close()
        app.stop()
