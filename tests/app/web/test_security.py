"""Attack tests: the server decides, never the page.

Each test drives a running app as a hostile client would: a raw websocket
with a foreign Origin or Host, a click on a disabled control, a property no
page should set, an upload that never ends. Each must change nothing and
load nothing; the same request from the user's own page must work, so that
a refusal is the gate's doing and not a broken client."""

from __future__ import annotations

import http.client
import ipaddress
import socket
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import viser
import websockets.exceptions
import websockets.sync.client

from sandbox.app.web.access import Access, Grant
from sandbox.app.web.gate import MAX_CONNECTIONS, TOKEN_RESERVE, WATCHERS_PER_ADDRESS, WRITTEN_FOR
from sandbox.app.world.orders import SetPlaying
from sandbox.model.config import Config
from tests.viser_wire import RawClient
from tests.waiting import wait_until, wait_until_steady

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
TOKEN = "classroom-secret-42"
TRIANGLE = b"0 0\n6 0\n3 5\n"


def make_app(**kwargs):
    from sandbox.commands.serve import App, free_port

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
    assert viser.__version__ == WRITTEN_FOR, "sandbox/app/web/gate.py wraps viser's internals: re-check them"


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
    folder.use.disabled = True  # a disabled control, whatever disabled it
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
    assert "GuiUpdateMessage" in watcher.received_types(30.0, until=frozenset({"GuiUpdateMessage"}))  # it sees the page
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


def test_the_inbox_and_its_refusal_logs_are_touched_on_the_servers_event_loop_alone(monkeypatch):
    """The inbox and the refusal logs take no lock (sandbox/app/web/inbox.py): a page's message checked,
    its refusal logged and its leaving all run on the server's event loop, one thread."""
    import contextlib
    import io
    import threading

    from sandbox.app.web.gate import start_server
    from sandbox.app.web.inbox import Inbox
    from sandbox.app.web.refusals import RefusalLog
    from sandbox.commands.serve import free_port

    touched: list[tuple[str, threading.Thread, bool]] = []

    def noted(cls: type, name: str) -> None:
        method = getattr(cls, name)

        def on_its_thread(self, *args, **kwargs):
            touched.append((f"{cls.__name__}.{name}", threading.current_thread(), _in_an_event_loop()))
            return method(self, *args, **kwargs)

        monkeypatch.setattr(cls, name, on_its_thread)

    for cls, names in ((Inbox, ("admit", "admit_local", "forget")), (RefusalLog, ("refused", "forget"))):
        for name in names:
            noted(cls, name)
    server, _ = start_server(Access.for_server("127.0.0.1"), host="127.0.0.1", port=free_port(), label="loop")
    try:
        client = RawClient(server.get_port(), {"Origin": f"http://127.0.0.1:{server.get_port()}"})
        client.say_hello()
        wait_until(lambda: server.get_clients(), what="the page to connect")
        client.set_value("no such control", 1)  # refused, and logged
        client.close()
        wanted = {"Inbox.admit", "RefusalLog.refused", "Inbox.forget", "RefusalLog.forget"}
        wait_until(lambda: wanted <= {name for name, _, _ in touched}, what="the check, the refusal, the leaving")
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    threads = {thread for _, thread, _ in touched}
    assert len(threads) == 1 and threading.main_thread() not in threads, touched
    assert all(in_loop for _, _, in_loop in touched), touched


def _in_an_event_loop() -> bool:
    import asyncio

    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return False
    return True


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
    app.runner.submit(SetPlaying(False))  # no new frames to draw: what grows is the upload's doing
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
    # 300 MB were sent: kept, even one part in ten would be 30 MB. What the process keeps of freed
    # 512-kB buffers (its allocator's arenas, the websocket's reads) was up to 6.6 MB in the full suite.
    assert grown < 16 * 1024 * 1024, f"the server grew by {grown / 1e6:.1f} MB"
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
    assert "FileTransferPartAck" not in types_before_the_next_broadcast(app, newcomer)  # nothing of it in the backlog
    uploader.close()
    newcomer.close()


