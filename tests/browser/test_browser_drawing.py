"""The drawing tools in the real page (headless Chromium): a designer draws an L
with 6 m arms by clicks and a press-drag-release, a C from its template with a
vertex dragged (and dragged across to see the red crossing), and a plus from
typed points; each is used and built for a while; the tools at 1024x768.
Waits are for conditions, never fixed sleeps. The page and the designer's
actions: tests/drawing_page.py.
"""

from __future__ import annotations

import pytest

from tests.browsing import BROWSER_MARKS
from tests.drawing_page import (L_ARMS, PLUS, TIMES, build, button, choose, click_floor, clock, designer_app,
                                 designer_page, drag_floor, drag_vertex, shot,
                                 status_says, use)
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS


@pytest.fixture(scope="module")
def app():
    yield from designer_app()


@pytest.fixture(scope="module")
def page(app, browser):
    yield from designer_page(app, browser)


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


# A phone (390 x 844) now gets the panel as a closed drawer (sandbox.app.web.page_layout; tests/browser/test_browser_phone.py);
# drawing on a phone's drawer is not driven here yet.
@pytest.mark.parametrize("width, height", [(1024, 768)])
def test_small_viewports_show_the_tools(app, page, width, height):
    """The module's page, narrowed to the viewport (a page of its own cost a load and a connect: 10-16 s of
    a worker, for the same tools at the same size). Last in the module: the page stays this size."""
    page.set_viewport_size({"width": width, "height": height})
    wait_until(lambda: page.evaluate("[innerWidth, innerHeight]") == [width, height], what=f"the page at {width}x{height}")
    draw, template = app.panel.shape.draw, page.get_by_label("Template", exact=True)
    if template.is_visible():  # the Draw folder open (the module's page opened it): closed, to open it at this size
        page.get_by_text("Draw", exact=True).first.click()
        template.wait_for(state="hidden")
    page.get_by_text("Draw", exact=True).first.click()
    before = list(draw.points)  # the plus's 12, kept after Close and use
    choose(page, "Template", "letter E")
    wait_until(lambda: len(draw.points) == 12 and draw.points != before, what="the E template")
    status_says(page, "Ready")
    shot(page, f"viewport-{width}x{height}")
    page.get_by_role("button", name="Clear", exact=True).click()
    wait_until(lambda: not draw.points, what="cleared")
