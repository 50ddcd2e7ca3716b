"""The drawing tools in the real page (headless Chromium): a designer draws an L
with 6 m arms by clicks and a press-drag-release, a C from its template with a
vertex dragged (and dragged across to see the red crossing), and a plus from
typed points; each is used and built for a while. Then: 30 clicks 0.3 s apart
on the running page give 30 points; a click on an edge inserts a point, the
Delete point button and the Delete key remove the selected one; a dragged
point follows the pointer while the button is down. Waits are for conditions,
never fixed sleeps (the clicks' pace is the designer's, not a wait).

Set PHOTOTAXIS_SHOTS=DIR to keep a screenshot of every step there.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

from tests.browsing import BROWSER_MARKS, playwright_api, small_app
from tests.waiting import wait_until, wait_until_steady

pytestmark = BROWSER_MARKS

SHOTS = os.environ.get("PHOTOTAXIS_SHOTS")
#: Each drawing, from the first action to Close and use, should take a designer less than this (s).
#: Printed, not asserted: on a loaded machine (CI's two cores running two test workers and two
#: browsers) the page answers each action later and the C took 70 s, which measures the load, not
#: the tools. The test prints each drawing's time at the end.
DESIGN_LIMIT = 60.0
#: Steps the swarm must run on a new goal before it counts as built "a bit".
BUILD_STEPS = 400

L_ARMS = [(29, 29), (35, 29), (35, 31), (31, 31), (31, 35), (29, 35)]  # 6 m arms, 2 m wide
PLUS = "29,31; 31,31; 31,29; 33,29; 33,31; 35,31; 35,33; 33,33; 33,35; 31,35; 31,33; 29,33"


@pytest.fixture(scope="module")
def app():
    app = small_app()
    yield app
    app.stop()


def open_page(app, browser, width: int, height: int):
    context = browser.new_context(viewport={"width": width, "height": height})
    page = context.new_page()
    before = set(app.server.get_clients())
    page.goto(f"http://127.0.0.1:{app.port}/")
    page.get_by_text("Goal shape", exact=True).wait_for()
    client = wait_until(lambda: next((c for k, c in app.server.get_clients().items() if k not in before), None),
                        what="the page to connect")
    return context, page, client


@pytest.fixture(scope="module")
def page(app, browser):
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
    canvases = page.locator("canvas").all()
    boxes = [c.bounding_box() or {"x": 0, "y": 0, "width": 0, "height": 0} for c in canvases]
    return max(boxes, key=lambda b: b["width"] * b["height"])


def camera_settled(client, config) -> bool:
    """The page's camera framed the arena from above (the server does it once the page says its size)."""
    from sandbox.app.scene import top_down_camera

    aspect = client.camera.aspect
    position, _, _ = top_down_camera(config, aspect)
    return bool(aspect) and np.allclose(client.camera.position, position, atol=1e-3)


#: The camera's height (m) once the designer has zoomed in on the construction area with the wheel.
ZOOMED_HEIGHT = 28.0


def zoom_in(page, client, height: float) -> None:
    """Roll the mouse wheel over the middle of the floor, as a designer does, until the camera is
    this low and at rest (it eases in, reporting as it goes)."""
    box = page.canvas
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    last = [None]

    def low_and_resting() -> bool:
        z = round(float(client.camera.position[2]), 3)
        resting, last[0] = z == last[0], z
        if resting and z > height:
            page.mouse.wheel(0, -400)
            last[0] = None
        return resting and z <= height

    # Polled every 0.25 s: a camera that has not moved in that time is at rest.
    wait_until(low_and_resting, 60, what="the camera zoomed in and at rest", poll=0.25)


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


def drag_floor(page, start, end, steps: int = 12, during=None) -> None:
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


def drag_vertex(page, draw, number: int, to, attempts: int = 3, steps: int = 12) -> None:
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


