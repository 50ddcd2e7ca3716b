"""No page can starve the others (issue 54, F, and the last of G): each connection's messages are read
within a budget, cameras and controls over theirs wait (the newest of each), a page that presses
against its budget is disconnected, and a malformed message is refused in one line of the log while
its connection goes on.

The budgets' arithmetic, the log's pace and the decoding are pinned by unit tests; the attacks come
over the network from raw websocket clients (tests/viser_wire.py), the long floods from a process of
their own (tests/flooding.py) while a page that reports its drawn frames counts what it gets.
``python -m tests.flood_bench`` measures the same floods against ``phototaxis serve``."""

from __future__ import annotations

import logging
import time

import msgspec
import pytest
import viser.infra

from sandbox.app.web import rates
from sandbox.app.web.rates import CAMERA, CONTROLS, FLOOD_SECONDS, Bucket, Budget, Flow
from sandbox.app.web.refusals import RefusalLog
from sandbox.app.web.viser_seam import messages
from sandbox.app.web.well_formed import LARGE_MESSAGE, Malformed, decode
from tests.flooding import CAMERA as HELLO
from tests.flooding import PacedPage, flood_result, rss, start_flood
from tests.app.web.test_security import TOKEN, app, connected, own_page, shared_app  # noqa: F401 - fixtures
from tests.viser_wire import RawClient
from tests.waiting import wait_until, wait_until_steady


def encoded(**fields) -> bytes:
    return msgspec.msgpack.encode(fields)


# ------------------------------------------------------------------ budgets
def test_a_bucket_gives_its_burst_then_its_rate():
    bucket = Bucket(Budget(rate=8.0, burst=2.0), now=100.0)
    assert bucket.take(100.0) and bucket.take(100.0) and not bucket.take(100.0)
    assert bucket.wait(100.0) == 0.125  # one token comes every 1/8 s
    assert bucket.wait(100.0625) == 0.0625
    assert bucket.take(100.125) and not bucket.take(100.125)
    assert bucket.take(200.0) and bucket.take(200.0) and not bucket.take(200.0)  # never more than the burst


def test_a_flow_lets_the_newest_camera_wait_and_applies_it_when_the_budget_allows():
    applied = []
    flow, now = Flow(controls=False, now=0.0), 0.0
    flow.handle = applied.append
    camera = messages.ViewerCameraMessage
    cameras = [camera(wxyz=(1.0, 0.0, 0.0, 0.0), position=(float(i), 0.0, 10.0), fov=1.0, near=0.01, far=100.0,
                      image_height=600, image_width=800, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0))
               for i in range(100)]
    woken = []
    flow._wake_in = woken.append  # (no event loop here: note when it would wake)
    for message in cameras:
        flow.offer(message, now)
    assert len(applied) == CAMERA.burst == 60  # the burst at once
    assert flow.counts["replaced"] == 39 and list(flow.waiting.values())[0][1] is cameras[-1]
    assert woken == [pytest.approx(1 / 60)] * 40  # the next camera's token comes in 1/60 s
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(rates.time, "monotonic", lambda: 1 / 60)
        flow._release()
    assert applied[-1] is cameras[-1] and len(applied) == 61 and not flow.waiting


def test_controls_wait_each_its_newest_and_at_most_sixteen_wait():
    flow = Flow(controls=True, now=0.0)
    flow.handle, flow._wake_in = (lambda message: None), (lambda seconds: None)
    update = messages.GuiUpdateMessage
    for i in range(int(CONTROLS.burst)):
        flow.offer(update(uuid="speed", updates={"value": i}), 0.0)
    for i in range(20):  # over the budget: the newest of each control waits
        flow.offer(update(uuid=f"control-{i % 18}", updates={"value": i}), 0.0)
    assert len(flow.waiting) == rates.MOST_WAITING == 16
    assert flow.counts["dropped"] == 2  # controls 16 and 17 found no room
    assert flow.counts["replaced"] == 2  # controls 0 and 1 came again: their newest value waits
    assert flow.waiting[("GuiUpdateMessage", "control-0", None, None)][1].updates == {"value": 18}


