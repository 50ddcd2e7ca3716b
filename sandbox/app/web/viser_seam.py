"""The one place the app touches viser's private code: the table :data:`USES`, its check, and the
functions the rest of the app calls instead.
Its check runs on the main thread before a server starts; each function runs on the thread that calls it, as the public API it stands in for would.

viser 1.1.1 has no public hook for what the gate, the inbox and the pacing need (the opening
handshake, each incoming message, the windows of the shared scene, a message to one page only), so
the app reaches into viser's private code. Each such use is a row of :data:`USES`: what we use, where
in viser it is, why we need it, and how :func:`check` finds it. :func:`check` runs before a server is
built and refuses to start, in one line naming the installed viser and what it lacks, when any row is
missing; nothing then fails half-way through a connection. ``tests/app/web/test_viser_seam.py`` fails when
any other module of ``sandbox`` names a private viser module or name. Where viser has a public way
that says the same (a control's ``value``, the handle classes), the app uses it; a handle's public
properties do not always say what the page was sent (a button group's ``disabled`` is always False),
so the inbox reads :func:`props`.

A private module is imported only here, and where a viser may lack it, without failing: the app can
still be imported, and :func:`check` says what is missing.
"""

from __future__ import annotations

import asyncio
import dataclasses
import dis
import importlib
import inspect
import logging
import types
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path
from typing import Any, AsyncGenerator, Callable

import viser

from sandbox.app.web.events import QueueStopped

log = logging.getLogger("sandbox.app.web.viser_seam")

#: The viser release whose private code this module uses (pinned in pyproject.toml and by a test).
WRITTEN_FOR = "1.1.1"

# How check() finds a row's piece.
ATTRIBUTE = "attribute"  # an attribute of a module or class (a method, a class, a function)
ASSIGNED = "assigned"    # an instance attribute: some method of the class (or a base) assigns self.<name>
FIELDS = "fields"        # the dataclass has these fields
KEYS = "keys"            # the TypedDict has these keys


@dataclass(frozen=True)
class Use:
    """One use of viser's private code: what, where in viser (``module:Class.attribute``), why, and how
    :func:`check` finds it (``names`` for several attributes, fields or keys of ``where``; ``arguments``:
    a callable that must take that many positional arguments)."""

    what: str
    where: str
    why: str
    how: str = ATTRIBUTE
    names: tuple[str, ...] = ()
    arguments: int | None = None


#: The message classes the app builds or tells apart (``viser._messages`` has no public home).
MESSAGE_NAMES = ("RunJavascriptMessage", "GuiUpdateMessage", "GuiButtonHoldMessage", "CommandTriggerMessage",
                 "ViewerCameraMessage", "ShareUrlRequest", "ShareUrlDisconnect", "GuiFormSubmitMessage",
                 "GuiFormDirtyMessage", "FileTransferStartUpload", "FileTransferPart", "FileTransferPartAck",
                 "RemoveNotificationMessage", "ScenePointerMessage", "SceneNodeClickMessage", "SceneNodeDragMessage",
                 "TransformControlsUpdateMessage", "TransformControlsDragStartMessage",
                 "TransformControlsDragEndMessage", "GetRenderResponseMessage", "LocalStorageGetItemResponseMessage",
                 "ReplayDoneMessage")

INFRA = "viser.infra._infra"
BUFFER = "viser.infra._async_message_buffer"

