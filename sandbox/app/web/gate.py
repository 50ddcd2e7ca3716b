"""The sandbox's viser server with a gate: :func:`start_server`.
Built on the main thread; its checks run on viser's event loop, and the app's event thread asks it a page's grant.

viser 1.1.1 answers any request: it checks neither ``Origin`` nor ``Host``,
lets any client set any property of any control (``disabled`` is drawn by
the page, never enforced), buffers uploads without a limit and broadcasts
their acknowledgements into the backlog every new viewer replays. It has no
hook for any of this, so this module reaches into its websocket server, in
four places, all of them private to viser 1.1.1 and reached through
:mod:`sandbox.app.web.viser_seam` (its table lists each; a test pins the version,
and :func:`start_server` refuses to start on a viser that lacks any):

1. **The opening handshake.** viser hands websockets a ``process_request``
   (it serves the page with it). Inside viser's infra module only, the name
   ``websockets`` is replaced by a view whose ``asyncio.server.serve`` wraps
   that function with :meth:`Gate.process_request`, which applies
   :mod:`sandbox.app.web.access` to every HTTP request and websocket upgrade,
   caps message sizes and counts connections (room kept for pages with the
   token, a limit per address for the others). While a server is being built
   and until its gate is attached, every request is refused (the gate fails
   closed).
2. **Each connection's grant.** An infra-level connect callback (it runs
   before the connection's first message is read) takes the grant the
   handshake decided for that raw connection.
3. **Incoming messages.** Each connection's messages are read within its
   budgets (:mod:`sandbox.app.web.rates`, which replaces viser's reading loop and
   decodes them with :mod:`sandbox.app.web.well_formed`); the server's (and each
   connection's) dispatch of them goes through
   :class:`sandbox.app.web.inbox.Inbox` first, which refuses what the grant does
   not allow and handles uploads itself.
4. **The shared scene's windows.** Each connection's windows of the
   broadcast buffer pass through :class:`sandbox.app.web.pacing.Pacer`, which
   holds them for a page until it reports drawing the last (the report is
   an address this gate answers, behind the same checks as the page). A
   seat's page (``serve --class``) is sent none of the shared scene and GUI,
   only the marker that ends the replay: everything it shows is its own.

The page is not a boundary: everything a control can trigger is checked here
or in the callback, whatever the page shows.

The gate runs on viser's event loop (the server's thread: handshakes, connections,
every message's check); the app's event thread asks it a page's grant, and
:func:`start_server` runs on the thread that builds the app (the main thread).
"""

from __future__ import annotations

import contextlib
import dataclasses
import http
import io
import logging
import threading
import time
import weakref
from concurrent.futures import Future
from typing import Any, Callable

import viser
import websockets

from sandbox.app.web import rates
from sandbox.app.web import viser_seam
from sandbox.app.web import wakeups
from sandbox.app.web.access import Access, Grant, address_group, redirect_target
from sandbox.app.web.inbox import Inbox
from sandbox.app.web.pacing import PATH as DRAWN_PATH
from sandbox.app.web.pacing import Pacer
from sandbox.app.web.page_keys import KEYS_JS
from sandbox.app.web.page_layout import LAYOUT_JS
from sandbox.app.web.page_sends import SENDS_JS
from sandbox.app.web.page_touch import TOUCH_JS
from sandbox.app.web.viser_seam import WRITTEN_FOR  # noqa: F401 - where the tests look for it

#: Largest websocket message a client may send: an upload part is 512 KiB (viser's client).
CONTROL_MESSAGE_BYTES = 1024 * 1024
#: A watching page sends nothing but its camera.
WATCH_MESSAGE_BYTES = 64 * 1024
#: Frames websockets may hold unread per connection (its default is 16).
MAX_QUEUE = 1
#: Open connections at once, watching pages included: a class of 64 watching pages and 8 with the token.
MAX_CONNECTIONS = 72
#: Of those, the ones kept for pages with the token: pages without it never hold more than the rest, so
#: the presenter connects however many others try.
TOKEN_RESERVE = 8
#: Pages without the token from one address (sandbox.app.web.access.address_group: every loopback address is one).
WATCHERS_PER_ADDRESS = 16

log = logging.getLogger("sandbox.app.web.gate")