def types_before_the_next_broadcast(app, client: RawClient) -> list[str]:
    """The types of what ``client`` got before a control added now for every page: its backlog, whole (the
    server sends every page one ordered stream, the backlog first), without a window of a fixed time."""
    marker = app.events.call(app.server.gui.add_markdown, "")
    try:
        types = []
        for message in client._messages(30.0):
            if message.get("type") == "GuiMarkdownMessage" and message.get("uuid") == uuid_of(marker):
                return types
            types.append(message.get("type", "?"))
        raise AssertionError("the control added for every page never came")
    finally:
        app.events.call(marker.remove)


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


# ------------------------------------------------------------- issue 39: the network holes
def raw_request(port: int, request_line: bytes, headers: dict[str, bytes] | list | None = None) -> tuple[int, dict]:
    """Send one HTTP request's exact bytes (what http.client would reject or encode); its status and headers.
    ``headers`` as a list of (name, value) pairs may repeat a name (a second Host among them)."""
    lines = [request_line, f"Host: 127.0.0.1:{port}".encode()]
    pairs = headers.items() if isinstance(headers, dict) else headers or []
    lines += [name.encode() + b": " + value for name, value in pairs]
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        sock.sendall(b"\r\n".join(lines) + b"\r\n\r\n")
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = sock.recv(65536)
            if not chunk:
                break
            head += chunk
    status_line, *header_lines = head.split(b"\r\n\r\n", 1)[0].decode("latin-1").split("\r\n")
    return int(status_line.split()[1]), dict(line.split(": ", 1) for line in header_lines)


def connect_many(port: int, headers_of: list[dict]) -> tuple[list[RawClient], list[int]]:
    """Open one websocket per headers at once, as a flooding script would: those let in, and the statuses
    of those refused."""
    def attempt(headers: dict) -> RawClient | int:
        try:
            return RawClient(port, headers)
        except websockets.exceptions.InvalidStatus as refused:
            return refused.response.status_code

    with ThreadPoolExecutor(max_workers=len(headers_of)) as pool:
        outcomes = list(pool.map(attempt, headers_of))
    return [o for o in outcomes if isinstance(o, RawClient)], [o for o in outcomes if isinstance(o, int)]


def close_all(clients: list[RawClient]) -> None:
    with ThreadPoolExecutor(max_workers=max(1, len(clients))) as pool:
        list(pool.map(RawClient.close, clients))


def presenter_controls(app) -> None:
    """A page with the token connects and its change acts: the presenter is never locked out."""
    presenter = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    connected(app, presenter)
    shape = "star" if app.runner.latest.shape_name != "star" else "square"
    presenter.set_value(uuid_of(app.panel.shape.shape), shape)
    wait_until(lambda: app.runner.latest.shape_name == shape, what="the presenter's change")
    presenter.close()


def test_a_crowd_without_the_token_on_one_address_leaves_room_for_the_presenter(shared_app):
    """Hole 1: 63 token-less websockets from this machine once filled the 64 connections and the teacher's
    page was answered 503. One address now holds at most WATCHERS_PER_ADDRESS watching pages."""
    app = shared_app
    crowd, refused = connect_many(app.port, [{}] * 63)
    assert len(crowd) == WATCHERS_PER_ADDRESS and set(refused) == {503}
    presenter_controls(app)
    assert all(client.ws.state.name == "OPEN" for client in crowd)  # the refusals cost the others nothing
    close_all(crowd)


@pytest.mark.slow
def test_a_full_class_without_the_token_leaves_room_for_the_presenter():
    """Hole 1, from many addresses (a class behind a proxy on this machine, --trust-proxy): with 63 pages
    without the token connected, the teacher's page still connects and controls; pages without the token
    take at most MAX_CONNECTIONS - TOKEN_RESERVE connections."""
    app = make_app(access=Access.for_server("127.0.0.1", token=TOKEN, trust_proxy=True))
    try:
        students = [{"X-Forwarded-For": f"198.51.100.{n}"} for n in range(63)]
        crowd, refused = connect_many(app.port, students)
        assert len(crowd) == 63 and not refused
        presenter_controls(app)
        more, refused = connect_many(app.port, [{"X-Forwarded-For": f"198.51.101.{n}"} for n in range(3)])
        assert len(crowd) + len(more) == MAX_CONNECTIONS - TOKEN_RESERVE and refused == [503, 503]
        close_all(crowd + more)
    finally:
        app.stop()