# ----------------------------------------------------------------------- tests
def test_draw_an_l_by_clicks_and_a_drag(app, page):
    draw = app.panel.shape.draw
    status_says(page, "No points yet")
    shot(page, "l-0-empty")
    began = clock()
    button(page, "Start drawing").click()
    wait_until(lambda: draw.drawing and draw.view._pad is not None, what="draw mode")
    for k, (x, y) in enumerate(L_ARMS[:3]):
        click_floor(page, x, y)
        wait_until(lambda: len(draw.points) == k + 1, what=f"point {k + 1}")
        if k == 1:
            status_says(page, "needs at least 3 points")
            shot(page, "l-1-two-points")
    # Point 4 by press, drag and release: the rubber band from point 3 follows the pointer.
    rubber = []
    drag_floor(page, (33, 33), L_ARMS[3], during=lambda: rubber.append(
        wait_until(lambda: draw.view.rubber.visible, what="the rubber band")) or shot(page, "l-1-rubber-band"))
    wait_until(lambda: len(draw.points) == 4, what="point 4 placed by the drag")
    assert rubber and not draw.view.rubber.visible
    for k, (x, y) in enumerate(L_ARMS[4:], 4):
        click_floor(page, x, y)
        wait_until(lambda: len(draw.points) == k + 1, what=f"point {k + 1}")
    assert draw.points == [tuple(map(float, p)) for p in L_ARMS]  # snapped to the 0.5 m grid
    status_says(page, "Ready")
    assert draw.view.preview_goal.visible and draw.view.preview_band.visible
    # The point is stored before the floor shows it (the click's callback draws it next): wait for the labels.
    wait_until(lambda: [label.text for label in draw.view._labels] == ["1", "2", "3", "4", "5", "6"],
               what="six numbered points on the floor")
    shot(page, "l-2-drawn")
    use(app, page, "L", 6, began)
    assert not draw.drawing and draw.points == [tuple(map(float, p)) for p in L_ARMS]  # kept, to tweak
    build(app, page, "L")


def test_draw_a_c_from_its_template_and_untangle_a_crossing(app, page):
    draw = app.panel.shape.draw
    began = clock()
    choose(page, "Template", "C")
    wait_until(lambda: len(draw.points) == 8, what="the C template's 8 points")
    x, y = draw.points[0]  # the template's lower-left corner, centred on the assembly centre
    assert draw.points[3] == (x + 2, y + 2) and draw.points[4] == (x + 2, y + 4)  # the slot's inner corners
    shot(page, "c-0-template")
    drag_vertex(page, draw, 4, (x + 1, y + 2))  # a deeper slot
    drag_vertex(page, draw, 5, (x + 1, y + 4))
    # Pull vertex 3 up past the slot: edge 3-4 crosses 5-6 and the outline runs back along 6-7.
    drag_vertex(page, draw, 3, (x + 6, y + 5))
    wait_until(lambda: draw.view.crossing.visible, what="the crossing edges in red")
    status_says(page, "touches itself")  # vertex 6 now lies on edge 2-3, and 3-4 crosses 5-6:
    status_says(page, "In red on the floor: edges 2-3, 3-4, 5-6 and 6-7")
    assert button(page, "Close and use").is_disabled()
    shot(page, "c-1-crossing")
    drag_vertex(page, draw, 3, (x + 6, y + 2))
    wait_until(lambda: not draw.view.crossing.visible, what="no red edge")
    status_says(page, "Ready")
    shot(page, "c-2-edited")
    use(app, page, "C", 8, began)
    build(app, page, "C")


