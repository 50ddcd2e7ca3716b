"""The Draw folder's state machine on a live server, without a browser: scene
clicks and drags are called as viser would call them, controls are set over
the wire as a page sets them (so the gate checks them as it checks every
control)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.app.panel.draw import PICK_TEMPLATE, status_text
from sandbox.app.view.sketch import DIM_OPACITY, SELECTED_COLOUR  # noqa: I001 - after the panel, which imports it first
from sandbox.shapes.geometry import signed_area
from sandbox.shapes.templates import template_vertices
from tests.inline_events import OnEvents
from tests.shown import shown
from tests.app.web.test_security import connected, make_app, own_page, refusals, uuid_of, wait_until
from tests.viser_wire import RawClient

SQUARE = [(10.0, 10.0), (14.0, 10.0), (14.0, 14.0), (10.0, 14.0)]


@pytest.fixture(scope="module")
def app():
    a = make_app()
    yield a
    a.stop()


@pytest.fixture
def draw(app):
    """The Draw folder, its methods run on the app's event thread (which owns it), as a page's clicks."""
    folder = OnEvents(app.panel.shape.draw, app.events)
    folder._change([])
    folder._set_drawing(False)
    folder.snap_on.value, folder.grid.value = True, 0.5
    yield folder
    folder._change([])
    folder._set_drawing(False)


@pytest.fixture
def page(app):
    client = RawClient(app.port, own_page(app))
    client.id = connected(app, client)
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
    assert "edges at vertices 1-2 and 3-4" in shown(draw.status.content)
    assert "In red on the floor: edges 1-2 and 3-4" in shown(draw.status.content)
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
    from sandbox.model.family import make_goal
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
    assert "pair 3: '6' is not two numbers" in shown(draw.status.content) and len(draw.points) == 5

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
    wait_until(lambda: refusals(app, page.id) >= 4, what="the four refused")
    assert app.runner.latest.goal_key == key and len(draw.points) == 4
    assert draw.template.value == PICK_TEMPLATE and len(draw.typed.value) < 4096 and draw.grid.value == 0.5


def test_status_text_words():
    assert status_text(0, True, "", None).startswith("**No points yet**")
    assert "place point 3" in status_text(2, True, "", None)
    text = status_text(4, False, "the outline crosses itself near (2, 2) (edges at vertices 1-2 and 3-4)", None,
                       red=["1-2", "3-4"])
    assert text.startswith("**Close and use is off**: the outline crosses") and "edges 1-2 and 3-4;" in shown(text)
    assert "edge 4-1;" in shown(status_text(4, False, "touches", None, red=["4-1"]))


# ------------------------------------------------- insert, select, delete (issue 40, item 3)
class Camera:
    """A page's camera straight above (x, y), as the server hears it: enough to know a pixel's size."""

    def __init__(self, x: float, y: float, height: float, metres_per_pixel: float, pixels: int = 1000):
        self.position = np.array([x, y, height])
        self.image_height = pixels
        self.fov = 2.0 * np.arctan(metres_per_pixel * pixels / (2.0 * height))


class Page:
    def __init__(self, camera: Camera):
        self.camera = camera


def test_clicking_an_edge_inserts_a_point_between_its_ends(draw):
    draw._set_drawing(True)
    draw._change(SQUARE)
    assert draw.click((12.1, 10.2))  # on edge 1-2 (within the handle's radius of it, without a page's camera)
    assert draw.points == [(10.0, 10.0), (12.0, 10.0), (14.0, 10.0), (14.0, 14.0), (10.0, 14.0)]
    assert draw.selected == 1 and "**Point 2 selected**" in draw.status.content  # the new point, named
    assert not draw.delete.disabled
    draw.click((10.2, 12.1))  # on the closing edge 5-1: the point goes last, as if added
    assert draw.points[-1] == (10.0, 12.0) and len(draw.points) == 6 and draw.selected is None
    draw.click((12.0, 12.0))  # inside, away from every edge: the next point
    assert draw.points[-1] == (12.0, 12.0) and len(draw.points) == 7


def test_an_edge_is_within_a_few_pixels_of_the_clicking_pages_view(draw):
    draw._set_drawing(True)
    draw.snap_on.value = False
    draw._change(SQUARE)
    far_out = Page(Camera(12.0, 12.0, 80.0, metres_per_pixel=0.1))  # the whole arena in view: 6 px = 0.6 m
    assert draw.click((12.0, 10.5), far_out) and len(draw.points) == 5 and draw.points[1] == (12.0, 10.5)
    zoomed = Page(Camera(12.0, 12.0, 10.0, metres_per_pixel=0.01))  # zoomed in: 6 px = 6 cm
    assert draw.click((14.05, 12.0), zoomed) and draw.points[3] == (14.05, 12.0)  # 5 px off edge 3-4: on it
    draw.click((14.3, 13.0), zoomed)  # 30 px off: not on it, a new last point
    assert draw.points[-1] == (14.3, 13.0) and len(draw.points) == 7
    draw.click((14.3, 13.05), far_out)  # 0.5 px from that point's handle: selects it, adds nothing
    assert draw.selected == 6 and len(draw.points) == 7


def test_a_click_on_a_handle_selects_its_point_and_delete_removes_it(app, draw, page):
    draw._change(SQUARE)
    assert draw.delete.disabled and all(command.disabled for command in draw.delete_keys)
    assert draw.click((14.1, 13.9))  # point 3's handle, even when not drawing (the inspector does not get it)
    assert draw.selected == 2 and draw.points == SQUARE  # selected, nothing added
    handles = draw.view._handles
    assert tuple(handles.batched_colors[2]) == SELECTED_COLOUR and handles.batched_scales[2] > handles.batched_scales[0]
    assert not draw.delete.disabled and not any(command.disabled for command in draw.delete_keys)
    page.click(uuid_of(draw.delete))  # the button, over the wire
    wait_until(lambda: len(draw.points) == 3 and draw.delete.disabled, what="point 3 deleted")
    assert draw.points == [SQUARE[0], SQUARE[1], SQUARE[3]] and draw.selected is None
    # The Delete key (a command of viser's page): refused while nothing is selected, acts once a point is.
    key = uuid_of(draw.delete_keys[0])
    page.send("CommandTriggerMessage", uuid=key)
    page.click(uuid_of(draw.delete))
    wait_until(lambda: refusals(app, page.id) >= 2, what="the key and the button refused")
    assert len(draw.points) == 3
    draw.click(SQUARE[1])
    page.send("CommandTriggerMessage", uuid=uuid_of(draw.delete_keys[1]))  # Backspace
    wait_until(lambda: len(draw.points) == 2 and draw.delete.disabled, what="point 2 deleted by its key")
    assert draw.points == [SQUARE[0], SQUARE[3]]


def test_a_dragged_handle_follows_every_update_without_a_new_preview(draw, monkeypatch):
    from sandbox.app.panel import draw as draw_module

    draw._change(SQUARE)
    previews = []
    real = draw_module.preview_goal
    monkeypatch.setattr(draw_module, "preview_goal", lambda *a: previews.append(1) or real(*a))
    draw.vertex_drag(1, "start", (14.0, 10.0))
    assert draw.selected == 1 and not draw.view.preview_goal.visible
    for k in range(1, 6):
        draw.vertex_drag(1, "update", (14.0 + k, 10.0 - k / 2))
        expected = draw.points[1]
        assert expected == (14.0 + k, round(2 * (10.0 - k / 2)) / 2)  # snapped
        np.testing.assert_allclose(draw.view._handles.batched_positions[1, :2], expected)  # the handle follows
        np.testing.assert_allclose(draw.view.line.points[0, 1, :2], expected)  # and the outline with it
    assert previews == []  # no preview while dragging: it is computed again on release
    draw.vertex_drag(1, "end", (19.0, 7.5))
    assert previews == [1] and draw.view.preview_goal.visible and draw.selected == 1


def test_clicks_that_come_while_the_event_thread_is_busy_all_land_in_order(app, draw, page, monkeypatch):
    """Every click on the floor is an event on the app's one queue (sandbox.app.web.events): clicks that
    come while it is busy wait their turn; none is merged with another or dropped."""
    import threading

    draw._set_drawing(True)
    inbox, heard = app.gate.inbox, []
    admit = inbox.admit
    monkeypatch.setattr(inbox, "admit", lambda client_id, grant, message: (
        heard.append(type(message).__name__ == "ScenePointerMessage") or admit(client_id, grant, message)))
    busy, release = threading.Event(), threading.Event()
    app.events.post(lambda: busy.set() or release.wait(20))
    wait_until(busy.is_set, what="the event thread busy")
    targets = [(20.0 + k, 40.0 + 2.0 * (k % 2)) for k in range(12)]  # a zigzag, 2.2 m between clicks
    try:
        for x, y in targets:  # straight down onto (x, y), as a page's click ray
            page.send("ScenePointerMessage", event_type="click", ray_origin=(x, y, 10.0),
                      ray_direction=(0.0, 0.0, -1.0), screen_pos=[[0.5, 0.5]], modifier=None)
        wait_until(lambda: sum(heard) == len(targets), what="the clicks at the server")
        assert draw.points == []  # none has run yet: the event thread is busy
    finally:
        release.set()
    wait_until(lambda: len(draw.points) == len(targets), what="every click a point")
    assert draw.points == targets


def test_use_and_run_to_the_end_builds_the_drawing_then_runs_it_to_the_end_step(app, draw, page):
    """One action from a drawing to its answer: the new world on the drawn goal, then Run to the end
    (to the Run folder's end step); a drawing that cannot be used leaves the button off."""
    run = app.panel.run
    draw._change([(10.0, 10.0), (14.0, 14.0), (14.0, 10.0), (10.0, 14.0)])  # a bow tie: crossing edges
    assert draw.close_and_run.disabled
    draw._change(SQUARE)
    assert not draw.close_and_run.disabled
    ending = run.end_step.value
    run.end_step.value = 300
    try:
        key = app.runner.latest.goal_key
        page.click(uuid_of(draw.close_and_run))
        wait_until(lambda: app.runner.latest.goal_key != key and app.runner.latest.shape_name == "drawn",
                   what="the drawn square in use")
        wait_until(lambda: app.runner.latest.step >= 300 and not run.run_to_end.disabled, what="the run to step 300")
        assert app.runner.latest.goal_key != key and len(draw.points) == 4
    finally:
        run.end_step.value = ending


# ------------------------------------------- the drawing and the goal built (issue 56, items 2 and 3)
def test_after_use_the_drawing_gives_way_and_edit_this_goal_brings_it_back(app, draw, page):
    """Issue 56, item 3: after *Close and use* the thick line, the numbered handles and the dashed preview
    left nothing over the goal built; they leave the floor (the points stay in the folder) and *Edit this
    goal* brings the running goal back as points, on the floor again."""
    draw._change(SQUARE)
    assert draw.view.line.visible and draw.view.preview_goal.visible and len(draw.view._labels) == 4
    key = app.runner.latest.goal_key
    page.click(uuid_of(draw.close))
    wait_until(lambda: app.runner.latest.goal_key != key and app.runner.latest.shape_name == "drawn",
               what="the square in use")
    view = draw.view
    # The event thread hides the line, then the preview, then says "In use": wait for the last of them.
    wait_until(lambda: "**In use**" in draw.status.content, 10, what="the drawing leaving the floor")
    assert not (view.line.visible or view.closing.visible or view.preview_goal.visible or view.preview_band.visible)
    assert not view._handles.visible and view._labels == [] and view._pad is None
    assert draw.given_way and draw.points == SQUARE and "**In use**" in draw.status.content  # kept, and said
    assert not draw.click(SQUARE[2])  # a hidden point is not picked up by a click on the floor
    page.click(uuid_of(draw.edit))
    wait_until(lambda: view.line.visible and len(view._labels) == 4, what="the running goal back as points")
    np.testing.assert_allclose(draw.points, app.runner.latest.goal_vertices, atol=1e-3)
    assert view.line.visible and view._handles.visible and len(view._labels) == 4 and view.preview_goal.visible


def test_a_goal_picked_elsewhere_moves_the_drawing_aside_too(app, draw, page):
    """Any goal used (picked, uploaded, a paper case) is the result to see: the drawing gives way to it."""
    draw._change(SQUARE)
    key = app.runner.latest.goal_key
    app.events.call(lambda: app.panel.shape.use(np.array(SQUARE) * 2, "square", None))
    wait_until(lambda: app.runner.latest.goal_key != key, what="the picked goal in use")
    wait_until(lambda: not draw.view.line.visible, 10, what="the drawing leaving the floor")
    assert draw.given_way and draw.points == SQUARE
    draw._set_drawing(True)  # Start drawing: the kept points come back
    assert not draw.given_way and draw.view.line.visible and len(draw.view._labels) == 4


#: The designer's typed F-like shape of issue 56, item 2, and where the default world builds it: the offset
#: goal moved 1.2507 m up so that it lies inside the construction wall (y 24.75-38.37, read back from the
#: goal built and from its design file); the points were drawn at y 23.50-37.12 before.
TYPED = "0 0\n2 0\n2 6\n5 6\n5 8\n-3 8\n-3 6\n0 6"
BUILT_Y = (24.750, 38.373)


@pytest.fixture(scope="module")
def default_boxes_app():
    """A world with the default 500 boxes (few robots): the one where the goal is moved inside the wall."""
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    a = App(Config(robots=12, update_every=10, hold_steps=3), port=free_port(), fps=30, steps_per_frame=2,
            process=False).start()
    yield a
    a.stop()


def test_typed_points_are_drawn_where_the_goal_is_built(default_boxes_app):
    app = default_boxes_app
    draw = OnEvents(app.panel.shape.draw, app.events)
    client = RawClient(app.port, own_page(app))
    client.id = connected(app, client)
    try:
        client.set_value(uuid_of(draw.typed), TYPED)
        wait_until(lambda: draw.typed.value == TYPED, what="the typed text")
        client.click(uuid_of(draw.apply))
        # Close and use enabled too: the points are stored before the buttons follow, and the gate refuses a
        # click on a disabled button.
        wait_until(lambda: len(draw.points) == 8 and not draw.close.disabled, what="the typed points, ready")
        ys = np.array(draw.points)[:, 1]
        assert (round(ys.min(), 3), round(ys.max(), 3)) == pytest.approx(BUILT_Y, abs=2e-3)
        np.testing.assert_allclose(draw._preview.goal, draw.points, atol=2e-3)  # on the dashed preview
        key = app.runner.latest.goal_key
        client.click(uuid_of(draw.close))
        wait_until(lambda: app.runner.latest.goal_key != key and app.runner.latest.shape_name == "drawn",
                   what="the typed shape in use")
        np.testing.assert_allclose(app.runner.latest.goal_vertices, draw.points, atol=2e-3)  # and on the goal built
    finally:
        client.close()
