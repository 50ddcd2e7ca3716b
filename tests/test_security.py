"""Attack tests: the server decides, never the page.

Each test drives a running app as a hostile client would: a raw websocket
with a foreign Origin or Host, a click on a disabled control, a property no
page should set, an upload that never ends. Each must change nothing and
load nothing; the same request from the user's own page must work, so that
a refusal is the gate's doing and not a broken client."""

from __future__ import annotations

import http.client
import socket
from pathlib import Path

import pytest
import viser
import websockets.exceptions
import websockets.sync.client

from sandbox.app.access import Access, Grant
from sandbox.app.gate import WRITTEN_FOR
from sandbox.model.config import Config
from tests.viser_wire import RawClient
from tests.waiting import wait_until, wait_until_steady

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
TOKEN = "classroom-secret-42"
TRIANGLE = b"0 0\n6 0\n3 5\n"


def make_app(**kwargs):
    from sandbox.app.server import App, free_port

    return App(SMALL, port=free_port(), fps=30, steps_per_frame=2, process=False, **kwargs).start()


@pytest.fixture
def app():
    a = make_app()
    yield a
    a.stop()


@pytest.fixture
def shared_app():
    """A server that needs the token for control (as --host 0.0.0.0 does), on loopback for the test."""
    a = make_app(access=Access.for_server("127.0.0.1", token=TOKEN))
    yield a
    a.stop()


def uuid_of(handle) -> str:
    return handle._impl.uuid


def own_page(app) -> dict[str, str]:
    return {"Origin": f"http://127.0.0.1:{app.port}"}


def connected(app, client: RawClient) -> int:
    """Say hello and wait until viser counts the client; its id."""
    before = set(app.server.get_clients())
    client.say_hello()
    new = wait_until(lambda: set(app.server.get_clients()) - before, what="the raw client to count as connected")
    return next(iter(new))


def refusals(app, client_id: int) -> int:
    return app.gate.inbox._refusals.get(client_id, 0)


def http_status(port: int, host_header: str, path: str = "/", headers: dict | None = None) -> http.client.HTTPResponse:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    connection.request("GET", path, headers={"Host": host_header, **(headers or {})})
    return connection.getresponse()


def test_the_gate_was_written_for_the_installed_viser():
    assert viser.__version__ == WRITTEN_FOR, "sandbox/app/gate.py wraps viser's internals: re-check them"


def test_a_page_of_another_origin_cannot_open_the_websocket(app):
    with pytest.raises(websockets.exceptions.InvalidStatus) as refused:
        RawClient(app.port, {"Origin": "http://evil.example"})
    assert refused.value.response.status_code == 403
    with pytest.raises(websockets.exceptions.InvalidStatus):
        RawClient(app.port, {"Origin": "null"})  # a sandboxed frame or a file:// page
    assert app.server.get_clients() == {} and app.runner.latest.shape_name == "circle"


def test_a_foreign_host_is_refused_for_pages_and_websockets(app):
    assert http_status(app.port, f"rebind.evil.example:{app.port}").status == 403
    assert http_status(app.port, f"127.0.0.1:{app.port}").status == 200
    assert http_status(app.port, f"localhost:{app.port}").status == 200
    sock = socket.create_connection(("127.0.0.1", app.port))
    with pytest.raises(websockets.exceptions.InvalidStatus):
        websockets.sync.client.connect(f"ws://rebind.evil.example:{app.port}/", sock=sock,
                                       subprotocols=[f"viser-v{viser.__version__}"])
    assert app.server.get_clients() == {}


def test_the_users_own_page_controls_the_sandbox(app):
    client = RawClient(app.port, own_page(app))
    connected(app, client)
    client.set_value(uuid_of(app.panel.shape.shape), "square")
    wait_until(lambda: app.runner.latest.shape_name == "square", what="the goal to change")
    client.close()


def test_a_disabled_control_never_acts(app, tmp_path):
    marker = tmp_path / "ran.txt"
    program = tmp_path / "evil.py"
    program.write_text(f"open({str(marker)!r}, 'w').write('ran')\nclass Evil:\n    def update(self, o): return None\n")
    folder = app.panel.program
    folder.use.disabled = True  # as a server shared without --allow-programs shows it
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    client.set_value(uuid_of(folder.path), f"{program}:Evil")
    client.send("GuiUpdateMessage", uuid=uuid_of(folder.use), updates={"disabled": False})  # enable it first
    client.click(uuid_of(folder.use))
    client.click(uuid_of(app.panel.shape.draw_close))  # disabled: fewer than 3 points drawn
    wait_until(lambda: refusals(app, cid) >= 3, what="three refusals")
    assert folder.use.disabled and not marker.exists()
    assert app.runner.latest.program == "the paper's controller"
    client.close()