def test_draw_a_plus_from_typed_points(app, page):
    draw = app.panel.shape.draw
    began = clock()
    # viser does not tie the label to its text area: the first one after the label
    points = page.locator("xpath=//*[normalize-space(text())='Points']/following::textarea"
                          "[contains(@class, 'mantine-Textarea-input')][1]")
    before = list(draw.points)  # the C, kept after Close and use
    points.fill("29,31; 31,31; 31")
    wait_until(lambda: draw.typed.value == "29,31; 31,31; 31", what="the typed text at the server")
    button(page, "Apply points").click()
    status_says(page, "Points not applied")
    page.get_by_text("'31' is not two numbers").first.wait_for()
    assert draw.points == before  # nothing applied
    shot(page, "plus-0-typo")
    points.fill(PLUS)
    wait_until(lambda: draw.typed.value == PLUS, what="the typed text at the server")
    button(page, "Apply points").click()
    wait_until(lambda: len(draw.points) == 12, what="the plus's 12 points")
    status_says(page, "Ready")
    shot(page, "plus-1-typed")
    use(app, page, "plus", 12, began)
    build(app, page, "plus")
    print("\n" + "\n".join(f"{name} designed and in use in {seconds:.1f} s" for name, seconds in TIMES.items()))


# A phone (390 x 844) now gets the panel as a closed drawer (sandbox.app.page_layout; tests/test_browser_phone.py);
# drawing on a phone's drawer is not driven here yet.
@pytest.mark.parametrize("width, height", [(1024, 768)])
def test_small_viewports_show_the_tools(app, browser, width, height):
    context, page, client = open_page(app, browser, width, height)
    try:
        page.get_by_text("Draw", exact=True).first.click()
        choose(page, "Template", "letter E")
        wait_until(lambda: len(app.panel.shape.draw.points) == 12, what="the E template")
        status_says(page, "Ready")
        shot(page, f"viewport-{width}x{height}")
        page.get_by_role("button", name="Clear", exact=True).click()
        wait_until(lambda: not app.panel.shape.draw.points, what="cleared")
    finally:
        context.close()


# ------------------------------------------- every click lands; insert, delete, follow (issue 40, item 3)
#: The designer's pace in the click test: a click every this many seconds, 30 of them.
CLICK_EVERY, CLICKS = 0.3, 30


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


def test_thirty_clicks_at_a_persons_pace_give_thirty_points(app, page):
    draw = app.panel.shape.draw
    clear(page, draw)
    enter_draw_mode(page, draw)
    assert app.runner.playing  # a running page: frames keep coming while the designer clicks
    c = app.runner.latest.world_config.centre
    # Round a 6 m circle, on the grid's nodes (a click a hair off still snaps there): 0.55 m apart or
    # more, so each click is off every point's handle and every edge before it.
    angles = np.linspace(0.0, 2.0 * np.pi, CLICKS, endpoint=False)
    targets = [snapped((c + 6.0 * np.cos(a), c + 6.0 * np.sin(a))) for a in angles]
    camera_still(page)  # an earlier test's drag may have put the camera back: aim once it is still
    began = clock()
    for k, (x, y) in enumerate(targets):
        at_pace(began + k * CLICK_EVERY)
        click_floor(page, x, y)
    clicked = clock() - began
    points = points_once_landed(draw, CLICKS, timeout=30.0)
    landed = clock() - began
    lost = [(k, t) for k, t in enumerate(targets) if t not in points]
    stray = [p for p in points if p not in targets]
    assert points == targets, f"lost clicks (index, point): {lost}; stray points: {stray}"
    shot(page, "clicks-30")
    print(f"\n{CLICKS} clicks made in {clicked:.1f} s (due every {CLICK_EVERY} s), all {CLICKS} points at the "
          f"server {landed:.1f} s after the first")


#: Three clicks on the scene's canvas in one turn of the page's script, as a page that was busy handles
#: the presses that waited for it: one after the other, well inside viser's 20 ms throttle window.
CLICKS_IN_ONE_TURN_JS = """(points) => {
  for (const [x, y] of points) {
    const target = document.elementFromPoint(x, y);  // the canvas a real press there reaches
    for (const type of ["pointerdown", "pointerup"]) {
      target.dispatchEvent(new PointerEvent(type, {bubbles: true, cancelable: true, composed: true,
        pointerId: 1, pointerType: "mouse", isPrimary: true, button: 0, buttons: type === "pointerdown" ? 1 : 0,
        clientX: x, clientY: y}));
    }
  }
}"""