class Gate:
    """One server's access rules applied to its handshakes, connections and messages."""

    def __init__(self, access: Access):
        self.access = access
        self.ready = False  # until attached, every request is refused
        self.server: viser.ViserServer | None = None
        self.inbox: Inbox | None = None
        self._handshaken: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # raw connection -> Grant
        self._grants: dict[int, Grant] = {}
        # Shared by viser's event loop (a page arriving and leaving, each message's check) and the app's
        # event thread, which asks a page's grant (when it arrives, when it loads a program): _grants.
        self._lock = threading.Lock()
        self.pacer = Pacer()

    # ------------------------------------------------------------ handshake
    def process_request(self, viser_answer: Callable | None) -> Callable:
        """websockets' ``process_request``: the gate's answer, else viser's (the page's files)."""

        def answer(connection: Any, request: Any) -> Any:
            try:
                return self._answer(connection, request, viser_answer)
            except Exception as exc:  # a request nothing here foresaw: one line and a 400, never a 500
                log.warning("refused a malformed request %s from %s: %s: %s", request.path.split("?")[0][:80],
                            _peer(connection), type(exc).__name__, str(exc)[:200])
                return connection.respond(http.HTTPStatus.BAD_REQUEST, "malformed request\n")

        return answer

    def _answer(self, connection: Any, request: Any, viser_answer: Callable | None) -> Any:
        """The gate's answer to one request (None lets websockets upgrade it), else viser's."""
        upgrades = request.headers.get_all("Upgrade")
        if len(upgrades) > 1:  # websockets' headers refuse to pick one: say so rather than fail
            log.warning("refused %s from %s: more than one Upgrade header", request.path.split("?")[0][:80],
                        _peer(connection))
            return connection.respond(http.HTTPStatus.BAD_REQUEST,
                                      "this request has more than one Upgrade header; send one\n")
        upgrade = bool(upgrades) and upgrades[0].lower() == "websocket"
        if not self.ready:
            return connection.respond(http.HTTPStatus.SERVICE_UNAVAILABLE, "starting; try again\n")
        peer = _peer(connection)
        decision = self.access.decide(request.headers, request.path, peer, websocket=upgrade,
                                      server_address=_server_address(connection))
        if decision.refused:
            log.warning("refused %s %s from %s: %s", "websocket" if upgrade else "request",
                        request.path.split("?")[0], peer, decision.reason)
            return connection.respond(decision.status, decision.reason + "\n")
        no_room = self._no_room_for(decision.grant) if upgrade else ""
        if no_room:
            log.warning("refused websocket from %s: %s", decision.grant.address, no_room)
            return connection.respond(http.HTTPStatus.SERVICE_UNAVAILABLE, no_room + "\n")
        if not upgrade and request.path.startswith(DRAWN_PATH):  # a page drew a frame
            known = self.pacer.drawn(request.path[len(DRAWN_PATH):])
            return connection.respond(http.HTTPStatus.NO_CONTENT if known else http.HTTPStatus.NOT_FOUND, "")
        if upgrade:
            self._handshaken[connection] = decision.grant
            rates.track(connection, decision.grant.acts)  # its budgets, from its first message
            limit = CONTROL_MESSAGE_BYTES if decision.grant.acts else WATCH_MESSAGE_BYTES
            connection.protocol.max_message_size = limit
            return None
        if decision.location:  # a new seat: the page goes on to its own address
            response = connection.respond(http.HTTPStatus.FOUND, "")
            response.headers["Location"] = decision.location  # ours: a path made here
            response.headers["Cache-Control"] = "no-store"
            return response
        if decision.page:  # a seat's address is the page that lives at /
            request = dataclasses.replace(request, path="/")
        if decision.store_token:  # keep the token in a cookie and take it out of the address bar
            response = connection.respond(http.HTTPStatus.FOUND, "")
            response.headers["Location"] = redirect_target(request.path)  # ours: never another site
            response.headers["Set-Cookie"] = self.access.set_cookie_header()
            response.headers["Cache-Control"] = "no-store"
            return response
        _one_list(request.headers, "Accept-Encoding")  # HTTP allows it twice; viser reads one value
        return viser_answer(connection, request) if viser_answer else None

    def _no_room_for(self, grant: Grant) -> str:
        """Why a new connection with ``grant`` finds no room (empty when it does): at most
        :data:`MAX_CONNECTIONS` in all; pages without the token leave :data:`TOKEN_RESERVE` of them free
        and hold at most :data:`WATCHERS_PER_ADDRESS` from one address."""
        with self._lock:
            grants = list(self._grants.values())
        grants += list(self._handshaken.values())
        if len(grants) >= MAX_CONNECTIONS:
            return "too many connections; try again later"
        if grant.controls:
            return ""
        if grant.seat:  # one page at a time holds a seat; the seats themselves are counted as they are issued
            if any(g.seat == grant.seat for g in grants):
                return "this world is open in another page; close it there first"
            if sum(1 for g in grants if not g.controls) >= MAX_CONNECTIONS - TOKEN_RESERVE:
                return "too many pages are open; try again later"
            return ""
        watching = [g for g in grants if not g.controls and not g.seat]
        if len(watching) >= MAX_CONNECTIONS - TOKEN_RESERVE:
            return "too many pages are watching; try again later"
        group = address_group(grant.address)
        if sum(address_group(g.address) == group for g in watching) >= WATCHERS_PER_ADDRESS:
            return f"too many pages are watching from your address (at most {WATCHERS_PER_ADDRESS})"
        return ""

    # ----------------------------------------------------------- connections
    def attach(self, server: viser.ViserServer, inbox: Inbox) -> None:
        """Hook the built server's connections and dispatch, then open the gate."""
        self.server, self.inbox = server, inbox
        self.access.port = server.get_port()
        quiet_handshakes()
        viser_seam.on_connections(server, self._on_connect, self._on_disconnect)
        viser_seam.guard_messages(server, lambda client_id, message:
                                  inbox.admit(client_id, self.grant(client_id), message))
        viser_seam.pace_windows(server, self._windows)
        self.ready = True

    def _windows(self, windows: Any, client_id: int, full: int) -> Any:
        """A connection's windows of the shared scene: paced, or for a seat's page, none of it."""
        grant = self.grant(client_id)
        if grant is not None and grant.seat:
            return _replay_marker_only(windows)
        return self.pacer.hold_windows(windows, client_id, full)

    def grant(self, client_id: int) -> Grant | None:
        with self._lock:
            return self._grants.get(client_id)

    def flow(self, client_id: int) -> rates.Flow | None:
        """The budgets of a page's connection, and what became of its messages."""
        raw = viser_seam.raw_connection(self.server, client_id) if self.server is not None else None
        return rates.flow_of(raw) if raw is not None else None

    def may_load_programs(self, client: Any) -> bool:
        grant = self.grant(getattr(client, "client_id", -1))
        return grant is not None and grant.controls and grant.programs

    async def _on_connect(self, connection: Any) -> None:
        raw = viser_seam.raw_connection(self.server, connection.client_id)
        grant = self._handshaken.pop(raw, None) if raw is not None else None
        with self._lock:
            if grant is not None:
                self._grants[connection.client_id] = grant
        flow = rates.flow_of(raw) if raw is not None else None
        if flow is not None:
            flow.client_id = connection.client_id  # (its refusals are logged under its id)
        if grant is None:  # not through our handshake: nothing it sends is heard
            log.warning("connection %s has no grant; closing it", connection.client_id)
            if raw is not None:
                await raw.close(1008, "refused")
            return
        inbox = self.inbox
        # this connection's own handlers (its camera, its own controls)
        viser_seam.guard_connection_messages(connection, lambda client_id, message:
                                             inbox.admit_local(client_id, grant, message))
        # The page reports the frames it draws, so it gets no more than it draws (sandbox.app.web.pacing),
        # arrows pressed on a slider do not also turn its camera (sandbox.app.web.page_keys), a busy page's
        # clicks are not held back and merged (sandbox.app.web.page_sends), a finger on the floor clicks as a
        # mouse does (sandbox.app.web.page_touch), and a phone's panel is a drawer (sandbox.app.web.page_layout).
        for source in (self.pacer.script_for(connection.client_id), KEYS_JS, SENDS_JS, TOUCH_JS, LAYOUT_JS):
            connection.queue_message(viser_seam.messages.RunJavascriptMessage(source=source))

    async def _on_disconnect(self, connection: Any) -> None:
        self.pacer.forget(connection.client_id)
        with self._lock:
            self._grants.pop(connection.client_id, None)
        if self.inbox is not None:
            self.inbox.forget(connection.client_id)