def test_a_page_may_set_a_value_but_no_other_property(app):
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    dropdown = uuid_of(app.panel.shape.shape)
    client.send("GuiUpdateMessage", uuid=dropdown, updates={"update_cb": []})  # would silence the control
    client.send("GuiUpdateMessage", uuid=dropdown, updates={"value": "square", "visible": False})
    client.set_value(dropdown, "no such shape")  # not one of its options
    client.set_value(uuid_of(app.panel.run.speed), 1e9)  # past the slider's end
    client.send("ShareUrlRequest")  # would publish the sandbox through viser's public tunnel
    wait_until(lambda: refusals(app, cid) >= 5, what="five refusals")
    assert app.runner.latest.shape_name == "circle" and app.server._share_tunnel is None
    client.set_value(dropdown, "star")  # the control still works
    wait_until(lambda: app.runner.latest.shape_name == "star", what="the goal to change")
    client.close()


def test_without_the_token_a_page_only_watches(shared_app):
    app = shared_app
    watcher = RawClient(app.port, own_page(app))
    wid = connected(app, watcher)
    assert app.gate.grant(wid) == Grant("watch", False, "127.0.0.1")
    assert "GuiUpdateMessage" in watcher.received_types(1.0)  # it sees the page and the frames
    watcher.set_value(uuid_of(app.panel.shape.shape), "square")
    watcher.send("ScenePointerMessage", event_type="click", ray_origin=(0.0, 0.0, 10.0),
                 ray_direction=(0.0, 0.0, -1.0), screen_pos=((0.5, 0.5),), modifier=None)
    wait_until(lambda: refusals(app, wid) >= 2, what="two refusals")
    assert app.runner.latest.shape_name == "circle"
    presenter = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    connected(app, presenter)
    presenter.set_value(uuid_of(app.panel.shape.shape), "square")
    wait_until(lambda: app.runner.latest.shape_name == "square", what="the presenter's change")
    watcher.close()
    presenter.close()


def test_the_token_in_the_link_becomes_a_cookie_and_leaves_the_address_bar(shared_app):
    app = shared_app
    response = http_status(app.port, f"127.0.0.1:{app.port}", f"/?token={TOKEN}")
    assert response.status == 302 and response.getheader("Location") == "/"
    cookie = response.getheader("Set-Cookie")
    assert f"phototaxis-token-{app.port}={TOKEN}" in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    assert http_status(app.port, f"127.0.0.1:{app.port}", "/?token=wrong").status == 200  # the page, to watch
    with_cookie = RawClient(app.port, {**own_page(app), "Cookie": cookie.split(";")[0]})
    cid = connected(app, with_cookie)
    assert app.gate.grant(cid).controls
    with_cookie.close()
    assert TOKEN in app.url


def test_only_a_page_on_this_machine_loads_programs_unless_allowed():
    local, remote = "127.0.0.1", "192.0.2.7"
    headers = {"Host": "192.0.2.1:8080", "Authorization": f"token {TOKEN}"}
    shared = Access.for_server("0.0.0.0", token=TOKEN)
    assert shared.decide(headers, "/", remote, websocket=True).grant == Grant("control", False, remote)
    assert shared.decide(headers, "/", local, websocket=True).grant.programs
    allowed = Access.for_server("0.0.0.0", token=TOKEN, allow_programs=True)
    assert allowed.decide(headers, "/", remote, websocket=True).grant.programs
    assert shared.decide({"Host": "192.0.2.1:8080"}, "/", remote, websocket=True).grant.role == "watch"
    none = Access.for_server("0.0.0.0", token=TOKEN, viewers="none")
    assert none.decide({"Host": "192.0.2.1:8080"}, "/", remote, websocket=True).refused


def test_a_page_whose_grant_has_no_programs_cannot_load_one(app, tmp_path):
    marker = tmp_path / "ran.txt"
    program = tmp_path / "p.py"
    program.write_text(f"open({str(marker)!r}, 'w').write('ran')\nclass P:\n    def update(self, o): return None\n")
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    app.gate._grants[cid] = Grant("control", programs=False, address="192.0.2.7")  # as from another machine
    client.set_value(uuid_of(app.panel.program.path), f"{program}:P")
    client.click(uuid_of(app.panel.program.use))
    client.set_value(uuid_of(app.panel.shape.shape), "square")  # after the click, in order
    wait_until(lambda: app.runner.latest.shape_name == "square", what="the later change")
    assert not marker.exists() and app.runner.latest.program == "the paper's controller"
    client.close()


def _rss() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS")


def test_an_endless_upload_never_grows_the_server(app):
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    upload = uuid_of(app.panel.shape.upload)
    part = b"x" * (512 * 1024)
    app.runner.set_playing(False)  # no new frames to draw: what grows is the upload's doing
    wait_until_steady(lambda: app.runner.latest.step)
    before = _rss()
    huge = client.start_upload(upload, size=300 * 1024 * 1024, parts=600)  # refused as announced
    for index in range(300):
        client.upload_part(upload, huge, index, part)
    lying = client.start_upload(upload, size=1000, parts=1)  # announces 1 kB, sends 150 MB
    for index in range(300):
        client.upload_part(upload, lying, index, part)
    client.set_value(uuid_of(app.panel.run.speed), 7)  # handled after every part above
    wait_until(lambda: app.runner.steps_per_frame == 7, timeout=60, what="the server to read it all")
    grown = _rss() - before
    assert grown < 1_000_000 + 5 * 1024 * 1024, f"the server grew by {grown / 1e6:.1f} MB"
    assert app.gate.inbox._transfers == {} and refusals(app, cid) >= 300
    client.close()