def test_three_clicks_the_page_handles_at_once_give_three_points(app, page):
    """The lost click of the thirty (sandbox.app.page_sends): three clicks handled within 20 ms gave the
    first and the last, the middle one merged into the last by viser's throttle."""
    draw = app.panel.shape.draw
    clear(page, draw)
    enter_draw_mode(page, draw)
    c = app.runner.latest.world_config.centre
    targets = [snapped((c + dx, c + dy)) for dx, dy in ((-4.0, -3.0), (0.0, 4.0), (4.0, -3.0))]
    camera_still(page)
    page.evaluate(CLICKS_IN_ONE_TURN_JS, [list(to_screen(page, *t)) for t in targets])
    assert points_once_landed(draw, len(targets), timeout=20.0) == targets


def test_a_click_on_an_edge_inserts_a_point_and_delete_removes_the_selected_one(app, page):
    from sandbox.app.draw_view import SELECTED_COLOUR

    draw = app.panel.shape.draw
    el = start_drawing_on_an_l(page, draw)
    began = clock()
    middle = ((el[0][0] + el[1][0]) / 2, (el[0][1] + el[1][1]) / 2)  # of edge 1-2, 6 m long: a grid node
    click_floor(page, middle[0] + 0.1, middle[1] + 0.05)  # on the edge, a few pixels off its line
    wait_until(lambda: len(draw.points) == 7, what="the point inserted on edge 1-2")
    assert draw.points == [el[0], middle, *el[1:]] and draw.selected == 1
    status_says(page, "Point 2 selected")
    wait_until(lambda: not button(page, "Delete point").is_disabled(), what="Delete point enabled")
    shot(page, "edit-1-inserted")
    button(page, "Delete point").click()
    wait_until(lambda: draw.points == el, what="the inserted point deleted by the button")
    wait_until(lambda: button(page, "Delete point").is_disabled(), what="Delete point off: nothing selected")
    click_floor(page, el[2][0] + 0.05, el[2][1] - 0.05)  # point 3's handle: selects it, adds nothing
    wait_until(lambda: draw.selected == 2, what="point 3 selected")
    status_says(page, "Point 3 selected")  # the page has it (and its keys on) before the key is pressed
    wait_until(lambda: tuple(draw.view._handles.batched_colors[2]) == SELECTED_COLOUR, what="point 3 shown selected")
    assert len(draw.points) == 6
    shot(page, "edit-2-selected")
    page.keyboard.press("Delete")
    wait_until(lambda: draw.points == [*el[:2], *el[3:]], what="point 3 deleted by the Delete key")
    click_floor(page, *el[1])  # point 2
    wait_until(lambda: draw.selected == 1, what="point 2 selected")
    status_says(page, "Point 2 selected")  # the page has it (and its keys on) before the key is pressed
    page.keyboard.press("Backspace")
    wait_until(lambda: draw.points == [el[0], *el[3:]], what="point 2 deleted by Backspace")
    TIMES["insert and delete"] = clock() - began
    shot(page, "edit-3-deleted")


