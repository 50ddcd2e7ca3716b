"""Polygon files uploaded over the network as a page sends them (issue 39, holes 2 and 5): a
megabyte of SVG curves is refused with a notice while another viewer's scene keeps coming and the
server stays its size; a file name with a NUL byte gets a notice, and the simulation goes on; two pages
uploading at once are each told of their own file (issue 54 G)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from sandbox.app.panel.shape import UPLOAD_REFUSED, upload_name
from sandbox.model.config import Config
from sandbox.shapes.isolated import read_polygon_isolated
from tests.shapes.test_shape_budget import svg_of_arcs
from tests.viser_wire import RawClient
from tests.waiting import wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
#: Longest pause in a viewer's scene while an upload is read. The reader is a child process, so the
#: server only waits on a pipe; measured 0.2-0.4 s gaps on two loaded cores (load average 20), the
#: same as without an upload. Reading in the server stalled every scene for 5.9 s.
STALL = 1.5
#: Seconds from the upload's first byte to its refusal on the page: measured 0.3-0.6 s on two loaded
#: cores (it was 37 s); the issue asks for 2, the bound leaves room for a busier machine.
REFUSED_WITHIN = 5.0
#: Growth of the server's memory for a refused megabyte: measured 1-3 MB (it was 286 MB).
GROWTH = 50 * 1024 * 1024


@pytest.fixture
def app():
    from sandbox.commands.serve import App, free_port

    a = App(SMALL, port=free_port(), fps=30, steps_per_frame=2, process=False).start()
    yield a
    a.stop()


class FrameClock:
    """A viewer that only watches: the times its scene updates arrive."""

    def __init__(self, client: RawClient):
        self.client, self.times = client, []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._receive, name="frame-clock", daemon=True)
        self._thread.start()

    def _receive(self) -> None:
        while not self._stop.is_set():
            try:
                self.client.ws.recv(timeout=0.2)
            except TimeoutError:
                continue
            except Exception:  # the connection closed: the test is over
                return
            self.times.append(time.monotonic())

    def frames_after(self, moment: float) -> int:
        return sum(1 for t in list(self.times) if t > moment)

    def largest_gap(self, start: float, end: float) -> float:
        """The longest time without a scene update between ``start`` and ``end``."""
        inside = [start] + [t for t in list(self.times) if start < t < end] + [end]
        return max(b - a for a, b in zip(inside, inside[1:]))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.client.close()


def page(app) -> RawClient:
    client = RawClient(app.port, {"Origin": f"http://127.0.0.1:{app.port}"})
    before = set(app.server.get_clients())
    client.say_hello()
    wait_until(lambda: set(app.server.get_clients()) - before, what="the page to count as connected")
    return client


def upload(app, client: RawClient, name: str, content: bytes) -> None:
    client.upload(app.panel.shape.upload._impl.uuid, name, content)


def notice(client: RawClient, title: str, seconds: float = 60.0) -> str:
    """The body of the first notification titled ``title`` the page gets."""
    for message in client._messages(seconds):
        if message.get("type") == "NotificationShowMessage" and message["props"]["title"] == title:
            return message["props"]["body"]
    raise AssertionError(f"no {title!r} notice within {seconds:.0f} s")


def rss() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS")


def test_a_megabyte_of_arcs_is_refused_without_stalling_a_viewer_or_growing_the_server(app):
    # The app's simulation process started the fork server the reader is forked from; here the
    # simulation runs in this process, so the first file read starts it (seconds on a loaded machine).
    read_polygon_isolated(b"0 0\n6 0\n3 5\n", "warm.txt")
    viewer = FrameClock(page(app))
    uploader = page(app)
    data = svg_of_arcs()
    warm = time.monotonic()
    wait_until(lambda: viewer.frames_after(warm) >= 10, what="the viewer's scene to flow")
    before, start = rss(), time.monotonic()
    upload(app, uploader, "arcs.svg", data)
    body = notice(uploader, UPLOAD_REFUSED)
    end = time.monotonic()
    wait_until(lambda: viewer.frames_after(end) >= 3, what="the scene after the refusal")
    grown, gap = rss() - before, viewer.largest_gap(start, end)
    print(f"refused in {end - start:.2f} s; largest gap {gap:.2f} s; server grew {grown / 1e6:.1f} MB")
    assert body.startswith("arcs.svg: the <path> has more than 10,000 points"), body
    assert end - start < REFUSED_WITHIN, f"refused after {end - start:.1f} s"
    assert gap < STALL, f"the viewer's scene stalled {gap:.2f} s"
    assert grown < GROWTH, f"the server grew by {grown / 1e6:.0f} MB"
    assert app.runner.latest.shape_name == "circle"
    viewer.close()
    uploader.close()


def test_a_file_name_with_a_nul_byte_gets_a_notice_and_the_run_goes_on(app):
    uploader = page(app)
    upload(app, uploader, "bad\x00.txt", b"0 0\n1 1\n")
    assert notice(uploader, UPLOAD_REFUSED).startswith("bad?.txt: has only 2 distinct vertices")
    step = app.runner.latest.step
    wait_until(lambda: app.runner.latest.step > step, what="the simulation to go on")
    upload(app, uploader, "../tri\x00angle.txt", b"0 0\n6 0\n3 5\n")
    assert notice(uploader, "Goal changed").startswith("Using tri?angle.txt (3 vertices)")
    wait_until(lambda: app.runner.latest.shape_name == "tri?angle.txt", what="the uploaded goal")
    uploader.close()


def test_an_upload_shorter_than_announced_gets_a_notice(app):
    """viser drops a file whose parts hold fewer bytes than announced, with a warning in the log."""
    uploader = page(app)
    component = app.panel.shape.upload._impl.uuid
    transfer = uploader.start_upload(component, size=1000, parts=1, name="short\x00.txt")
    uploader.upload_part(component, transfer, 0, b"0 0\n6 0\n3 5\n")
    assert notice(uploader, "File not uploaded") == "short?.txt: 12 bytes arrived of the 1000 announced."
    assert app.gate.inbox._transfers == {} and app.runner.latest.shape_name == "circle"
    uploader.close()


def test_two_pages_uploading_at_once_are_each_told_of_their_own_file(app):
    """Hole G3 (issue 54): the upload callback read the button's value, which viser shares between pages,
    so of two uploads finished before the first callback ran, both pages were told of (and used) the
    second file. The app's events are held until both uploads are in, then each page's notice names its
    own file."""
    first, second = page(app), page(app)
    holding, release = threading.Event(), threading.Event()
    app.events.post(lambda: (holding.set(), release.wait(30)))
    wait_until(holding.is_set, what="the app's events to be held")
    try:
        upload(app, first, "first-square.txt", b"0 0\n4 0\n4 4\n0 4\n")
        upload(app, second, "second-triangle.txt", b"0 0\n6 0\n3 5\n")
        for client in (first, second):  # acknowledged: the inbox has handed the file to the callbacks
            assert "FileTransferPartAck" in client.received_types(30, until=frozenset({"FileTransferPartAck"}))
    finally:
        release.set()
    assert notice(first, "Goal changed").startswith("Using first-square.txt (4 vertices)")
    assert notice(second, "Goal changed").startswith("Using second-triangle.txt (3 vertices)")
    first.close()
    second.close()


@pytest.mark.parametrize("sent, shown", [("a\x00b.svg", "a?b.svg"), ("C:\\Users\\me\\goal.txt", "goal.txt"),
                                         ("/etc/passwd", "passwd"), ("..", "upload.txt"), ("", "upload.txt"),
                                         ("\ud800.json", "?.json"), ("x" * 300 + ".wkt", "x" * 73 + "....wkt")])
def test_an_uploads_name_is_cleaned_for_showing(sent, shown):
    assert upload_name(sent) == shown