USES: tuple[Use, ...] = (
    # ---------------------------------------------------------------- the gate (sandbox.app.web.gate)
    Use("websockets as viser's infra module sees it", f"{INFRA}:websockets",
        "the gate wraps websockets' serve there: its process_request checks every HTTP request and "
        "websocket upgrade, and it caps message sizes and queues (viser takes no process_request)"),
    Use("a ViserServer's websocket server", "viser._viser:ViserServer._websock_server",
        "its connect and disconnect callbacks, its dispatch and its broadcast buffer", ASSIGNED),
    Use("connect and disconnect callbacks of the websocket server", f"{INFRA}:WebsockServer",
        "a connection's grant is taken before its first message is read (ViserServer's own come later)",
        names=("on_client_connect", "on_client_disconnect")),
    Use("the raw websockets connection of a client id", f"{INFRA}:WebsockServer._live_connections",
        "the grant the handshake decided is kept per raw connection; a connection without one is closed",
        ASSIGNED),
    Use("the server's dispatch of incoming messages", f"{INFRA}:WebsockServer._handle_incoming_message",
        "every message goes through the inbox's checks before viser acts on it", arguments=2),
    Use("a connection's own dispatch of incoming messages",
        f"{INFRA}:WebsockClientConnection._handle_incoming_message",
        "the same checks before the page's own handlers (its camera, its own controls)", arguments=2),
    Use("the loop that reads each connection's messages", f"{INFRA}:_message_consumer",
        "replaced process-wide by sandbox.app.web.rates.consume: each connection's budget is applied before a "
        "message is read, and a malformed message is refused in one line instead of closing the connection "
        "with a traceback", arguments=3),
    Use("a connection's message queue", f"{INFRA}:WebsockClientConnection.queue_message",
        "scripts of ours for one page at connect, and messages for one page only", arguments=1),
    Use("a connection's client id", f"{INFRA}:WebsockClientConnection.client_id",
        "grants, pacing and uploads are kept per client id", ASSIGNED),
    # ------------------------------------------------------------- the pacing (sandbox.app.web.pacing)
    Use("the shared scene's message buffer", f"{INFRA}:WebsockServer._broadcast_buffer",
        "its windows are paced per page", ASSIGNED),
    Use("the windows of the broadcast buffer, one generator per connection",
        f"{BUFFER}:AsyncMessageBuffer.window_generator",
        "each page's windows are held until the page reports drawing the last", arguments=1),
    Use("the size at which viser cuts a window", f"{BUFFER}:AsyncMessageBuffer",
        "a full window may end inside a frame, so the rest follows at once", FIELDS, names=("max_window_size",)),
    # ---------------------------------------------------------- the wake-ups (sandbox.app.web.wakeups)
    Use("each message buffer's wake-up event and loop", f"{BUFFER}:AsyncMessageBuffer",
        "AsyncMessageBuffer.__init__ is wrapped process-wide so that each new buffer's message_event is "
        "one other threads may set safely", FIELDS, names=("message_event", "event_loop")),
    Use("asyncio.Event's flag", "asyncio.locks:Event._value",
        "a LoopSafeEvent raises the flag from another thread without touching the waiters "
        "(sandbox.app.web.wakeups)", ASSIGNED),
    # --------------------------------------------------------------- the inbox (sandbox.app.web.inbox)
    Use("the message classes", "viser._messages", "the inbox tells messages apart and sends some itself; "
        "the gate sends RunJavascriptMessage; sandbox.app.web.well_formed decodes those a page sends",
        names=MESSAGE_NAMES),
    Use("a handle's state", "viser._assignable_props_api:AssignablePropsBase._impl",
        "its uuid, whether it is removed, and its props as the page was sent them (a button group's "
        "public disabled is always False)", ASSIGNED),
    Use("a control's state", "viser._gui_handles:_GuiHandleState", "uuid, removed and props of a control",
        FIELDS, names=("uuid", "removed", "props")),
    Use("a command's state", "viser._gui_handles:_CommandHandleState", "uuid, removed and props of a command",
        FIELDS, names=("uuid", "removed", "props")),
    Use("controls by uuid", "viser._gui_api:GuiApi._gui_input_handle_from_uuid",
        "the control a message names, shared or the page's own, to check it is shown and enabled", ASSIGNED),
    Use("keyboard commands by uuid", "viser._gui_api:GuiApi._command_handle_from_uuid",
        "the command a message names, to check it is enabled", ASSIGNED),
    Use("an upload button's callbacks", "viser._gui_handles:_GuiHandleState",
        "the inbox receives uploads itself (size limit, one per page) and calls them with the whole file in "
        "the event (viser would put it in the button's value, which every page shares)", FIELDS,
        names=("update_cb",)),
    Use("a client's connection", "viser._viser:ClientHandle._websock_connection",
        "a message to this page only, never into the backlog every new page replays", ASSIGNED),
    # -------------------------------------------------------------- the icons (sandbox.app.web.icons)
    Use("viser's icon reader", "viser._icons", "replaced by one that opens the icon archive once "
        "(1.3 s saved per server start)", names=("svg_from_icon", "ICONS_DIR")),
    Use("the icon reader where the GUI calls it", "viser._gui_api:svg_from_icon",
        "imported by name there, so replaced there too"),
    Use("the icon reader where the handles call it", "viser._gui_handles:svg_from_icon",
        "imported by name there, so replaced there too"),
    # ------------------------------------------------------------------ route_callbacks (the lead's)
    Use("the server's thread pool", "viser._viser:ViserServer._thread_executor",
        "sync callbacks (connect, disconnect, camera) and each new page's GUI and scene get it: route_callbacks "
        "replaces it", ASSIGNED),
    Use("the GUI's thread pool", "viser._gui_api:GuiApi._thread_executor",
        "sync GUI callbacks (updates, clicks, commands) run on it: route_callbacks replaces it, and "
        "finish_upload gives it an upload button's", ASSIGNED),
    Use("the scene's thread pool", "viser._scene_api:SceneApi._thread_executor",
        "sync scene callbacks (pointer, clicks, drags) run on it: route_callbacks replaces it", ASSIGNED),
)


