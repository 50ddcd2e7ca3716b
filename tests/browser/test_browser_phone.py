"""A phone can play it (issue 41, items 5 and 6) in the real page: headless Chromium at 390 x 844 with
touch (``has_touch``), taps through Playwright's touchscreen and a drag through real touch events
(CDP's ``Input.dispatchTouchEvent``), each checked on the server (the lamp, the lights); and a
challenge round at 1024 x 768. Set PHOTOTAXIS_SCREENSHOTS to a folder to keep the screenshots."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from sandbox.app.web.page_layout import SHORTCUTS_ID, SOFTWARE_NOTICE
from sandbox.app.world.orders import SetPlaying
from sandbox.app.world.snapshot import LAMP_PROGRAM, PAPER_PROGRAM
from tests.browsing import BROWSER_MARKS, largest_canvas
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS

PHONE = {"width": 390, "height": 844}


@pytest.fixture(scope="module")
def app():
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    app = App(Config(robots=40, boxes=80, update_every=20, hold_steps=5), port=free_port(), steps_per_frame=4,
              fps=15)
    app.start()
    yield app
    app.stop()


@pytest.fixture(scope="module")
def phone(app, browser):
    context = browser.new_context(viewport=PHONE, has_touch=True, is_mobile=True)
    page = context.new_page()
    page.goto(f"http://127.0.0.1:{app.port}/")
    page.get_by_text("Goal shape", exact=True).wait_for(state="attached")
    wait_until(lambda: app.server.get_clients(), what="the phone to connect")
    yield context, page
    context.close()


def screenshot(page, tmp_path: Path, name: str) -> Path:
    folder = Path(os.environ.get("PHOTOTAXIS_SCREENSHOTS") or tmp_path)
    path = folder / name
    page.screenshot(path=str(path))
    return path


def scene_box(page) -> dict:
    """The scene canvas's box on the page (the largest canvas)."""
    return largest_canvas(page)[1]


def drawer_height(page) -> float:
    return page.evaluate("""() => {
        const p = [...document.querySelectorAll('.mantine-Paper-root')].find(
            (p) => p.style.position === 'fixed' && p.style.bottom === '0px');
        return p ? p.getBoundingClientRect().height : -1;
    }""")


def test_a_phone_gets_the_arena_whole_a_drawer_and_no_lasting_notice(app, phone):
    _, page = phone
    shortcuts = page.locator(f"#{SHORTCUTS_ID}")
    shortcuts.wait_for()
    wait_until(lambda: 0 < drawer_height(page) < 90, what="the panel closed to its handle")
    drawer = page.evaluate("""() => [...document.querySelectorAll('.mantine-Paper-root')].find(
        (p) => p.style.position === 'fixed' && p.style.bottom === '0px').getBoundingClientRect().width""")
    assert drawer == PHONE["width"]  # the drawer spans the width: it covers no corner of the arena alone
    canvas = scene_box(page)
    assert canvas["width"] == PHONE["width"]
    # viser's own notice (the page draws in software here): it may come, and it goes by itself.
    notice = page.get_by_text(SOFTWARE_NOTICE)
    wait_until(lambda: notice.count() == 0, timeout=30, what="the software-rendering notice to close")
    for name in ("Be the light", "Challenge"):
        box = shortcuts.get_by_role("button", name=name, exact=True).bounding_box()
        assert box and box["y"] + box["height"] <= PHONE["height"] - 50  # above the drawer's handle