def test_a_page_that_presses_against_its_budget_for_five_seconds_floods():
    flow, t = Flow(controls=False, now=0.0), 0.0
    while not flow.floods(t):  # a page that sends as fast as it is read
        t += flow.wait_to_read(t)
        flow.reading.take(t)
    assert t == pytest.approx(FLOOD_SECONDS, abs=0.01)  # its burst spent at once, then 5 s at the rate
    paused = Flow(controls=False, now=0.0)
    for _ in range(int(rates.WATCH_READING.burst)):
        paused.reading.take(0.0)
    assert paused.wait_to_read(0.0) == pytest.approx(1 / 120) and paused.pressing_since == 0.0
    assert paused.wait_to_read(2.0) == 0.0 and paused.pressing_since is None  # it paused: its budget filled
    assert not paused.floods(6.0)


def test_refusals_are_logged_at_most_once_a_second_per_page_with_a_count(caplog):
    log = RefusalLog(logging.getLogger("test.refusals"))
    with caplog.at_level(logging.WARNING, logger="test.refusals"):
        log.refused(7, "first", now=10.0)
        log.refused(7, "second", now=10.2)
        log.refused(8, "other page", now=10.3)
        log.refused(7, "third", now=10.9)
        log.refused(7, "fourth", now=11.1)
        log.refused(7, "fifth", now=11.5)
        log.forget(7)
        log.forget(8)
    assert [r.getMessage() for r in caplog.records] == [
        "refused a message from connection 7: first",
        "refused a message from connection 8: other page",
        "refused 3 messages from connection 7 in the last 1 s; the latest: fourth",
        "refused 1 more message from connection 7 before it left; the latest: fifth"]


# ------------------------------------------------------------------ decoding
def test_a_page_s_messages_decode_as_viser_decodes_them():
    for fields in (HELLO, dict(type="GuiUpdateMessage", uuid="u", updates={"value": 3.5}),
                   dict(type="ScenePointerMessage", event_type="click", ray_origin=(0, 0, 10), ray_direction=(0, 0, -1),
                        screen_pos=((0.5, 0.5),), modifier=None),
                   dict(type="FileTransferPart", source_component_uuid="c", transfer_uuid="t", part_index=0,
                        content=b"x" * (LARGE_MESSAGE + 10)),
                   dict(type="ShareUrlRequest")):
        raw = msgspec.msgpack.encode(fields)
        assert decode(raw) == viser.infra.Message.deserialize(raw)  # (viser's own decoder, for comparison)


@pytest.mark.parametrize("fields, why", [
    ({**HELLO, "image_height": 0}, "Expected `int` >= 1 - at `$.image_height`"),
    ({**HELLO, "image_width": 10 ** 7}, "Expected `int` <= 65536 - at `$.image_width`"),
    ({**HELLO, "fov": float("nan")}, "Expected `float` > 0.0 - at `$.fov`"),
    ({**HELLO, "position": (0.0, float("inf"), 1.0)}, "Expected `float` <= 1000000000.0 - at `$.position[1]`"),
    ({**HELLO, "fov": "wide"}, "Expected `float`, got `str` - at `$.fov`"),
    ({**HELLO, "wxyz": (0.0, 0.0, 0.0, 0.0)}, "the camera's orientation (0.0, 0.0, 0.0, 0.0) is not a unit quaternion"),
    ({**HELLO, "near": 5.0, "far": 1.0}, "the camera's far plane 1.0 is not beyond its near plane 5.0"),
    ({**HELLO, "up": 1}, "Object contains unknown field `up`"),
    ({"type": "GuiFormDirtyMessage"}, "Object missing required field `uuid`"),
    ({"type": "GuiFormDirtyMessage", "uuid": 5}, "Expected `str`, got `int` - at `$.uuid`"),
    ({"type": "FrameMessage"}, "Invalid value 'FrameMessage' - at `$.type`"),
    ({"type": "GuiUpdateMessage", "uuid": "u", "updates": {str(i): i for i in range(17)}},
     "Expected `object` of length <= 16 - at `$.updates`"),
])
def test_a_malformed_message_says_in_one_line_what_is_wrong(fields, why):
    with pytest.raises(Malformed) as refused:
        decode(msgspec.msgpack.encode(fields))
    assert str(refused.value) == why