MALFORMED = {
    "a non-ASCII token in the query": (b"GET /?token=%C3%A9 HTTP/1.1", {}),
    "bytes that are not UTF-8 in the query": (b"GET /?token=%FF%FE HTTP/1.1", {}),
    "raw UTF-8 in the query": ("GET /?token=\u00e9 HTTP/1.1".encode(), {}),
    "a non-ASCII Authorization header": (b"GET / HTTP/1.1", {"Authorization": "token \u00e9".encode()}),
    "a Latin-1 Authorization header": (b"GET / HTTP/1.1", {"Authorization": b"token \xe9t\xe9-secret"}),
    "a token with a space": (b"GET / HTTP/1.1", {"Authorization": b"token classroom secret"}),
    "a non-ASCII cookie": (b"GET / HTTP/1.1", {"Cookie": "phototaxis-token-PORT=\u00e9".encode()}),
    "a quoted cookie": (b"GET / HTTP/1.1", {"Cookie": b'phototaxis-token-PORT="x"'}),
}


def test_a_malformed_token_is_refused_with_403_never_a_server_error(shared_app):
    """Hole 6: a non-ASCII token (query, header or cookie) answered 500; any malformed token is now a 403
    with one line, for the page and for the websocket, and the server goes on serving."""
    app = shared_app
    for what, (request_line, headers) in MALFORMED.items():
        headers = {name: value.replace(b"PORT", str(app.port).encode()) for name, value in headers.items()}
        status, _ = raw_request(app.port, request_line, headers)
        assert status == 403, f"{what}: answered {status}"
    with pytest.raises(websockets.exceptions.InvalidStatus) as refused:
        RawClient(app.port, {"Cookie": f"phototaxis-token-{app.port}=caf\u00e9".encode("utf-8").decode("latin-1")})
    assert refused.value.response.status_code == 403
    assert raw_request(app.port, b"GET / HTTP/1.1")[0] == 200  # a page without a token still watches
    presenter_controls(app)


def test_the_link_with_the_token_works_over_a_stale_cookie(shared_app):
    """A cookie left by an earlier server (another token, same port) no longer hides the link's token."""
    app = shared_app
    status, headers = raw_request(app.port, f"GET /?token={TOKEN} HTTP/1.1".encode(),
                                  {"Cookie": f"phototaxis-token-{app.port}=an-older-token".encode()})
    assert status == 302 and f"={TOKEN};" in headers["Set-Cookie"]


OFF_SITE = ["//evil.example/", "///evil.example/", "/\\evil.example/", "/\\/evil.example", "\\\\evil.example",
            "/%2F%2Fevil.example", "/%5Cevil.example", "https://evil.example/", "http:evil.example", "/.//evil.example",
            "/a//evil.example", "/\tevil", "/@evil.example"]


def test_the_token_redirect_goes_only_to_a_path_of_ours(shared_app):
    """Hole 7: with a valid token, GET //evil.example/?token=T answered Location: //evil.example/ (an open
    redirect); every target that is not a plain path of ours now goes to /."""
    app = shared_app
    for target in OFF_SITE:
        status, headers = raw_request(app.port, f"GET {target}?token={TOKEN} HTTP/1.1".encode())
        assert (status, headers["Location"]) == (302, "/"), f"{target!r} sent the page to {headers['Location']!r}"
    status, headers = raw_request(app.port, f"GET /index.html?token={TOKEN}&x=1 HTTP/1.1".encode())
    assert status == 302 and headers["Location"] == "/index.html"


@pytest.fixture
def classroom_app():
    """A server shared beyond this machine, started as serve --host 0.0.0.0 starts it."""
    a = make_app(host="0.0.0.0", access=Access.for_server("0.0.0.0", token=TOKEN))
    yield a
    a.stop()


def program_file(tmp_path: Path, name: str) -> tuple[str, Path]:
    """A program whose import leaves a marker file: its spec and the marker."""
    marker = tmp_path / f"{name}.ran"
    program = tmp_path / f"{name}.py"
    program.write_text(f"open({str(marker)!r}, 'w').write('ran')\nclass P:\n    def update(self, o): return None\n")
    return f"{program}:P", marker