def test_touch_taps_and_a_drag_move_the_lamp_and_paint_lights(app, phone, tmp_path):
    context, page = phone
    runner, lamp = app.runner, app.panel.lamp
    runner.submit(SetPlaying(True))
    page.locator(f"#{SHORTCUTS_ID}").get_by_role("button", name="Be the light", exact=True).tap()
    wait_until(lambda: runner.latest.program == LAMP_PROGRAM, what="the lamp, from the shortcut")
    page.locator(f"#{SHORTCUTS_ID}").get_by_role("button", name="Give the light back", exact=True).wait_for()
    box = scene_box(page)
    cx, top = box["x"] + box["width"] / 2, box["y"]
    # The arena is framed at the top of a phone's view, as wide as the view: its middle is half a width down.
    cy = top + box["width"] / 2

    def tap(x: float, y: float) -> np.ndarray:
        before = lamp._centre
        page.touchscreen.tap(x, y)
        wait_until(lambda: lamp._centre != before, what=f"the lamp moved by a tap at ({x:.0f}, {y:.0f})")
        return np.array(lamp._centre)

    taps = [tap(cx - 80, cy), tap(cx + 80, cy), tap(cx, cy - 80)]
    assert taps[1][0] > taps[0][0] + 5 and taps[2][1] > taps[0][1] + 5  # right is +x, up is +y: the floor
    radius = float(lamp.radius.value)
    pitch = runner.latest.world_config.light_pitch

    def lit_within(centre: np.ndarray, reach: float) -> bool:
        lit = np.argwhere(runner.latest.intensities > 0)
        return len(lit) > 0 and np.hypot(*((lit + 0.5) * pitch - centre).T).max() <= reach

    wait_until(lambda: lit_within(taps[-1], radius), what="the lights about the last tap only")

    # A drag with real touch events: the lamp follows the finger, step by step, to where it is lifted.
    cdp = context.new_cdp_session(page)

    def touch(kind: str, x: float | None = None, y: float | None = None) -> None:
        points = [] if x is None else [{"x": x, "y": y, "id": 1}]
        cdp.send("Input.dispatchTouchEvent", {"type": kind, "touchPoints": points})

    def drag(path: list[tuple[float, float]]) -> list[np.ndarray]:
        seen = []
        before = lamp._centre
        touch("touchStart", *path[0])
        wait_until(lambda: lamp._centre != before, what="the lamp under the finger")
        seen.append(np.array(lamp._centre))
        for x, y in path[1:]:
            before = lamp._centre
            touch("touchMove", x, y)
            wait_until(lambda: lamp._centre != before, what=f"the lamp to follow the finger to ({x:.0f}, {y:.0f})")
            seen.append(np.array(lamp._centre))
        touch("touchEnd")
        return seen

    path = [(cx - 100 + 25 * i, cy + 60) for i in range(9)]  # 200 px to the right
    centres = drag(path)
    xs = [c[0] for c in centres]
    assert all(b > a for a, b in zip(xs, xs[1:])), xs  # along the finger, rightwards on the floor
    camera = app.server.get_clients()[max(app.server.get_clients())].camera
    looked = tuple(np.round(camera.look_at, 2))
    wait_until(lambda: lit_within(centres[-1], radius), what="the lamp's lights where the finger left")
    assert tuple(np.round(camera.look_at, 2)) == looked  # the finger led the lamp, not the camera
    screenshot(page, tmp_path, "phone-be-the-light.png")

    # With the brush, a drag paints a trail of lights.
    lamp.click_does.value = "paints lights on"
    centres = drag([(cx - 100 + 25 * i, cy - 40) for i in range(9)])
    span = centres[-1][0] - centres[0][0]
    lit = np.argwhere(runner.latest.intensities > 0)
    wait_until(lambda: np.ptp((np.argwhere(runner.latest.intensities > 0)[:, 0] + 0.5) * pitch) >= span,
               what="a painted trail as long as the drag")
    assert len(lit) > 0
    lamp.click_does.value = "moves the lamp"
    page.locator(f"#{SHORTCUTS_ID}").get_by_role("button", name="Give the light back", exact=True).tap()
    wait_until(lambda: runner.latest.program == PAPER_PROGRAM, what="the paper's controller back")