def test_only_an_uploads_part_may_be_large_and_a_text_frame_is_no_message():
    huge = encoded(type="GuiUpdateMessage", uuid="u", updates={"value": list(range(40_000))})
    with pytest.raises(Malformed, match="a message of 1.* bytes that is not an upload's part"):
        decode(huge)
    with pytest.raises(Malformed, match="a text frame"):
        decode("{}")
    with pytest.raises(Malformed, match="malformed"):
        decode(b"\xc1")


# ------------------------------------------------------------------ over the network
def tracebacks(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.exc_info or "Traceback" in r.getMessage()]


def test_a_camera_with_no_height_is_refused_in_one_line_and_the_pages_go_on(shared_app, caplog):
    """``image_height: 0`` during a page's first 30 s divided by zero in the app, twice per message, and
    the page kept its connection; NaN and huge numbers too. Now each is refused before viser sees it."""
    app = shared_app
    watcher, other = RawClient(app.port, own_page(app)), RawClient(app.port, own_page(app))
    wid, _ = connected(app, watcher), connected(app, other)
    camera = app.server.get_clients()[wid].camera
    with caplog.at_level(logging.WARNING):
        for fields in ({"fov": float("nan")}, {"position": (1e300, 0.0, 0.0)}, {"image_height": -600},
                       {"image_height": 0, "image_width": 0}, {"image_height": 0}):
            watcher.send("ViewerCameraMessage", **{**HELLO, **fields, "type": "ViewerCameraMessage"})
        watcher.set_value("any-control", 1)  # refused (it watches): once it is, the cameras were handled ...
        wait_until(lambda: app.gate.inbox._refusals.get(wid), what="the watcher's value refused")
        app.events.call(lambda: None)  # ... and the app's events for them have run
        assert not app.events.errors and not tracebacks(caplog)
        watcher.send("ViewerCameraMessage", **{**HELLO, "position": (3.0, 4.0, 10.0), "type": "ViewerCameraMessage"})
        wait_until(lambda: tuple(camera.position) == (3.0, 4.0, 10.0), what="the good camera after the bad ones")
        drawn = app.frames_drawn
        wait_until(lambda: app.frames_drawn >= drawn + 10, what="ten more frames")
        assert app.gate.flow(wid).counts["malformed"] == 5 and not app.events.errors and not tracebacks(caplog)
        lines = [r.getMessage() for r in caplog.records if r.name == "sandbox.app.web.rates"]
        assert lines == [f"refused a message from connection {wid}: Expected `float` > 0.0 - at `$.fov`"]
    watcher.close()
    other.close()


def test_a_malformed_message_keeps_its_connection_and_a_line_of_log(app, caplog):
    """A malformed camera or GuiFormDirtyMessage closed the sender's connection with a traceback."""
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    with caplog.at_level(logging.WARNING):
        client.send("GuiFormDirtyMessage", uuid="form", extra=1)
        client.send("GuiFormDirtyMessage")
        client.send("ViewerCameraMessage", **{**HELLO, "fov": "wide", "type": "ViewerCameraMessage"})
        client.send("NoSuchMessage")
        client.ws.send(b"\xc1 not msgpack")
        client.ws.send("a text frame")
        client.set_value(app.panel.run.speed._impl.uuid, 7)  # still heard
        wait_until(lambda: app.runner.steps_per_frame == 7, what="the page's value after the malformed ones")
    assert app.gate.flow(cid).counts["malformed"] == 6
    assert not tracebacks(caplog) and not app.events.errors
    assert [r.getMessage() for r in caplog.records if r.name == "sandbox.app.web.rates"] == [
        f"refused a message from connection {cid}: Object contains unknown field `extra`"]
    client.close()


def counter(register) -> list:
    """A list that grows by one each time the app runs the callback ``register`` adds."""
    calls: list = []
    register(lambda *args: calls.append(time.monotonic()))
    return calls


def test_a_burst_of_cameras_is_applied_at_most_the_camera_budget_and_the_newest_wins(shared_app):
    app = shared_app
    watcher = RawClient(app.port, own_page(app))
    wid = connected(app, watcher)
    camera = app.server.get_clients()[wid].camera
    calls = counter(camera.on_update)
    for i in range(200):  # within the reading budget's burst: all read at once
        watcher.send("ViewerCameraMessage", **{**HELLO, "position": (float(i), 0.0, 10.0), "type": "ViewerCameraMessage"})
    wait_until(lambda: tuple(camera.position) == (199.0, 0.0, 10.0), what="the newest camera")
    wait_until_steady(lambda: len(calls))
    assert len(calls) <= CAMERA.burst + 5, f"{len(calls)} cameras applied"  # (the others replaced as they waited)
    assert app.gate.flow(wid).counts["replaced"] >= 130
    watcher.close()