def test_a_dragged_point_follows_the_pointer(app, page):
    draw = app.panel.shape.draw
    el = start_drawing_on_an_l(page, draw)
    heard: list[tuple[float, str, tuple]] = []  # what the server hears of the drag: (time, phase, point)
    on_drag = draw.view._on_vertex_drag
    draw.view._on_vertex_drag = lambda index, phase, point: heard.append((clock(), phase, point)) or on_drag(
        index, phase, point)
    start, steps = el[2], 12
    end = (start[0] + 3.0, start[1] + 3.0)
    path = [(start[0] + (end[0] - start[0]) * k / steps, start[1] + (end[1] - start[1]) * k / steps)
            for k in range(1, steps + 1)]
    seen = []  # the point's position at the server after each move, the button still down
    try:
        page.mouse.move(*to_screen(page, *start))
        page.mouse.down()
        began = clock()
        for p in path:
            page.mouse.move(*to_screen(page, *p))
            seen.append(draw.points[2])
        # The button still down: the point, its handle and the outline reach the pointer.
        wait_until(lambda: draw.points[2] == snapped(path[-2]) or draw.points[2] == snapped(end),
                   what="the point at the pointer before the release")
        wait_until(lambda: np.allclose(draw.view._handles.batched_positions[2, :2], draw.points[2]),
                   what="its handle with it")
        followed = clock() - began
        shot(page, "drag-following")
    finally:
        page.mouse.up()
        draw.view._on_vertex_drag = on_drag
    wait_until(lambda: draw.points[2] == snapped(end), what="the point where it was let go")
    updates = [t for t, phase, _ in heard if phase == "update"]
    moved = sorted({p for p in seen if p != start})
    print(f"\ndrag: {len(updates)} updates at the server for {steps} moves in {followed:.1f} s "
          f"({len(updates) / max(followed, 1e-9):.1f} a second); {len(moved)} positions seen while moving")
    assert len(moved) >= steps // 3  # the point moved with the pointer, not only at the release


#: The designer's loop, end to end (issue 40's "one minute from idea to answer"): its time is printed;
#: the bar (60 s on this machine, alone) is measured with the default world, not on a loaded test run.
LOOP_END = 100_000


def test_from_idea_to_answer_draw_tweak_use_run_to_the_end_and_read(app, page):
    """Draw an L with 6 m arms by clicks at a person's pace (one every 0.5 s), move one vertex, insert
    one, use it and run it to 100,000 steps without drawing (one button), and read the result in the
    page."""
    draw, result = app.panel.shape.draw, app.panel.result
    clear(page, draw)
    began = clock()
    enter_draw_mode(page, draw)
    for k, (x, y) in enumerate(L_ARMS):
        at_pace(began + 0.5 * (k + 1))
        click_floor(page, x, y)
    wait_until(lambda: len(draw.points) == 6, what="the L's six points")
    at_pace(began + 0.5 * (len(L_ARMS) + 1))
    # the short arm 3 m wide instead of 2; a quick drag (each move waits for a frame of the test browser's
    # software drawing, 3-7 a second)
    drag_vertex(page, draw, 3, (35, 32), steps=3)
    click_edge(page, draw, (32.0, 29.0), 0)  # on edge 1-2, half-way: a point inserted there
    assert (35.0, 32.0) in draw.points and (29.0, 29.0) in draw.points  # the moved vertex kept, one more point
    shot(page, "loop-1-tweaked")
    if app.panel.run.end_step.value != LOOP_END:  # 100,000 is where the field starts: a designer leaves it
        field = page.get_by_label("Run to step", exact=True)
        field.scroll_into_view_if_needed()
        field.fill(str(LOOP_END))
        field.press("Tab")
        wait_until(lambda: app.panel.run.end_step.value == LOOP_END, what="the end step")
    world, drawn = app.runner.latest.world_key, clock() - began
    button(page, "Use and run to the end").click()  # Close and use, then Run to the end: one action
    wait_until(lambda: app.runner.latest.world_key != world and app.runner.latest.shape_name == "drawn",
               what="a new world on the drawn L")
    used = clock() - began
    wait_until(lambda: app.runner.latest.step >= LOOP_END, 300, what="the end of the run")
    ran = clock() - began
    page.get_by_text("of the boxes in the goal", exact=False).first.wait_for()  # the answer, in the page
    read = clock() - began
    assert "perfect packing" in result.text.content and result.rings is not None
    shot(page, "loop-2-answer")
    print(f"\nfrom the first click to the answer at step {LOOP_END:,}: {read:.0f} s (drawn and tweaked at "
          f"{drawn:.0f} s, the new world at {used:.0f} s, step {LOOP_END:,} at {ran:.0f} s)")
