"""The designer's page for the drawing tests (``test_browser_drawing``, ``test_browser_editing``): a
small app, a 1600x1000 page zoomed in on the construction area with the Draw folder open, and what a
designer does in it (clicks and drags on the floor, buttons, templates), each waiting on a condition.

Set PHOTOTAXIS_SHOTS=DIR to keep a screenshot of every step there.
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np

from tests.browsing import largest_canvas, playwright_api, small_app
from tests.waiting import wait_until, wait_until_steady


SHOTS = os.environ.get("PHOTOTAXIS_SHOTS")
#: Each drawing, from the first action to Close and use, should take a designer less than this (s).
#: Printed, not asserted: on a loaded machine (CI's two cores running two test workers and two
#: browsers) the page answers each action later and the C took 70 s, which measures the load, not
#: the tools. The test prints each drawing's time at the end.
DESIGN_LIMIT = 60.0
#: Steps the swarm must run on a new goal before it counts as built "a bit": enough for the screenshot
#: of the build (PHOTOTAXIS_SHOTS) to show one; without screenshots, enough to show the world runs on it
#: (400 steps were 6.7 s a drawing at the small world's 60 steps a second, 20 s of the module).
BUILD_STEPS = 400 if SHOTS else 60
#: Pointer moves in a drag of the drawing tests (each waits for a frame of the test browser's software
#: drawing, 0.5-2 s on a loaded machine); that a dragged point follows every move is
#: tests/browser/test_browser_editing.py's, with its own 12.
DRAG_STEPS = 4

L_ARMS = [(29, 29), (35, 29), (35, 31), (31, 31), (31, 35), (29, 35)]  # 6 m arms, 2 m wide
PLUS = "29,31; 31,31; 31,29; 33,29; 33,31; 35,31; 35,33; 33,33; 33,35; 31,35; 31,33; 29,33"


def designer_app():
    """The app under the page (a generator: each test module's ``app`` fixture yields from it)."""
    app = small_app()
    yield app
    app.stop()


def open_page(app, browser, width: int, height: int, prepare=None):
    """A new page on ``app``, loaded and counted by its server: (context, page, its client).
    ``prepare(page)`` runs before the page loads (a handler that must see everything, dialogs included)."""
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    if prepare is not None:
        prepare(page)
    before = set(app.server.get_clients())
    page.goto(f"http://127.0.0.1:{app.port}/")
    page.get_by_text("Goal shape", exact=True).wait_for()
    client = wait_until(lambda: next((c for k, c in app.server.get_clients().items() if k not in before), None),
                        what="the page to connect")
    return context, page, client


def designer_page(app, browser):
    """The designer's page (a generator: each test module's ``page`` fixture yields from it)."""
    context, page, client = open_page(app, browser, 1600, 1000)
    page.client, page.app = client, app
    wait_until(lambda: camera_settled(client, app.runner.latest.world_config), what="the camera framing")
    page.canvas = canvas_box(page)  # asked once: a busy page answers layout questions slowly
    zoom_in(page, client, ZOOMED_HEIGHT)
    page.get_by_text("Draw", exact=True).first.click()
    page.get_by_role("button", name="Start drawing", exact=True).wait_for()
    yield page
    context.close()


def dismiss_notifications(page) -> None:
    """Close the page's notices (headless Chromium is told its WebGL is software): they cover the floor."""
    close_all = "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click())"
    wait_until(lambda: page.evaluate(close_all) or not page.locator(".mantine-Notification-root").count(),
               what="the notices closed")


#: Seconds spent taking screenshots: not the designer's time.
SHOOTING = [0.0]


def clock() -> float:
    """Seconds of the designer's time so far (screenshots left out)."""
    return time.perf_counter() - SHOOTING[0]


def shot(page, name: str) -> None:
    if SHOTS:
        start = time.perf_counter()
        dismiss_notifications(page)
        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(Path(SHOTS) / f"{name}.png"))
        SHOOTING[0] += time.perf_counter() - start


def canvas_box(page) -> dict:
    return largest_canvas(page)[1]


def camera_settled(client, config) -> bool:
    """The page's camera framed the arena from above (the server does it once the page says its size)."""
    from sandbox.app.view.scene import top_down_camera

    aspect = client.camera.aspect
    position, _, _ = top_down_camera(config, aspect)
    return bool(aspect) and np.allclose(client.camera.position, position, atol=1e-3)


#: The camera's height (m) once the designer has zoomed in on the construction area with the wheel.
ZOOMED_HEIGHT = 28.0