def test_a_burst_of_values_is_applied_at_most_the_controls_budget_and_the_last_value_stands(app):
    """A page with the token sending values as fast as it can (9,000-13,000 a second took the others to
    1-2 frames a second): they are applied at most the controls' budget, the newest of them last."""
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    speed = app.panel.run.speed
    calls = counter(speed.on_update)
    started = time.monotonic()
    for i in range(200):
        client.set_value(speed._impl.uuid, 2 + i % 50)
    sending = time.monotonic() - started
    wait_until(lambda: app.runner.steps_per_frame == 2 + 199 % 50, what="the last value")
    wait_until_steady(lambda: len(calls))
    # the burst, and what the budget refills while a busy machine takes its time to send the 200
    allowed = CONTROLS.burst + CONTROLS.rate * sending + 5
    assert len(calls) <= allowed, f"{len(calls)} values applied, {allowed:.0f} allowed ({sending:.2f} s sending)"
    assert speed.value == 2 + 199 % 50 and app.gate.flow(cid).counts["replaced"] >= 130
    client.close()


# ------------------------------------------------------------------ floods (slow)
FLOOD_SECONDS_LONG = 5.0
#: The memory a flood may leave behind in the server (it reached 650-900 MB and stayed).
RETURNED_WITHIN = 50 * 1024 * 1024


def frames_kept(page: PacedPage, start: float, seconds: float) -> float:
    """The least frames a second ``page`` must keep during a flood: 15, or three quarters of what it got
    in the ``seconds`` before ``start`` on a machine too busy to give it 20."""
    before = page.rate(start - seconds, start)
    return min(15.0, 0.75 * before)


def flood_and_measure(app, page: PacedPage, kind: str, connections: int, headers: dict, uuid: str = "") -> None:
    """Flood the app for :data:`FLOOD_SECONDS_LONG` s; the page keeps its frames, the server its memory,
    the flooders are disconnected."""
    wait_until(lambda: len(page.frames) > 60, what="the page's first two seconds of frames")
    start, before = time.monotonic(), rss()
    flooding = start_flood(app.port, kind, connections, FLOOD_SECONDS_LONG, headers, uuid)
    sent, _ = flood_result(flooding)
    end = time.monotonic()
    rate, least = page.rate(start + 1.0, end), frames_kept(page, start, 2.0)
    gap = page.largest_gap(start + 1.0, end)
    print(f"{kind}: sent {sent} ({sent / (end - start):.0f}/s); the page got {rate:.1f} frames/s "
          f"(largest gap {gap:.2f} s); at least {least:.1f} needed")
    assert rate >= least, f"the page got {rate:.1f} frames a second during the flood"
    wait_until(lambda: len(app.server.get_clients()) == 1, timeout=FLOOD_SECONDS + 30,
               what="the flooding pages to be disconnected")
    grown = rss() - before
    print(f"{kind}: the server grew by {grown / 1e6:.1f} MB")
    assert grown < RETURNED_WITHIN, f"the server kept {grown / 1e6:.0f} MB"


@pytest.mark.slow
def test_four_watchers_flooding_cameras_and_controls_leave_another_page_its_frames(shared_app, caplog):
    app = shared_app
    page = PacedPage(app.port, own_page(app))
    with caplog.at_level(logging.WARNING):
        flood_and_measure(app, page, "mixed", 4, own_page(app))
    closed = [r.getMessage() for r in caplog.records if r.getMessage().startswith("closed connection")]
    assert len(closed) == 4 and all("messages a second for 5 s" in line for line in closed), closed
    assert not tracebacks(caplog) and not app.events.errors
    page.close()


@pytest.mark.slow
def test_a_page_with_the_token_flooding_values_leaves_another_page_its_frames(shared_app):
    app = shared_app
    page = PacedPage(app.port, own_page(app))
    flood_and_measure(app, page, "values", 1, {**own_page(app), "Authorization": f"token {TOKEN}"},
                      uuid=app.panel.run.speed._impl.uuid)
    page.close()