# --------------------------------------------------------------- building
# Shared by the thread that builds a server (the main thread) and the new server's event loop thread,
# which reads _gate_being_built (_gated_serve) while its builder waits: one build at a time, so a
# second builder cannot swap the gate under it.
_building = threading.Lock()
_gate_being_built: Gate | None = None
_serve = websockets.asyncio.server.serve


def _gated_serve(*args: Any, **kwargs: Any) -> Any:
    """websockets' ``serve`` as viser's infra module sees it: the gate goes in front of viser's answer."""
    gate = _gate_being_built
    if gate is None:  # a viser server not built by start_server: refuse everything rather than serve it open
        gate = Gate(Access())
    kwargs["process_request"] = gate.process_request(kwargs.get("process_request"))
    kwargs["max_size"] = CONTROL_MESSAGE_BYTES
    kwargs["max_queue"] = MAX_QUEUE
    return _serve(*args, **kwargs)


def start_server(access: Access, *, host: str, port: int, label: str, verbose: bool = False,
                 inbox: Callable[[Gate], Inbox] | None = None,
                 callbacks: Callable[..., Future] | None = None) -> tuple[viser.ViserServer, Gate]:
    """A viser server behind a gate for ``access``; ``inbox(gate)`` builds the message checks;
    ``callbacks(fn, *args)``, if given, runs every callback viser would run on its thread pool (the
    app's event queue), from before the first page can connect. Refuses
    (:class:`sandbox.app.web.viser_seam.ViserMismatch`) on a viser that lacks what the seam uses."""
    global _gate_being_built
    viser_seam.check()
    viser_seam.serve_websockets_through(_gated_serve)
    viser_seam.read_messages_through(rates.consume)
    wakeups.install()
    gate = Gate(access)
    with _building:
        _gate_being_built = gate
        try:
            with contextlib.redirect_stdout(io.StringIO()) if not verbose else contextlib.nullcontext():
                server = viser.ViserServer(host=host, port=port, label=label, verbose=verbose)
        finally:
            _gate_being_built = None
    try:
        if callbacks is not None:  # before the gate opens: no page's callback goes anywhere else
            viser_seam.route_callbacks(server, callbacks)
        gate.attach(server, inbox(gate) if inbox else Inbox(server, gate))
    except BaseException:
        server.stop()
        raise
    return server, gate