def zoom_in(page, client, height: float) -> None:
    """Roll the mouse wheel over the middle of the floor, as a designer does, until the camera is
    this low and at rest (it eases in, reporting as it goes). Each notch of the wheel takes the camera
    the same share nearer (viser dollies by a factor per wheel event): the first notch, once at rest,
    says how many more reach ``height``, and those are rolled at once (a rest after each notch, five of
    them, took 5-6 s of each drawing module's set-up); notches one at a time finish, if need be."""
    box = page.canvas
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)

    def at_rest() -> float:  # a camera that has not moved for 0.25 s is at rest
        return wait_until_steady(lambda: round(float(client.camera.position[2]), 3), quiet=0.25, timeout=60)

    start = at_rest()
    if start <= height:
        return

    def roll(notches: int, z: float) -> float:
        """The camera's height at rest after ``notches`` more, once it has moved from ``z``."""
        for _ in range(notches):
            page.mouse.wheel(0, -400)
        return wait_until(lambda: (now := at_rest()) < z and now, 60, what="the camera nearer after the wheel")

    z = roll(1, start)
    share = z / start
    z = roll(math.ceil(math.log(height / z) / math.log(share)), z) if z > height else z
    while z > height:
        z = roll(1, z)


def to_screen(page, x: float, y: float) -> tuple[float, float]:
    """The pixel over floor point (x, y), projected through the page's camera (as the server last
    heard it: its position, where it looks, its up and its vertical field of view)."""
    camera = page.client.camera
    box = page.canvas
    position, look_at = np.asarray(camera.position, float), np.asarray(camera.look_at, float)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, np.asarray(camera.up_direction, float))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    v = np.array([x, y, 0.0]) - position
    depth, half_height = float(v @ forward), float(np.tan(camera.fov / 2.0))
    half_width = half_height * box["width"] / box["height"]
    return (box["x"] + box["width"] / 2.0 * (1.0 + float(v @ right) / (depth * half_width)),
            box["y"] + box["height"] / 2.0 * (1.0 - float(v @ up) / (depth * half_height)))


def click_floor(page, x: float, y: float) -> None:
    page.mouse.click(*to_screen(page, x, y))


def drag_floor(page, start, end, steps: int = DRAG_STEPS, during=None) -> None:
    """Press at ``start``, move to ``end`` in steps (calling ``during()`` half-way), release."""
    page.mouse.move(*to_screen(page, *start))
    page.mouse.down()
    for k in range(1, steps + 1):
        t = k / steps
        page.mouse.move(*to_screen(page, start[0] + t * (end[0] - start[0]), start[1] + t * (end[1] - start[1])))
        if during is not None and k == steps // 2:
            during()
    # the page sends drag updates about 20 times a second: let the last position arrive before the release
    page.mouse.move(*to_screen(page, *end))
    page.mouse.up()


def button(page, name: str):
    return page.get_by_role("button", name=name, exact=True)


def status(page) -> str:
    return page.locator("p", has_text="Close and use").first.inner_text() if page.locator(
        "p", has_text="Close and use").count() else ""


def status_says(page, text: str) -> None:
    """The Draw folder's status line on the page says ``text``. A failure tells a server that never
    wrote it from a page that never drew it (twice under two suites at once, cause not found)."""
    try:
        page.get_by_text(text, exact=False).first.wait_for()
    except playwright_api.Error as exc:
        server_says = page.app.panel.shape.draw.status.content if hasattr(page, "app") else "?"
        raise AssertionError(f"the page did not show {text!r} ({type(exc).__name__}); the server's status "
                             f"line says {server_says!r}") from None


def choose(page, label: str, option: str) -> None:
    field = page.get_by_label(label, exact=True)
    for _ in range(5):
        field.click()
        item = page.get_by_role("option", name=option, exact=True)
        item.wait_for(state="visible")
        item.click()
        try:
            wait_until(lambda: item.count() == 0 or not item.is_visible(), 3, f"{label} closed")
            return
        except AssertionError:
            continue
    raise AssertionError(f"could not choose {option!r} in {label!r}")


#: How long each drawing took, from its first action to the goal in use (s, screenshots left out),
#: printed at the end.
TIMES: dict[str, float] = {}


def use(app, page, name: str, vertices: int, began: float) -> None:
    """Close and use; the drawing's time ends when the new world on the goal has started (the goal is
    set first and the world then starts afresh: a build measured from before that start, on a loaded
    machine, counted from the old world's step and timed out)."""
    world = app.runner.latest.world_key
    button(page, "Close and use").click()
    wait_until(lambda: app.runner.latest.world_key != world and app.runner.latest.shape_name == "drawn",
               what=f"a new world on the drawn {name}")
    TIMES[name] = clock() - began
    assert len(app.runner.latest.goal_vertices) == vertices
    if TIMES[name] >= DESIGN_LIMIT:
        print(f"\nthe {name} took {TIMES[name]:.0f} s (more than {DESIGN_LIMIT:.0f} s: a loaded machine?)")


def build(app, page, name: str) -> None:
    """Let the swarm work on the new goal for a while."""
    start = app.runner.latest.step
    wait_until(lambda: app.runner.latest.step >= start + BUILD_STEPS, 60, what=f"the swarm to build the {name}")
    shot(page, f"{name}-building")