class ViserMismatch(RuntimeError):
    """The installed viser lacks a piece of :data:`USES`: the app refuses to start on it."""


# ------------------------------------------------------------------ check
def check() -> None:
    """Refuse (one line) to serve on a viser that lacks any piece of :data:`USES`."""
    absent = missing()
    if absent:
        raise ViserMismatch(f"viser {viser.__version__} lacks what sandbox/app/web/viser_seam.py uses from viser "
                            f"{WRITTEN_FOR}: {', '.join(absent)}; install viser=={WRITTEN_FOR}")


def missing(uses: tuple[Use, ...] = USES) -> list[str]:
    """The pieces of ``uses`` the installed viser (and Python) lack, each as ``module:Class.attribute``."""
    return [piece for use in uses for piece in _missing(use)]


def _missing(use: Use) -> list[str]:
    module_name, _, path = use.where.partition(":")
    target = _import(module_name)
    if target is None:
        return [module_name]
    parts = path.split(".") if path else []
    owner_parts = parts[:-1] if use.how == ASSIGNED else parts
    for depth, part in enumerate(owner_parts):
        target = getattr(target, part, _ABSENT)
        if target is _ABSENT:
            return [f"{module_name}:{'.'.join(owner_parts[:depth + 1])}"]
    if use.how == ASSIGNED:
        return [] if _assigns(target, parts[-1]) else [use.where]
    if use.arguments is not None and not _takes(target, use.arguments):
        return [f"{use.where} (taking {use.arguments} arguments)"]
    have = (_field_names(target) if use.how == FIELDS else _key_names(target) if use.how == KEYS
            else {name for name in use.names if hasattr(target, name)})
    return [f"{use.where}{':' if not path else '.'}{name}" for name in use.names if name not in have]


_ABSENT = object()


def _import(module_name: str) -> Any:
    try:
        return importlib.import_module(module_name)
    except ImportError:
        return None


def _assigns(cls: Any, name: str) -> bool:
    """True when some function of ``cls`` or its bases assigns ``self.<name>`` (read from their bytecode)."""
    if not isinstance(cls, type):
        return False
    return any(_stores(code, name) for klass in cls.__mro__ for value in vars(klass).values()
               for code in _codes(value))


def _codes(value: Any) -> list[types.CodeType]:
    if isinstance(value, (staticmethod, classmethod)):
        value = value.__func__
    if isinstance(value, property):
        return [f.__code__ for f in (value.fget, value.fset) if f is not None and hasattr(f, "__code__")]
    value = getattr(value, "func", value)  # functools.cached_property
    code = getattr(value, "__code__", None)
    return [code] if isinstance(code, types.CodeType) else []


def _stores(code: types.CodeType, name: str) -> bool:
    if name in code.co_names and any(i.opname == "STORE_ATTR" and i.argval == name for i in dis.get_instructions(code)):
        return True
    return any(_stores(const, name) for const in code.co_consts if isinstance(const, types.CodeType))


def _takes(function: Any, count: int) -> bool:
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return False
    unbound = inspect.isfunction(function) and "." in function.__qualname__  # a method read off its class
    try:
        signature.bind(*[None] * (count + unbound))
    except TypeError:
        return False
    return True