def test_upload_acknowledgements_reach_only_the_uploader(app):
    uploader = RawClient(app.port, own_page(app))
    connected(app, uploader)
    upload = uuid_of(app.panel.shape.upload)
    transfer = uploader.start_upload(upload, size=len(TRIANGLE), parts=1, name="tri.txt")
    uploader.upload_part(upload, transfer, 0, TRIANGLE)
    wait_until(lambda: app.runner.latest.shape_name == "tri.txt", what="the uploaded goal")
    # The acknowledgement, then the closing of viser's own "uploaded" notice (the panel says what
    # became of the file: issue 24, item 7).
    received = uploader.received_types(30.0, until=frozenset({"FileTransferPartAck", "RemoveNotificationMessage"}))
    assert "FileTransferPartAck" in received and "RemoveNotificationMessage" in received
    newcomer = RawClient(app.port, own_page(app))
    connected(app, newcomer)
    assert "FileTransferPartAck" not in newcomer.received_types(1.5)  # nothing of it in the backlog
    uploader.close()
    newcomer.close()


def command_uuid(app, label: str) -> str:
    return next(uuid for uuid, handle in app.server.gui._command_handle_from_uuid.items() if handle.label == label)


def test_keyboard_commands_are_checked_like_buttons(shared_app):
    """A key (viser's command palette) triggers a server action: a watching page's is refused, a disabled
    command never acts, the presenter's acts."""
    app = shared_app
    play = command_uuid(app, "Play / pause")
    watcher = RawClient(app.port, own_page(app))
    wid = connected(app, watcher)
    watcher.send("CommandTriggerMessage", uuid=play)
    wait_until(lambda: refusals(app, wid) >= 1, what="the watcher's key refused")
    assert app.runner.playing
    presenter = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    pid = connected(app, presenter)
    app.server.gui._command_handle_from_uuid[play].disabled = True
    presenter.send("CommandTriggerMessage", uuid=play)
    presenter.send("CommandTriggerMessage", uuid="no-such-command")
    wait_until(lambda: refusals(app, pid) >= 2, what="two refusals")
    assert app.runner.playing
    app.server.gui._command_handle_from_uuid[play].disabled = False
    presenter.send("CommandTriggerMessage", uuid=play)
    wait_until(lambda: not app.runner.playing, what="the presenter's space to pause")
    watcher.close()
    presenter.close()


def test_a_page_cannot_press_another_pages_own_controls(app):
    """The inspector's Stop button is each page's own: checked like a shared control (a disabled one
    never acts), and another page's is not there to press."""
    first, second = RawClient(app.port, own_page(app)), RawClient(app.port, own_page(app))
    fid, sid = connected(app, first), connected(app, second)
    inspector = app.panel.inspector
    wait_until(lambda: {fid, sid} <= set(inspector.viewers), what="both pages' inspectors")
    inspector.follow(app.server.get_clients()[fid], 3)
    inspector.follow(app.server.get_clients()[sid], 5)
    first_stop = uuid_of(inspector.viewers[fid].stop)
    second.click(first_stop)  # not second's control
    wait_until(lambda: refusals(app, sid) >= 1, what="the other page's press refused")
    inspector.viewers[fid].stop.disabled = True
    first.click(first_stop)
    wait_until(lambda: refusals(app, fid) >= 1, what="the disabled button refused")
    assert inspector.viewers[fid].robot == 3 and inspector.viewers[sid].robot == 5
    inspector.viewers[fid].stop.disabled = False
    first.click(first_stop)
    wait_until(lambda: app.runner.followed == (5,), what="the page's own Stop to act")
    assert inspector.viewers[fid].robot is None and inspector.viewers[sid].robot == 5
    first.close()
    second.close()


def test_a_watching_page_cannot_start_compare_mode(shared_app):
    """Compare mode starts a simulation process: only a controlling page may, by the dropdown or by
    Learn's Show me."""
    app = shared_app
    watcher = RawClient(app.port, own_page(app))
    wid = connected(app, watcher)
    watcher.set_value(uuid_of(app.panel.compare.choice), "star-switch")
    watcher.click(uuid_of(app.panel.show_me_buttons[0]))
    wait_until(lambda: refusals(app, wid) >= 2, what="two refusals")
    assert app.comparison.runner is None and app.panel.compare.choice.value == "nothing"
    presenter = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    connected(app, presenter)
    presenter.set_value(uuid_of(app.panel.compare.choice), "star-switch")
    wait_until(lambda: app.comparison.runner is not None, what="the presenter's comparison")
    watcher.close()
    presenter.close()