def notification(client: RawClient, title: str, seconds: float = 30.0) -> dict:
    """The first notification titled ``title`` the server sends the client (waits for it). Every message is
    read: one frame of the server's may hold several notifications (``first`` left the rest of its frame
    unread, and on a loaded machine the one looked for was among them)."""
    for message in client._messages(seconds):
        if message.get("type") == "NotificationShowMessage" and message["props"]["title"] == title:
            return message["props"]
    raise AssertionError(f"no {title!r} notification within {seconds:.0f} s")


def own_network_address() -> str | None:
    """This machine's address on its network, if it has one: what a page that asked for the machine's
    name comes from."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("203.0.113.1", 9))  # no packet is sent: the route's source address
        except OSError:
            return None
        address = probe.getsockname()[0]
    return None if ipaddress.ip_address(address).is_loopback else address


def try_to_load(app, client: RawClient, spec: str) -> None:
    client.set_value(uuid_of(app.panel.program.path), spec)
    client.click(uuid_of(app.panel.program.use))


def test_on_a_shared_server_the_teachers_own_page_loads_programs_and_others_are_told_why(classroom_app, tmp_path):
    """Hole 9: docs/security.md says a page on this machine with the token may load programs on
    --host 0.0.0.0; the folder was disabled there and a click refused silently. Now the teacher's page
    loads one, and a page that may not (here: through a proxy, hole 10) is told why."""
    app = classroom_app
    assert not app.panel.program.use.disabled
    teacher = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    connected(app, teacher)
    spec, marker = program_file(tmp_path, "teachers")
    try_to_load(app, teacher, spec)
    wait_until(marker.exists, what="the teacher's program to load")
    proxied = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}", "X-Forwarded-For": "127.0.0.1"})
    pid = connected(app, proxied)
    assert app.gate.grant(pid) == Grant("control", False, "127.0.0.1")
    spec, marker = program_file(tmp_path, "proxied")
    try_to_load(app, proxied, spec)
    assert "only a page opened on the server's own machine" in notification(proxied, "Program not used")["body"]
    assert not marker.exists()
    teacher.close()
    proxied.close()


def test_a_page_that_asked_for_this_machines_network_address_is_this_machines(classroom_app):
    """The teacher opens the printed link (the machine's name, so its network address, not loopback) on the
    server's own machine: that connection comes from this very address, and may load programs."""
    app = classroom_app
    address = own_network_address()
    if address is None:
        pytest.skip("this machine has no network address")
    page = RawClient(app.port, {"Origin": f"http://{address}:{app.port}", "Authorization": f"token {TOKEN}"},
                     host=address)
    cid = connected(app, page)
    assert app.gate.grant(cid) == Grant("control", True, address)
    page.close()


def test_behind_a_proxy_a_page_is_this_machines_only_when_the_proxy_is_trusted():
    """Hole 10: behind a reverse proxy on this machine every visitor's connection is loopback. Without
    --trust-proxy a request with proxy headers is not this machine's page, nor is a browser page of
    another origin (what a proxy that adds no header passes on); with it, X-Forwarded-For's last address,
    the one the proxy added, is the page's, and only from a connection that comes from this machine."""
    headers = {"Host": "127.0.0.1:8080", "Authorization": f"token {TOKEN}"}

    def grant(access: Access, extra: dict, peer: str = "127.0.0.1") -> Grant:
        access.port = 8080
        return access.decide({**headers, **extra}, "/", peer, websocket=True).grant

    plain = Access.for_server("0.0.0.0", token=TOKEN, allow_origins=["https://classroom.example"])
    assert grant(plain, {}).programs and grant(plain, {"Origin": "http://127.0.0.1:8080"}).programs
    for proxy in ({"X-Forwarded-For": "127.0.0.1"}, {"Forwarded": "for=127.0.0.1"}, {"X-Real-IP": "127.0.0.1"}):
        assert grant(plain, proxy) == Grant("control", False, "127.0.0.1"), proxy
    assert not grant(plain, {"Origin": "https://classroom.example"}).programs
    assert Access.for_server("127.0.0.1", trust_proxy=True).token  # visitors come from afar: control needs one
    trusted = Access.for_server("0.0.0.0", token=TOKEN, trust_proxy=True)
    assert grant(trusted, {"X-Forwarded-For": "127.0.0.1, 203.0.113.9"}) == Grant("control", False, "203.0.113.9")
    assert grant(trusted, {"X-Forwarded-For": "203.0.113.9, 127.0.0.1"}) == Grant("control", True, "127.0.0.1")
    assert grant(trusted, {"X-Forwarded-For": "[2001:db8::1]:4711"}).address == "2001:db8::1"
    assert grant(trusted, {"X-Real-IP": "127.0.0.1"}) == Grant("control", False, "127.0.0.1")  # no X-Forwarded-For
    assert grant(trusted, {}) == Grant("control", True, "127.0.0.1")  # a browser on this machine, straight in
    # A connection from elsewhere (past the proxy) is not believed, whatever it says.
    assert grant(trusted, {"X-Forwarded-For": "127.0.0.1"}, peer="192.0.2.7") == Grant("control", False, "192.0.2.7")


def test_serve_trust_proxy_reaches_the_servers_rules_and_a_bad_token_is_one_line(monkeypatch, capsys):
    from sandbox.commands import serve as server
    from sandbox.commands import main

    seen: dict = {}

    def no_app(config, **kwargs):  # the rules serve built, without listening
        seen.update(kwargs)
        raise OSError(98, "Address already in use")

    monkeypatch.setattr(server, "App", no_app)
    assert main(["serve", "--host", "0.0.0.0", "--trust-proxy"]) == 2 and seen["access"].trust_proxy
    assert main(["serve", "--host", "0.0.0.0"]) == 2 and not seen["access"].trust_proxy
    capsys.readouterr()
    assert main(["serve", "--token", "caf\u00e9-secret-42"]) == 2
    said = capsys.readouterr().err.strip()
    assert "--token must be" in said and "ASCII" in said and "\n" not in said


# ----------------------------------------------------------- issue 54 G: the small holes
def refused_websocket_status(port: int, headers: list[tuple[str, str]], path: str = "/") -> int:
    """The status a websocket handshake with ``headers`` (a list: a name may repeat) is refused with."""
    with pytest.raises(websockets.exceptions.InvalidStatus) as refused:
        RawClient(port, headers, path=path).close()
    return refused.value.response.status_code


def test_a_duplicated_host_or_origin_is_refused_with_403_never_a_server_error(app, caplog):
    """Hole G1: two Host or two Origin headers answered 500 (viser's headers refuse to pick one) and nothing
    was logged. A request that repeats either is refused with 403 and one line, whatever the values, page
    and websocket alike; the same request with one of each still works."""
    own_host, own_origin = f"127.0.0.1:{app.port}", f"http://127.0.0.1:{app.port}"
    twice = {
        "the same Host twice": [("Host", own_host.encode())],
        "another Host after ours": [("Host", b"rebind.evil.example")],
        "the same Origin twice": [("Origin", own_origin.encode())] * 2,
        "our Origin and another": [("Origin", own_origin.encode()), ("Origin", b"http://evil.example")],
    }
    for what, headers in twice.items():
        status, _ = raw_request(app.port, b"GET / HTTP/1.1", headers)
        assert status == 403, f"page with {what}: answered {status}"
        ws_headers = [(name, value.decode()) for name, value in headers]
        if any(name == "Host" for name, _ in headers):  # the client sends its own Host: one more makes two
            ws_headers = [("Host", own_host)] if what == "the same Host twice" else ws_headers
        status = refused_websocket_status(app.port, ws_headers)
        assert status == 403, f"websocket with {what}: answered {status}"
    said = [r.getMessage() for r in caplog.records if r.name == "sandbox.app.web.gate"]
    assert sum("more than one" in line for line in said) == 2 * len(twice), said
    assert raw_request(app.port, b"GET / HTTP/1.1", [("Origin", own_origin.encode())])[0] == 200
    connected(app, RawClient(app.port, own_page(app)))


def test_every_token_a_request_presents_must_be_well_formed(shared_app):
    """Hole G2: ?token=VALID&token=%C3%A9 answered 302 (only the first query token was read), where a
    malformed token is a 403. Every token a request presents (each query parameter, each cookie, each
    Authorization header) must be well-formed; control needs one of them to be the server's, so the
    token repeated, or beside a stale one, still controls."""
    app = shared_app
    cookie = f"phototaxis-token-{app.port}"
    malformed = {
        "the token and then a non-ASCII one": (f"/?token={TOKEN}&token=%C3%A9", []),
        "a non-ASCII one and then the token": (f"/?token=%C3%A9&token={TOKEN}", []),
        "the token and an empty one": (f"/?token={TOKEN}&token=", []),
        "two cookies in one header": ("/", [("Cookie", f"{cookie}={TOKEN}; {cookie}=caf\u00e9".encode())]),
        "two Cookie headers": ("/", [("Cookie", f"{cookie}={TOKEN}".encode()), ("Cookie", f"{cookie}=a b".encode())]),
        "two Authorization headers": ("/", [("Authorization", f"token {TOKEN}".encode()),
                                            ("Authorization", "token caf\u00e9".encode())]),
    }
    for what, (path, headers) in malformed.items():
        status, _ = raw_request(app.port, f"GET {path} HTTP/1.1".encode(), headers)
        assert status == 403, f"{what}: answered {status}"
    assert refused_websocket_status(app.port, [], path=f"/?token={TOKEN}&token=%C3%A9") == 403
    for repeated in (f"/?token={TOKEN}&token={TOKEN}", f"/?token=an-older-token&token={TOKEN}"):
        status, headers = raw_request(app.port, f"GET {repeated} HTTP/1.1".encode())
        assert status == 302 and f"={TOKEN};" in headers["Set-Cookie"], repeated
    presenter_controls(app)


def test_repeated_headers_a_browser_may_send_never_make_a_server_error(app, caplog):
    """Left from hole G1: two Upgrade headers answered 500 (the gate asked websockets' headers for one value)
    and two Accept-Encoding headers, which HTTP allows, answered 500 from viser's page server. Two Upgrade
    headers are a 400 with one line; two Accept-Encoding headers are read as one list and get the page."""
    status, _ = raw_request(app.port, b"GET / HTTP/1.1", [("Upgrade", b"websocket"), ("Upgrade", b"websocket")])
    assert status == 400
    said = [r.getMessage() for r in caplog.records if r.name == "sandbox.app.web.gate"]
    assert any("more than one Upgrade header" in line for line in said), said
    status, headers = raw_request(app.port, b"GET / HTTP/1.1", [("Accept-Encoding", b"identity"),
                                                                 ("Accept-Encoding", b"gzip")])
    assert status == 200 and headers.get("Content-Encoding") == "gzip"
    assert not [r for r in caplog.records if r.exc_info], "a traceback was logged"
    connected(app, RawClient(app.port, own_page(app)))


def test_a_connection_that_closes_before_its_request_logs_one_line_not_a_traceback(app, caplog, monkeypatch):
    """A bare TCP connection closed before any request made websockets log 'opening handshake failed' with
    its whole traceback: a script opening and closing sockets would fill the log. It is one line, at most
    one a second."""
    import logging

    from sandbox.app.web.gate import QuietHandshakes

    # A filter of its own: the process's counts a second from the last line it let through, and a line an
    # earlier test of this worker caused held back all twenty here (the wait below then ran out its minute).
    monkeypatch.setattr(logging.getLogger("websockets.server"), "filters", [QuietHandshakes()])
    for _ in range(20):
        socket.create_connection(("127.0.0.1", app.port), timeout=5).close()
    wait_until(lambda: any("opening handshake failed" in r.getMessage() for r in caplog.records),
               what="websockets to notice the closed connections")
    failed = [r for r in caplog.records if "opening handshake failed" in r.getMessage()]
    assert all(r.exc_info is None for r in failed), "a traceback was logged"
    assert len(failed) <= 2, [r.getMessage() for r in failed]
    connected(app, RawClient(app.port, own_page(app)))