def drag_vertex(page, draw, number: int, to, attempts: int = 3, steps: int = DRAG_STEPS) -> None:
    """Drag the handle of vertex ``number`` (as the floor shows it) to ``to``. The server has a point
    before the page draws its handle: a press that came first (once, on a loaded machine, right after a
    template was chosen) turned the camera instead, and while drawing one sometimes placed a new point
    where it was released (the press reached the drawing pad under the handle: seen with the default
    world's heavier page, 3 frames a second, not on the small one). Then the stray point is undone, the
    camera put back and the drag made again, as a designer would."""
    target, camera = tuple(map(float, to)), page.client.camera
    kept = (tuple(camera.position), tuple(camera.look_at), tuple(camera.up_direction))
    before = list(draw.points)
    for attempt in range(1, attempts + 1):
        camera_still(page)
        drag_floor(page, draw.points[number - 1], to, steps)
        moved = lambda: draw.points[number - 1] == target and len(draw.points) == len(before)  # noqa: E731
        strayed = lambda: len(draw.points) > len(before)  # noqa: E731 - the press missed: a new point
        try:
            wait_until(lambda: moved() or strayed(), 20, what=f"vertex {number} at {to}")
            if moved():
                return
        except AssertionError:
            if attempt == attempts:
                raise
        print(f"\ndrag {attempt} of vertex {number} missed: {draw.points}")
        assert attempt < attempts, f"vertex {number} never reached {to}"
        if strayed():
            button(page, "Undo last point").click()
            wait_until(lambda: draw.points == before, 20, what="the stray point taken back")
        camera.position, camera.look_at, camera.up_direction = kept


def camera_still(page) -> None:
    """Wait until the page's camera, as the server last heard it, has stopped moving: a click aimed
    through a camera still easing (after a drag, or a new view) lands elsewhere on the page."""
    camera = page.client.camera
    wait_until_steady(lambda: (tuple(np.round(camera.position, 4)), tuple(np.round(camera.look_at, 4))))


def click_edge(page, draw, at, edge: int, attempts: int = 3) -> None:
    """Click edge ``edge`` (from point ``edge`` to the next, counted from 0) at floor point ``at``: a
    point inserted there. A click that landed elsewhere (a new point last, or on another edge) is taken
    back as a designer would (Undo, or Delete point for an inserted one, which is selected) and made
    again."""
    target, before = tuple(map(float, at)), list(draw.points)
    for attempt in range(1, attempts + 1):
        camera_still(page)
        click_floor(page, *target)
        try:
            wait_until(lambda: len(draw.points) == len(before) + 1, 20, what=f"a point inserted at {at}")
        except AssertionError:
            print(f"\nclick {attempt} on edge {edge} made no point")
            if attempt == attempts:
                raise
            continue
        if draw.points[edge + 1] == target:
            return
        print(f"\nclick {attempt} on edge {edge} missed: {draw.points}")
        assert attempt < attempts, f"the click meant for edge {edge} at {at} made {draw.points}"
        button(page, "Delete point" if draw.selected is not None else "Undo last point").click()
        wait_until(lambda: draw.points == before, 20, what="the stray point taken back")


def at_pace(due: float) -> None:
    """Hold the next click until ``due`` (clock()): the designer's pace. It waits for nothing in the page."""
    wait_until(lambda: clock() >= due, what="the designer's next click", poll=0.01)


def snapped(p, step: float = 0.5) -> tuple[float, float]:
    from sandbox.shapes.drawing import snap

    return snap(p, step)


def clear(page, draw) -> None:
    """No points (Clear is off when there are none)."""
    if draw.points:
        button(page, "Clear").click()
    wait_until(lambda: not draw.points, what="cleared")


def enter_draw_mode(page, draw) -> None:
    """Start drawing unless the page already is, and wait for the drag surface."""
    if not draw.drawing:
        button(page, "Start drawing").click()
    wait_until(lambda: draw.drawing and draw.view._pad is not None, what="draw mode")


def points_once_landed(draw, count: int, timeout: float) -> list:
    """The drawing's points once ``count`` have reached the server, or after ``timeout`` s as they are:
    the caller compares them with its targets, which names a lost click."""
    try:
        wait_until(lambda: len(draw.points) >= count, timeout=timeout, what=f"{count} points")
    except AssertionError:
        pass
    return list(draw.points)


def start_drawing_on_an_l(page, draw) -> list[tuple[float, float]]:
    """The L template's points in the drawing (6 m arms, on the grid, centred), and draw mode on."""
    clear(page, draw)
    choose(page, "Template", "L")
    wait_until(lambda: len(draw.points) == 6, what="the L template")
    enter_draw_mode(page, draw)
    wait_until(lambda: draw.view._handles is not None and draw.view.handles_shown == 6,
               what="the L's handles")
    return list(draw.points)