async def _replay_marker_only(windows: Any) -> Any:
    """Of the shared buffer's windows, only the marker that ends the replay (the page waits for it)."""
    async for window in windows:
        kept = [message for message in window if isinstance(message, viser_seam.messages.ReplayDoneMessage)]
        if kept:
            yield kept


def _one_list(headers: Any, name: str) -> None:
    """A header sent more than once, as one comma-separated list (HTTP allows a list header to be split;
    websockets' headers refuse to give one value for it, and viser asks for one)."""
    values = headers.get_all(name)
    if len(values) > 1:
        del headers[name]
        headers[name] = ", ".join(values)


class QuietHandshakes(logging.Filter):
    """websockets logs "opening handshake failed" with a whole traceback for each connection that closes or
    sends something other than HTTP before its request: a script opening sockets would fill the log. This
    makes it one warning naming the last reason, at most one a second, with a count of the ones not said."""

    def __init__(self, every: float = 1.0):
        super().__init__()
        self.every, self._said_at, self._unsaid = every, float("-inf"), 0
        # Shared by the event loop threads of every viser server in the process: one filter on websockets'
        # logger serves them all (`serve` runs one server; a process may run more, as the tests do).
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        if record.msg != "opening handshake failed":
            return True
        reason = _last_reason(record.exc_info)
        record.exc_info, record.exc_text, record.stack_info = None, None, None
        now = time.monotonic()
        with self._lock:
            if now - self._said_at < self.every:
                self._unsaid += 1
                return False
            unsaid, self._said_at, self._unsaid = self._unsaid, now, 0
        record.levelno, record.levelname = logging.WARNING, "WARNING"
        record.msg, record.args = "opening handshake failed: %s%s", (
            reason, f" ({unsaid} more since the last line)" if unsaid else "")
        return True


def _last_reason(exc_info: Any) -> str:
    """The innermost cause of a logged exception, in one line."""
    exc = exc_info[1] if exc_info else None
    while exc is not None and exc.__cause__ is not None:
        exc = exc.__cause__
    return f"{type(exc).__name__}: {str(exc)[:200]}" if exc is not None else "no reason given"


def quiet_handshakes(logger: logging.Logger = logging.getLogger("websockets.server")) -> None:
    """Put :class:`QuietHandshakes` on websockets' server logger, once per process."""
    if not any(isinstance(f, QuietHandshakes) for f in logger.filters):
        logger.addFilter(QuietHandshakes())


def _peer(connection: Any) -> str:
    try:
        address = connection.remote_address
    except Exception:  # noqa: BLE001 - a half-open socket has none
        return ""
    return str(address[0]) if address else ""


def _server_address(connection: Any) -> str:
    """The address the connection reached the server at (a page on this machine that asked for its network
    name comes from this very address)."""
    try:
        address = connection.local_address
    except Exception:  # noqa: BLE001 - a half-open socket has none
        return ""
    return str(address[0]) if address else ""