def test_the_challenge_is_one_tap_away_and_hints_on_a_phone(app, phone, tmp_path):
    _, page = phone
    folder = app.panel.challenge
    folder.round_steps, folder.hint_seconds = 100_000, 1.0  # a round that lasts, a hint soon
    page.locator(f"#{SHORTCUTS_ID}").get_by_role("button", name="Challenge", exact=True).tap()
    start = page.get_by_role("button", name="Start a round", exact=True)
    wait_until(lambda: start.is_visible() and start.bounding_box()["y"] < PHONE["height"], what="the folder in view")
    top = page.evaluate("""() => [...document.querySelectorAll('.mantine-Paper-root')].find(
        (p) => p.style.position === 'fixed' && p.style.bottom === '0px').getBoundingClientRect().top""")
    assert top >= PHONE["width"] - 4, top  # the open drawer stops below the arena (framed as wide as the page)
    start.tap()
    wait_until(lambda: folder.round is not None and folder.round.world is not None, what="the round's world")
    r = folder.round
    # the lamp is aimed at once and lights the floor at the controller's next update (CI read the frame between)
    wait_until(lambda: app.runner.latest.program == LAMP_PROGRAM and app.runner.latest.intensities.any(),
               what="the round's lamp, lit")
    robots = app.runner.latest.robot_positions
    lit = (np.argwhere(app.runner.latest.intensities > 0) + 0.5) * app.runner.latest.world_config.light_pitch
    centre = lit.mean(axis=0)
    near = np.hypot(*(robots - centre).T) <= float(app.panel.lamp.radius.value)
    assert near.sum() >= 2, (centre, near.sum())  # the lamp starts on robots, not over the empty goal
    page.get_by_text("Hint:", exact=False).first.wait_for()  # nothing brought in for a second
    page.get_by_text("brought in", exact=False).first.wait_for()
    path = screenshot(page, tmp_path, "phone-challenge.png")
    assert path.exists() and r.started is not None
    r.steps = 0  # the round ends at its next frame
    wait_until(lambda: r.score is not None, what="the round's end")
    wait_until(lambda: r.paper is not None, timeout=120, what="the paper's reference")
    folder.round_steps, folder.hint_seconds = 20_000, 10.0


def test_a_challenges_end_on_a_projector(app, browser, tmp_path):
    context = browser.new_context(viewport={"width": 1024, "height": 768})
    page = context.new_page()
    try:
        page.goto(f"http://127.0.0.1:{app.port}/")
        page.get_by_text("Goal shape", exact=True).wait_for()
        folder = app.panel.challenge
        folder.round_steps = 400
        earlier = folder.round  # an earlier test's round may have ended the same way: its verdict still shows
        page.get_by_text("Challenge", exact=True).first.click()
        page.get_by_role("button", name="Start a round", exact=True).click()
        wait_until(lambda: folder.round is not earlier and folder.round is not None
                   and folder.round.paper is not None, timeout=120, what="this round scored beside the paper's")
        r = folder.round
        wait_until(lambda: "the paper's controller:" in folder.status.content, what="this round's verdict")
        page.get_by_text("the paper's controller:", exact=False).first.wait_for()
        status = page.get_by_text("the paper's controller:", exact=False).first
        status.scroll_into_view_if_needed()
        box = status.bounding_box()
        assert box and box["x"] >= 0 and box["x"] + box["width"] <= 1024  # the whole verdict in view
        screenshot(page, tmp_path, "challenge-end-1024.png")
        assert r.score.started == r.paper.started  # the same world, counted the same way
    finally:
        folder.round_steps = 20_000
        context.close()
        app.panel.program.load(None, None)


def test_a_dropdowns_list_opens_on_the_screen_and_picks(app, phone):
    """viser places a dropdown's list for its 20em sheet and does not flip it: in the drawer it opened off
    the screen's right edge and below its bottom. On a phone it is a sheet along the screen's bottom."""
    _, page = phone
    if drawer_height(page) < 90:
        page.get_by_text("Phototaxis sandbox").first.tap()  # the drawer's handle
        wait_until(lambda: drawer_height(page) > 200, what="the drawer open")
    picker = page.get_by_label("group", exact=True)
    if not picker.is_visible():
        folder = page.get_by_text("Population and physics", exact=True).first
        folder.scroll_into_view_if_needed()
        folder.tap()
        picker.wait_for()
    picker.scroll_into_view_if_needed()
    picker.tap()
    option = page.get_by_role("option", name="Light grid", exact=True)
    option.wait_for()
    box = option.bounding_box()
    assert box and box["x"] >= 0 and box["x"] + box["width"] <= PHONE["width"], box
    assert box["y"] >= 0 and box["y"] + box["height"] <= PHONE["height"], box
    option.tap()
    wait_until(lambda: app.panel.parameters.group.value == "Light grid", what="the group picked on the server")
    page.get_by_label("light pitch (m)", exact=True).wait_for()
