"""Following a robot (issue 41, item 4), over the network as a page does it: the f key brings the robot
into the page's view (its camera follows by default), *Camera follows* is the page's own tick box, and
the robot's disc is drawn inside its ring in the page's own scene."""

from __future__ import annotations

import numpy as np
import pytest

from tests.app.web.test_security import command_uuid, connected, make_app, own_page, uuid_of
from tests.viser_wire import RawClient
from tests.waiting import paused_step, wait_until


@pytest.fixture
def app():
    a = make_app()
    yield a
    a.stop()


def test_f_brings_the_robot_into_view_and_camera_follows_is_a_tick_box(app):
    page = RawClient(app.port, own_page(app))
    pid = connected(app, page)
    inspector = app.panel.inspector
    wait_until(lambda: pid in inspector.viewers, what="the page's inspector")
    viewer, client = inspector.viewers[pid], app.server.get_clients()[pid]
    assert viewer.follows.value is True  # followed robots come into view by default
    page.send("CommandTriggerMessage", uuid=command_uuid(app, "Follow a random robot"))  # the f key
    wait_until(lambda: viewer.robot is not None, what="a followed robot")

    def looking_at_the_robot() -> bool:
        robot = app.runner.latest.robot_positions[viewer.robot]
        return np.hypot(*(np.asarray(client.camera.look_at[:2]) - robot)) < 1.0 and client.camera.position[2] < 20

    wait_until(looking_at_the_robot, what="the page's camera over the robot")
    assert pid in inspector.followers
    page.set_value(uuid_of(viewer.follows), False)  # unticked: the page sees its View again
    wait_until(lambda: pid not in inspector.followers, what="the camera to stop following")
    wait_until(lambda: client.camera.position[2] > 20, what="the whole arena again")
    page.set_value(uuid_of(viewer.follows), True)  # ticked again: back over the robot at once
    wait_until(looking_at_the_robot, what="the camera over the robot again")
    page.close()


def test_the_followed_robot_is_drawn_inside_its_ring_in_the_same_message(app):
    """The shared scene reaches a slow page in windows, the page's own nodes at once: the followed
    robot's disc is drawn again with its ring, from the same snapshot, so it is never outside it."""
    page = RawClient(app.port, own_page(app))
    pid = connected(app, page)
    inspector = app.panel.inspector
    wait_until(lambda: pid in inspector.viewers, what="the page's inspector")
    app.lockstep.set_playing(False)  # the robot stands still while the test reads ring and disc
    paused_step(app.runner)
    inspector.follow(app.server.get_clients()[pid], 2)
    viewer = inspector.viewers[pid]
    wait_until(lambda: viewer.disc.visible and viewer.ring.visible, what="the ring and the disc")
    ring = np.asarray(viewer.ring.points, float)[:, 0, :2]
    centre = ring.mean(axis=0)
    radius = np.hypot(*(ring - centre).T).min()
    disc, heading = np.asarray(viewer.disc.points, float)[0], np.asarray(viewer.heading.points, float)[0]
    assert np.hypot(*(disc[:2] - centre)) < 0.05  # the disc at the ring's centre
    assert viewer.disc.point_size < radius  # and within it (a point's size is its radius)
    assert np.hypot(*(heading[:2] - disc[:2])) + viewer.heading.point_size < viewer.disc.point_size  # its heading dot
    page.close()
