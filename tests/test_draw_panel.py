"""The Draw folder's state machine on a live server, without a browser: scene
clicks and drags are called as viser would call them, controls are set over
the wire as a page sets them (so the gate checks them as it checks every
control)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.app.panel.draw import PICK_TEMPLATE, status_text
from sandbox.app.draw_view import DIM_OPACITY  # noqa: I001 - after the panel, which imports it first
from sandbox.model.geometry import signed_area
from sandbox.shapes.templates import template_vertices
from tests.test_security import connected, make_app, own_page, uuid_of, wait_until
from tests.viser_wire import RawClient

SQUARE = [(10.0, 10.0), (14.0, 10.0), (14.0, 14.0), (10.0, 14.0)]


@pytest.fixture(scope="module")
def app():
    a = make_app()
    yield a
    a.stop()


@pytest.fixture
def draw(app):
    folder = app.panel.shape.draw
    folder._change([])
    folder._set_drawing(False)
    folder.snap_on.value, folder.grid.value = True, 0.5
    yield folder
    folder._change([])
    folder._set_drawing(False)


@pytest.fixture
def page(app):
    client = RawClient(app.port, own_page(app))
    connected(app, client)
    yield client
    client.close()


def test_clicks_add_snapped_points_only_while_drawing(draw):
    assert not draw.click((10.2, 9.9))  # not drawing: the inspector's click
    draw._set_drawing(True)
    assert draw.view._pad is not None  # drags on the floor place points now
    assert draw.view._pad.opacity == DIM_OPACITY > 0.3  # and the live scene is dimmed under the drawing
    for x, y in [(10.2, 9.9), (13.8, 10.1), (14.1, 14.2)]:
        assert draw.click((x, y))
    assert draw.points == [(10.0, 10.0), (14.0, 10.0), (14.0, 14.0)]
    assert draw.click((10.1, 10.2)) and len(draw.points) == 3  # on point 1: grabs it, adds nothing
    draw.snap_on.value = False
    draw.click((10.3, 13.7))
    assert draw.points[-1] == (10.3, 13.7)
    draw._set_drawing(False)
    assert draw.view._pad is None


def test_press_drag_release_places_a_point_with_a_rubber_band(draw):
    draw._set_drawing(True)
    draw.click((10, 10))
    draw.pad_drag("start", (11.0, 11.0))
    draw.pad_drag("update", (12.2, 12.9))
    assert draw.view.rubber.visible and len(draw.points) == 1
    np.testing.assert_allclose(draw.view.rubber.points[0, :, :2], [(10, 10), (12.0, 13.0)])  # snapped end
    draw.pad_drag("end", (12.2, 12.9))
    assert draw.points == [(10.0, 10.0), (12.0, 13.0)] and not draw.view.rubber.visible


def test_dragging_a_handle_moves_its_vertex_and_keeps_the_numbers(draw):
    draw._change(SQUARE)
    assert [label.text for label in draw.view._labels] == ["1", "2", "3", "4"]
    draw.vertex_drag(2, "start", (14.0, 14.0))
    assert not draw.view.preview_goal.visible  # recomputed at the release
    draw.vertex_drag(2, "update", (15.3, 15.6))
    draw.vertex_drag(2, "end", (15.3, 15.6))
    assert draw.points[2] == (15.5, 15.5) and draw.view.preview_goal.visible
    np.testing.assert_allclose(draw.view._labels[2].position[:2], np.array([15.5, 15.5]) + 0.9 * draw.view.handle_radius)


def test_a_crossing_is_red_named_and_blocks_close_and_use(draw):
    draw._change([(10, 10), (14, 14), (14, 10), (10, 14)])  # a bow tie: 1-2 crosses 3-4
    assert draw.view.crossing.visible and draw.close.disabled
    assert len(draw.view.crossing.points) == 2  # the two edges
    assert "edges at vertices 1-2 and 3-4" in draw.status.content
    assert "In red on the floor: edges 1-2 and 3-4" in draw.status.content
    draw.vertex_drag(1, "end", (14, 10.5))  # drag 2 ...
    draw.vertex_drag(2, "end", (14, 14))  # ... and 3 back into a simple outline
    assert draw.points == [(10.0, 10.0), (14.0, 10.5), (14.0, 14.0), (10.0, 14.0)]
    assert not draw.view.crossing.visible and not draw.close.disabled


def test_status_says_what_each_disabled_button_waits_for(draw):
    assert draw.undo.disabled and draw.clear.disabled and draw.close.disabled
    assert "No points yet" in draw.status.content
    draw._change(SQUARE[:2])
    assert not draw.undo.disabled and draw.close.disabled
    assert "Close and use needs at least 3 points**: 2 so far" in draw.status.content
    draw.snap_on.value = False
    wait_until(lambda: draw.grid.disabled, what="the grid number off with snapping")
    draw.snap_on.value = True
    wait_until(lambda: not draw.grid.disabled, what="the grid number back")


def test_preview_is_the_goal_at_its_final_size_with_its_outlines(app, draw):
    from sandbox.model.goal import make_goal
    from sandbox.model.outlines import sizing_for

    draw._change(SQUARE)
    config = app.runner.latest.world_config
    goal = make_goal(config, np.array(SQUARE))
    sizing = sizing_for(config, goal, config.flare)
    shown = draw._preview
    np.testing.assert_allclose(shown.goal, goal.vertices)
    np.testing.assert_allclose(shown.smallest, sizing.polygon(sizing.smallest))
    np.testing.assert_allclose(shown.largest, sizing.polygon(sizing.largest))
    assert draw.view.preview_goal.visible and draw.view.preview_band.visible
    assert f"({goal.area:.0f} m², centred)" in draw.status.content
    draw.show_preview.value = False
    wait_until(lambda: not draw.view.preview_goal.visible, what="the preview hidden")
    draw.show_preview.value = True
    wait_until(lambda: draw.view.preview_goal.visible, what="the preview back")


def test_a_page_picks_a_template_types_points_and_uses_them(app, draw, page):
    page.set_value(uuid_of(draw.template), "house")
    wait_until(lambda: len(draw.points) == 5, what="the house template")
    relative = np.array(draw.points) - np.array(draw.points).min(axis=0)
    np.testing.assert_allclose(relative, template_vertices("house"))
    wait_until(lambda: draw.template.value == PICK_TEMPLATE, what="the dropdown back to its prompt")
    assert draw.typed.value.splitlines()[0] == "%g %g" % draw.points[0]  # the drawing as text

    page.set_value(uuid_of(draw.typed), "0 0\n6 0\n6")
    wait_until(lambda: draw.typed.value == "0 0\n6 0\n6", what="the typed text")
    page.click(uuid_of(draw.apply))
    wait_until(lambda: "Points not applied" in draw.status.content, what="the error line")
    assert "pair 3: '6' is not two numbers" in draw.status.content and len(draw.points) == 5

    page.set_value(uuid_of(draw.typed), "[[0, 0], [6, 0], [6, 6], [0, 6]]")
    wait_until(lambda: draw.typed.value.startswith("[["), what="the typed JSON")
    page.click(uuid_of(draw.apply))
    # Issue 40, item 3: typed points are a shape in their own coordinates, shown centred in the arena at
    # the size it will be built (the goal's area: the boxes' total area).
    wait_until(lambda: len(draw.points) == 4 and draw.points[0] != SQUARE[0], what="the typed square")
    snap = app.runner.latest
    goal = snap.goal_vertices if snap.goal_vertices is not None else snap.goal_outline
    half, c = abs(signed_area(np.asarray(goal))) ** 0.5 / 2, snap.world_config.centre
    np.testing.assert_allclose(draw.points, [(c - half, c - half), (c + half, c - half), (c + half, c + half),
                                             (c - half, c + half)], atol=2e-3)
    key = app.runner.latest.goal_key
    page.click(uuid_of(draw.close))
    wait_until(lambda: app.runner.latest.goal_key != key and app.runner.latest.shape_name == "drawn",
               what="the typed square in use")
    assert len(draw.points) == 4 and not draw.drawing  # kept, to tweak and use again
    # Edit this goal: the running goal comes back as the drawing's points.
    draw._change([])
    page.click(uuid_of(draw.edit))
    wait_until(lambda: len(draw.points) == 4, what="the running goal as points")
    np.testing.assert_allclose(draw.points, app.runner.latest.goal_vertices, atol=1e-3)


def test_the_gate_refuses_what_a_page_cannot_do(app, draw, page):
    draw._change([(10, 10), (14, 14), (14, 10), (10, 14)])  # crossing: Close and use is off
    key = app.runner.latest.goal_key
    page.click(uuid_of(draw.close))
    page.set_value(uuid_of(draw.template), "no such template")
    page.set_value(uuid_of(draw.typed), "1 2\n" * 2000)  # 8000 characters: over the text limit
    page.set_value(uuid_of(draw.grid), 50.0)  # over the grid's maximum
    page.received_types(0.5)
    assert app.runner.latest.goal_key == key and len(draw.points) == 4
    assert draw.template.value == PICK_TEMPLATE and len(draw.typed.value) < 4096 and draw.grid.value == 0.5


def test_status_text_words():
    assert status_text(0, True, "", None).startswith("**No points yet**")
    assert "place point 3" in status_text(2, True, "", None)
    text = status_text(4, False, "the outline crosses itself near (2, 2) (edges at vertices 1-2 and 3-4)", None,
                       red=["1-2", "3-4"])
    assert text.startswith("**Close and use is off**: the outline crosses") and "edges 1-2 and 3-4;" in text
    assert "edge 4-1;" in status_text(4, False, "touches", None, red=["4-1"])