def _field_names(cls: Any) -> set[str]:
    return {field.name for field in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set()


def _key_names(cls: Any) -> set[str]:
    return set(getattr(cls, "__required_keys__", ())) | set(getattr(cls, "__optional_keys__", ()))


# --------------------------------------------------------------- messages
class _Absent:
    """A message class this viser lacks: nothing is an instance of it (check() refuses to start)."""


#: viser's message classes, as ``messages.GuiUpdateMessage``; only those :data:`MESSAGE_NAMES` lists.
messages = types.SimpleNamespace(**{name: getattr(_import("viser._messages"), name, _Absent)
                                    for name in MESSAGE_NAMES})


# ---------------------------------------------------- websocket server (gate)
def serve_websockets_through(serve: Callable[..., Any]) -> None:
    """viser's infra module sees a ``websockets`` whose ``asyncio.server.serve`` is ``serve`` (once;
    every other name is websockets' own, and no other module sees a change)."""
    infra = importlib.import_module(INFRA)
    if isinstance(infra.websockets, _View):
        return
    real = infra.websockets
    server_view = _View(real.asyncio.server, {"serve": serve})
    asyncio_view = _View(real.asyncio, {"server": server_view})
    infra.websockets = _View(real, {"asyncio": asyncio_view})


class _View:
    """A module seen through ``overrides`` (every other attribute is the module's own)."""

    def __init__(self, module: Any, overrides: dict[str, Any]):
        self._module, self._overrides = module, overrides

    def __getattr__(self, name: str) -> Any:
        return self._overrides[name] if name in self._overrides else getattr(self._module, name)


def read_messages_through(consume: Callable[[Any, Callable[[Any], None], Any], Any]) -> None:
    """viser reads each connection's messages with ``consume(connection, handle, message_class)`` (a
    coroutine: it receives from the raw websockets ``connection``, and passes each message it accepts to
    ``handle``), process-wide, once."""
    infra = importlib.import_module(INFRA)
    if getattr(infra._message_consumer, "_ours", False):
        return
    consume._ours = True
    infra._message_consumer = consume


def on_connections(server: viser.ViserServer, connect: Callable, disconnect: Callable) -> None:
    """``connect(connection)`` / ``disconnect(connection)`` (async) for each websocket connection, before
    its first message is read (a ``connection`` has ``client_id`` and ``queue_message``)."""
    infra = server._websock_server
    infra.on_client_connect(connect)
    infra.on_client_disconnect(disconnect)


def raw_connection(server: viser.ViserServer, client_id: int) -> Any:
    """The websockets connection of ``client_id`` (its handshake's), or None."""
    return server._websock_server._live_connections.get(client_id)


def guard_messages(server: viser.ViserServer, admit: Callable[[int, Any], bool]) -> None:
    """The server acts on an incoming message only when ``admit(client_id, message)`` says so."""
    _guard(server._websock_server, admit)


def guard_connection_messages(connection: Any, admit: Callable[[int, Any], bool]) -> None:
    """The same for one connection's own handlers (its camera, its own controls)."""
    _guard(connection, admit)


def _guard(handler: Any, admit: Callable[[int, Any], bool]) -> None:
    dispatch = handler._handle_incoming_message

    async def guarded(client_id: int, message: Any) -> None:
        if admit(client_id, message):
            await dispatch(client_id, message)

    handler._handle_incoming_message = guarded


def send_to(client: viser.ClientHandle, message: Any) -> None:
    """``message`` to this page only, never into the backlog every new page replays."""
    client._websock_connection.queue_message(message)


# ---------------------------------------------------------- windows (pacing)
Pace = Callable[[AsyncGenerator, int, int], AsyncGenerator]


def pace_windows(server: viser.ViserServer, pace: Pace) -> None:
    """Each connection's windows of the shared scene pass through ``pace(windows, client_id, full)``, where
    ``full`` is the size at which viser cuts a window."""
    buffer = server._websock_server._broadcast_buffer
    generator = buffer.window_generator

    def window_generator(client_id: int, *args: Any, **kwargs: Any) -> AsyncGenerator:
        return pace(generator(client_id, *args, **kwargs), client_id, buffer.max_window_size)

    buffer.window_generator = window_generator


# ------------------------------------------------------- wake-ups (wakeups)
def give_message_buffers(make_event: Callable[[asyncio.AbstractEventLoop], asyncio.Event]) -> None:
    """Every message buffer viser builds from now on gets ``make_event(its event loop)`` as its
    ``message_event`` (once per process)."""
    cls = importlib.import_module(BUFFER).AsyncMessageBuffer
    if getattr(cls.__init__, "_events_from", None) is not None:
        return
    built = cls.__init__

    def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
        built(self, *args, **kwargs)
        self.message_event = make_event(self.event_loop)

    __init__._events_from = make_event
    cls.__init__ = __init__


def set_event_flag(event: asyncio.Event, value: bool) -> None:
    """Raise or lower ``event``'s flag without touching its waiters (asyncio has no public way)."""
    event._value = value


# ------------------------------------------------------------ icons (icons)
def icon_reader() -> Callable[[str], str] | None:
    """The function viser's GUI reads its icons with, or None when this viser has none."""
    module = _import("viser._gui_api")
    return getattr(module, "svg_from_icon", None)


def icon_archive() -> Path | None:
    """viser's archive of icons, or None when it is not where viser 1.1 keeps it."""
    icons = _import("viser._icons")
    path = Path(icons.ICONS_DIR) / "tabler-icons.zip" if hasattr(icons, "ICONS_DIR") else None
    return path if path is not None and path.is_file() else None


def read_icons_with(reader: Callable[[str], str]) -> bool:
    """viser reads its icons with ``reader`` from now on; False (and nothing changed) where it cannot."""
    modules = [_import(name) for name in ("viser._gui_api", "viser._gui_handles", "viser._icons")]
    if not all(hasattr(module, "svg_from_icon") for module in modules):
        return False
    for module in modules:
        module.svg_from_icon = reader
    return True


# ----------------------------------------------------------- GUI handles (inbox)
def handle_uuid(handle: Any) -> str:
    """The uuid a control or command is named by in messages."""
    return handle._impl.uuid


def is_removed(handle: Any) -> bool:
    return handle._impl.removed


def props(handle: Any) -> Any:
    """A control's or command's properties as the page was sent them (its label, disabled, visible,
    options, min, max...)."""
    return handle._impl.props


def input_handle(gui: viser.GuiApi, uuid: str) -> Any:
    """The control ``uuid`` of this GUI (the shared one, or a page's own), or None."""
    return gui._gui_input_handle_from_uuid.get(uuid)


def command_handle(gui: viser.GuiApi, uuid: str) -> Any:
    """The keyboard command ``uuid`` of this GUI, or None."""
    return gui._command_handle_from_uuid.get(uuid)


@dataclasses.dataclass(frozen=True)
class UploadEvent(viser.GuiEvent):
    """viser's event for an upload button, with the file this upload brought: the button's ``value`` is
    one for every page, and another page's upload may replace it before this event's callback runs."""

    file: viser.UploadedFile


def finish_upload(gui: viser.GuiApi, client: Any, component: str, file: viser.UploadedFile) -> None:
    """Hand a whole uploaded ``file`` (received by the inbox from ``client``) to the callbacks of the upload
    button ``component``, as viser would (plain ones on the GUI's thread pool, async ones on this event
    loop), but each with its own file (:class:`UploadEvent`); the button's shared value is left alone."""
    handle = input_handle(gui, component)
    if handle is None or is_removed(handle) or client is None:
        return
    event = UploadEvent(client, client.client_id, handle, file)
    for callback in list(handle._impl.update_cb):
        if inspect.iscoroutinefunction(callback):
            asyncio.get_running_loop().create_task(callback(event))
        else:
            gui._thread_executor.submit(callback, event).add_done_callback(_log_failure)


def _log_failure(done: Future) -> None:
    """What viser's thread pool says of a callback that raised (a stopped queue's skipped one is no failure)."""
    error = done.exception()
    if error is not None and not isinstance(error, QueueStopped):
        log.error("an upload's callback failed", exc_info=error)


# ------------------------------------------------------------ callbacks
class _Routed:
    """Stands where viser keeps its thread pool: each callback goes to ``submit``. Shutting it down (as
    the server's ``stop`` does) leaves ``submit`` alone, its owner's business, and shuts the pool it
    replaced (a page half-way through connecting may still have used it)."""

    def __init__(self, submit: Callable[..., Future], replaced: Any):
        self._submit, self._replaced = submit, replaced

    def submit(self, fn: Callable, *args: Any) -> Future:
        """``submit(fn, *args)``, except that a callback the stopping app will not run ends quietly:
        viser logs a failed callback as "Task failed with exception", and a page's last messages
        arrive while the app stops (each ``bench --live`` printed two such tracebacks)."""
        routed, answer = self._submit(fn, *args), Future()

        def settle(done: Future) -> None:
            error = done.exception()
            if error is None:
                answer.set_result(done.result())
            elif isinstance(error, QueueStopped):
                answer.set_result(None)
            else:
                answer.set_exception(error)

        routed.add_done_callback(settle)
        return answer

    def shutdown(self, *args: Any, **kwargs: Any) -> None:
        self._replaced.shutdown(wait=False)


def route_callbacks(server: viser.ViserServer, submit: Callable[..., Future]) -> None:
    """Every synchronous callback viser would run on its thread pool (GUI updates and clicks, commands,
    scene pointer and click events, camera updates, client connect and disconnect) runs through
    ``submit(fn, *args)`` instead, which returns a ``concurrent.futures.Future``. Pages connected already
    are routed too, and each new page's GUI and scene take the server's. Call it before pages connect
    (a page half-way through connecting keeps viser's pool)."""
    routed = _Routed(submit, server._thread_executor)
    server._thread_executor = routed
    for api in (server.gui, server.scene):
        api._thread_executor = routed
    for client in server.get_clients().values():
        client.gui._thread_executor = client.scene._thread_executor = routed
