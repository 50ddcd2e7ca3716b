"""A real page's own messages pass the budgets and the decoding untouched (issue 54, F): the camera
turned by a drag, a slider held by its arrow keys, buttons clicked. None of them is malformed, none
waits for a budget or is dropped (sandbox.app.web.rates, sandbox.app.web.well_formed): the budgets are above
what viser's client sends, and the structures match what it sends."""

from __future__ import annotations

import pytest

from tests.browsing import BROWSER_MARKS, small_app
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS


@pytest.fixture(scope="module")
def app():
    app = small_app()
    yield app
    app.stop()


def test_a_pages_own_messages_are_never_refused_held_or_dropped(app, browser):
    page = browser.new_page(viewport={"width": 1100, "height": 760})
    page.goto(f"http://127.0.0.1:{app.port}/")
    page.get_by_text("Goal shape", exact=True).wait_for()
    client_id = next(iter(wait_until(app.server.get_clients, what="the page to connect")))
    camera = app.server.get_clients()[client_id].camera
    canvases = page.locator("canvas").all()
    box = max((c.bounding_box() or {"width": 0, "height": 0} for c in canvases),
              key=lambda b: b["width"] * b["height"])
    start = tuple(camera.position)
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    for step in range(40):  # a drag turning the view: viser's client sends its camera every 20 ms at most
        page.mouse.move(x + 6 * step, y + 2 * step)
        page.wait_for_timeout(25)
    page.mouse.up()
    wait_until(lambda: tuple(camera.position) != start, what="the turned camera")
    speed = app.runner.steps_per_frame
    thumb = page.get_by_role("slider").first  # "Steps per frame"
    thumb.focus()
    thumb.press("ArrowRight", delay=200)
    thumb.press("ArrowRight", delay=200)
    wait_until(lambda: app.runner.steps_per_frame == speed + 2, what="the speed to change")
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not app.runner.playing, what="pause")
    page.get_by_role("button", name="Play", exact=True).click()
    wait_until(lambda: app.runner.playing, what="play")
    counts = app.gate.flow(client_id).counts
    print(dict(counts))
    assert counts["read"] >= 10 and counts["malformed"] == 0, dict(counts)
    assert counts["replaced"] == 0 and counts["dropped"] == 0, dict(counts)
    page.close()
