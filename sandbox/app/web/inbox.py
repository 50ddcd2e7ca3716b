"""Every message a page sends, checked before viser acts on it: :class:`Inbox`.
Runs on viser's event loop, as each message is read.

viser applies whatever a client sends: a ``GuiUpdateMessage`` may set any
attribute of a control's state (its value, but also ``disabled``, its
callbacks...), to a disabled or hidden control, with a value outside its
options or range. :meth:`Inbox.admit` lets a message through only when the
connection's grant allows it and, for a control, when it is a new value, in
range, for a control that is shown and enabled. Refusals are logged (at most
one line a second per connection, with a count:
:class:`sandbox.app.web.refusals.RefusalLog`) and a watching page is told once
that it only watches.

Uploads are handled here, not by viser: an upload starts only if its
announced size is within the limit, its parts are counted as they arrive and
the transfer is dropped the moment they pass it, one transfer per page at a
time, and the acknowledgements go to the uploading page alone (viser
broadcasts them into the backlog every new page replays). A whole file
reaches the button's callbacks in its own event, not through the button's
value, which every page shares.

Everything here runs on viser's event loop, the server's thread that reads every connection (the
checks, the uploads, a page leaving): no other thread touches the inbox, so it takes no lock.
"""

from __future__ import annotations

import asyncio
import logging
import math
import re
from dataclasses import dataclass, field
from typing import Any, Callable

from viser import (
    GuiButtonGroupHandle,
    GuiButtonHandle,
    GuiCheckboxHandle,
    GuiDropdownHandle,
    GuiNumberHandle,
    GuiSliderHandle,
    GuiTextHandle,
    GuiUploadButtonHandle,
    UploadedFile,
)

from sandbox.app.web import viser_seam
from sandbox.app.web.access import Grant
from sandbox.app.web.refusals import RefusalLog
from sandbox.app.web.viser_seam import messages

log = logging.getLogger("sandbox.app.web.inbox")

#: Largest file a page may upload: a polygon file (sandbox.shapes.formats.MAX_BYTES).
UPLOAD_LIMIT = 1_000_000
#: viser's client sends a file in parts of this size.
UPLOAD_PART = 512 * 1024
#: viser's client shows its own green "File uploaded successfully" once the last part is acknowledged,
#: even for a file the panel then refuses; the panel says what became of every upload itself, so that
#: notice is closed, after these many seconds (it appears a frame or more after the acknowledgement,
#: and closing a notice not yet shown does nothing: once soon, once more for a slow page).
UPLOAD_NOTICE_CLOSED_AFTER = (0.4, 1.5)
#: Longest text a text field takes.
TEXT_LIMIT = 4096

#: What a watching page may send: its own camera.
WATCH_MESSAGES = (messages.ViewerCameraMessage,)
#: Never taken from any page: a public share link would bypass the token, and forms are not used.
NEVER = (messages.ShareUrlRequest, messages.ShareUrlDisconnect, messages.GuiFormSubmitMessage,
         messages.GuiFormDirtyMessage)


_UPLOADS = (messages.FileTransferStartUpload, messages.FileTransferPart)


class Refused(Exception):
    """Why a message is not acted on (logged, not shown to the page unless it says so)."""


class BadValue(Refused):
    """A value a person could have typed (out of range, not an option): the page is told, and shown
    the value that stands."""


@dataclass
class _Transfer:
    client_id: int
    component: str
    filename: str
    mime_type: str
    size: int
    part_count: int
    parts: dict[int, bytes] = field(default_factory=dict)
    received: int = 0


class Inbox:
    """The checks of one server's incoming messages (see the module docstring), on its event loop."""

    def __init__(self, server: Any, gate: Any, *, upload_limit: int = UPLOAD_LIMIT):
        self.server, self.gate = server, gate
        self.upload_limit = int(upload_limit)
        self._transfers: dict[str, _Transfer] = {}
        self._refusals: dict[int, int] = {}
        self._refusal_log = RefusalLog(log)
        self._told_watching: set[int] = set()

    # ---------------------------------------------------------------- entry
    def admit(self, client_id: int, grant: Grant | None, message: Any) -> bool:
        """True when viser may act on ``message``; uploads are handled here (False). A seat's page
        (``serve --class``) reaches none of the shared handlers (the teacher's GUI and floor): its
        messages go to its own page's handlers only, checked there (:meth:`admit_local`)."""
        if isinstance(message, _UPLOADS):
            return self._admit_checked(client_id, grant, message, self._take_upload)
        if grant is not None and grant.seat:
            return False
        return self._admit_checked(client_id, grant, message)

    def _take_upload(self, client_id: int, grant: Grant | None, message: Any) -> bool:
        """An upload's part, from a page that may send it, kept here (viser never acts on one)."""
        self._check_sender(client_id, grant, message)
        self._upload(client_id, message)
        return False

    def _accept(self, client_id: int, grant: Grant | None, message: Any) -> bool:
        self._check(client_id, grant, message)
        return True

    def admit_local(self, client_id: int, grant: Grant | None, message: Any) -> bool:
        """The same message, on its way to the connection's own handlers (its camera, and the controls
        made for this page alone, such as its inspector's): checked as :meth:`admit` checks it, which
        has already counted it and told the page when it was refused."""
        if isinstance(message, _UPLOADS):
            return False
        if grant is not None and grant.seat:  # the shared dispatch did not check it: here it counts
            return self._admit_checked(client_id, grant, message)
        try:
            self._check(client_id, grant, message, quietly=True)
            return True
        except Refused:
            return False

    def _admit_checked(self, client_id: int, grant: Grant | None, message: Any,
                       take: Callable[[int, Grant | None, Any], bool] | None = None) -> bool:
        """``take`` (by default: check the message, then let viser act on it), and a refusal said once:
        a value not used is set back on the page, and every refusal is counted."""
        try:
            return (take or self._accept)(client_id, grant, message)
        except BadValue as why:
            text, handle = why.args
            self._tell(client_id, "Value not used", text)
            self._send(client_id, messages.GuiUpdateMessage(viser_seam.handle_uuid(handle), {"value": handle.value}))
            self._refused(client_id, message, text)
            return False
        except Refused as why:
            self._refused(client_id, message, str(why))
            return False

    def forget(self, client_id: int) -> None:
        """A page left: drop its upload and its counts."""
        self.forget_upload_of(client_id)
        self._refusals.pop(client_id, None)
        self._told_watching.discard(client_id)
        self._refusal_log.forget(client_id)

    # --------------------------------------------------------------- checks
    def _check_sender(self, client_id: int, grant: Grant | None, message: Any, quietly: bool = False) -> None:
        if grant is None:
            raise Refused("the connection has no grant")
        if isinstance(message, NEVER):
            raise Refused(f"{type(message).__name__} is never accepted")
        if not grant.acts and not isinstance(message, WATCH_MESSAGES):
            if not quietly:
                self._tell_watching(client_id)
            raise Refused("a watching page may not control the sandbox")

    def _check(self, client_id: int, grant: Grant | None, message: Any, quietly: bool = False) -> None:
        self._check_sender(client_id, grant, message, quietly)
        if isinstance(message, messages.GuiUpdateMessage):
            self._check_update(client_id, message)
        elif isinstance(message, messages.GuiButtonHoldMessage):
            self._control(client_id, message.uuid, GuiButtonHandle)
        elif isinstance(message, messages.CommandTriggerMessage):
            self._command(client_id, message.uuid)

    def _control(self, client_id: int, uuid: str, kind: type | tuple) -> Any:
        """The shown, enabled control ``uuid`` of the given kind, shared or this page's own, or Refused."""
        handle = self._handle(client_id, viser_seam.input_handle, uuid)
        if handle is None or viser_seam.is_removed(handle):
            raise Refused(f"no control {uuid!r}")
        if not isinstance(handle, kind):
            raise Refused(f"{_label(handle)} is a {type(handle).__name__}")
        props = viser_seam.props(handle)
        if getattr(props, "disabled", False):
            raise Refused(f"{_label(handle)} is disabled")
        if not getattr(props, "visible", True):
            raise Refused(f"{_label(handle)} is hidden")
        return handle

    def _command(self, client_id: int, uuid: str) -> Any:
        """The enabled keyboard command ``uuid`` (shared or this page's own), or Refused."""
        handle = self._handle(client_id, viser_seam.command_handle, uuid)
        if handle is None or viser_seam.is_removed(handle):
            raise Refused(f"no command {uuid!r}")
        props = viser_seam.props(handle)
        if props.disabled:
            raise Refused(f"command {props.label!r} is disabled")
        return handle

    def _handle(self, client_id: int, lookup: Callable[[Any, str], Any], uuid: str) -> Any:
        """The handle ``lookup(gui, uuid)`` finds in the shared GUI, else in the sending page's own GUI
        (a page cannot reach another page's), or None. A seat's page finds only its own."""
        handle = None if self._seated(client_id) else lookup(self.server.gui, uuid)
        if handle is None:
            client = self._client(client_id)
            handle = None if client is None else lookup(client.gui, uuid)
        return handle

    def _check_update(self, client_id: int, message: Any) -> None:
        updates = message.updates
        if not isinstance(updates, dict) or set(updates) != {"value"}:
            raise Refused(f"a page may change a control's value only, not {sorted(map(str, updates))}")
        handle = self._control(client_id, message.uuid, _VALUE_CHECKS)
        for kind, check in _VALUE_CHECKS_BY_KIND:
            if isinstance(handle, kind):
                problem = check(handle, updates["value"])
                if problem:
                    raise BadValue(f"{viser_seam.props(handle).label or 'value'}: {problem}", handle)
                return

    def _seated(self, client_id: int) -> bool:
        grant = self.gate.grant(client_id) if self.gate is not None else None
        return grant is not None and bool(grant.seat)

    # -------------------------------------------------------------- uploads
    def _upload(self, client_id: int, message: Any) -> None:
        if isinstance(message, messages.FileTransferStartUpload):
            self._start_upload(client_id, message)
        else:
            self._upload_part(client_id, message)

    def _start_upload(self, client_id: int, message: Any) -> None:
        self.forget_upload_of(client_id)  # one transfer per page: a new one replaces it
        size, parts = _whole(message.size_bytes), _whole(message.part_count)
        try:
            self._control(client_id, message.source_component_uuid, GuiUploadButtonHandle)
            if size is None or parts is None or size < 0 or parts != math.ceil(size / UPLOAD_PART):
                raise Refused(f"an upload of {message.size_bytes!r} bytes cannot come in {message.part_count!r} parts")
            if size > self.upload_limit:
                raise Refused(f"{_megabytes(size)} is larger than the {_megabytes(self.upload_limit)} limit")
        except Refused as why:
            self._end_upload_in_page(client_id, message, size=max(0, size or 0))
            self._tell(client_id, "File not uploaded", f"{_safe_name(message.filename)}: {why}.")
            raise
        transfer = _Transfer(client_id, message.source_component_uuid, str(message.filename)[:255],
                             str(message.mime_type)[:255], size, parts)
        self._transfers[message.transfer_uuid] = transfer
        if parts == 0:
            self._finish(message.transfer_uuid, transfer)

    def _upload_part(self, client_id: int, message: Any) -> None:
        content = bytes(message.content)
        transfer = self._transfers.get(message.transfer_uuid)
        if transfer is None or transfer.client_id != client_id:
            raise Refused("a part of no upload in progress")
        index = _whole(message.part_index)
        if index is None or index in transfer.parts or not 0 <= index < transfer.part_count:
            raise Refused(f"part {message.part_index!r} of {transfer.part_count} again or out of range")
        over = transfer.received + len(content) > transfer.size
        if over:  # drop the whole transfer: what it holds is freed now
            del self._transfers[message.transfer_uuid]
        else:
            transfer.parts[index] = content
            transfer.received += len(content)
        complete = not over and len(transfer.parts) == transfer.part_count
        if complete:
            del self._transfers[message.transfer_uuid]
        short = complete and transfer.received != transfer.size
        if over:
            self._tell(client_id, "File not uploaded", f"{_safe_name(transfer.filename)}: more bytes arrived "
                                                      f"than the {transfer.size} announced.")
            raise Refused("an upload sent more than it announced")
        if short:  # viser would drop it with a warning in the log and nothing on the page
            self._end_upload_in_page(client_id, message, size=transfer.size)
            self._tell(client_id, "File not uploaded", f"{_safe_name(transfer.filename)}: {transfer.received} "
                                                      f"bytes arrived of the {transfer.size} announced.")
            raise Refused("an upload sent less than it announced")
        self._send(client_id, messages.FileTransferPartAck(
            source_component_uuid=transfer.component, transfer_uuid=message.transfer_uuid,
            transferred_bytes=transfer.received, total_bytes=transfer.size))
        if complete:
            self._finish(message.transfer_uuid, transfer)

    def forget_upload_of(self, client_id: int) -> None:
        for uuid in [u for u, t in self._transfers.items() if t.client_id == client_id]:
            del self._transfers[uuid]

    def _finish(self, transfer_uuid: str, transfer: _Transfer) -> None:
        """Hand the whole file to the upload button's callbacks, in their event: the page that sent it
        is told of this file, whatever another page uploads meanwhile."""
        content = b"".join(transfer.parts[index] for index in range(transfer.part_count))
        client = self._client(transfer.client_id)
        gui = client.gui if client is not None and self._seated(transfer.client_id) else self.server.gui
        viser_seam.finish_upload(gui, client, transfer.component, UploadedFile(name=transfer.filename, content=content))
        close = messages.RemoveNotificationMessage(uuid=f"upload-{transfer_uuid}")
        for seconds in UPLOAD_NOTICE_CLOSED_AFTER:
            _later(seconds, self._send, transfer.client_id, close)

    def _end_upload_in_page(self, client_id: int, message: Any, size: int) -> None:
        """Close the page's own 'Uploading...' notice and free its button (viser's client waits for
        an acknowledgement of every byte)."""
        self._send(client_id, messages.FileTransferPartAck(
            source_component_uuid=message.source_component_uuid, transfer_uuid=message.transfer_uuid,
            transferred_bytes=size, total_bytes=size))
        self._send(client_id, messages.RemoveNotificationMessage(uuid=f"upload-{message.transfer_uuid}"))

    # ----------------------------------------------------------- telling
    def _client(self, client_id: int) -> Any:
        return self.server.get_clients().get(client_id)

    def _send(self, client_id: int, message: Any) -> None:
        client = self._client(client_id)
        if client is not None:
            viser_seam.send_to(client, message)  # this page only, never the backlog

    def _tell(self, client_id: int, title: str, body: str) -> None:
        client = self._client(client_id)
        if client is not None:
            client.add_notification(title, body, color="red", auto_close_seconds=10.0)

    def _tell_watching(self, client_id: int) -> None:
        if client_id in self._told_watching:
            return
        self._told_watching.add(client_id)
        client = self._client(client_id)
        if client is not None:
            client.add_notification("Watching only", "This page watches the sandbox. To control it, open the "
                                    "link with its token (the one printed when the server started).",
                                    color="yellow", auto_close_seconds=12.0)

    def _refused(self, client_id: int, message: Any, why: str) -> None:
        self._refusals[client_id] = self._refusals.get(client_id, 0) + 1
        self._refusal_log.refused(client_id, f"{type(message).__name__}: {why}")


# ------------------------------------------------------------------ values
def _label(handle: Any) -> str:
    return f"control {getattr(viser_seam.props(handle), 'label', None) or viser_seam.handle_uuid(handle)!r}"


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)


def _check_button(handle: Any, value: Any) -> str | None:
    return None if value is True else f"a click is True, not {value!r}"


def _check_checkbox(handle: Any, value: Any) -> str | None:
    return None if isinstance(value, bool) else f"{value!r} is not True or False"


def _check_choice(handle: Any, value: Any) -> str | None:
    options = viser_seam.props(handle).options
    return None if isinstance(value, str) and value in options else f"{str(value)[:40]!r} is not one of its options"


def _check_range(handle: Any, value: Any) -> str | None:
    number = _number(value)
    if number is None:
        return f"{str(value)[:40]!r} is not a finite number"
    props = viser_seam.props(handle)
    low, high = getattr(props, "min", None), getattr(props, "max", None)
    if (low is not None and number < low) or (high is not None and number > high):
        shown = "" if low is None else _plain(low), "" if high is None else _plain(high)
        return f"{_plain(number)} is outside the allowed range [{shown[0]}, {shown[1]}]"
    return None


def _plain(number: float) -> str:
    return str(int(number)) if float(number).is_integer() and abs(number) < 1e15 else f"{number:g}"


def _check_text(handle: Any, value: Any) -> str | None:
    if not isinstance(value, str):
        return f"{type(value).__name__} is not text"
    return None if len(value) <= TEXT_LIMIT else f"{len(value)} characters is more than {TEXT_LIMIT}"


_VALUE_CHECKS_BY_KIND = ((GuiButtonHandle, _check_button), (GuiCheckboxHandle, _check_checkbox),
                         (GuiDropdownHandle, _check_choice), (GuiButtonGroupHandle, _check_choice),
                         (GuiSliderHandle, _check_range), (GuiNumberHandle, _check_range),
                         (GuiTextHandle, _check_text))
#: The controls a page may set; any other kind is refused.
_VALUE_CHECKS = tuple(kind for kind, _ in _VALUE_CHECKS_BY_KIND)


def _whole(value: Any) -> int | None:
    return value if isinstance(value, int) and not isinstance(value, bool) else None


def _megabytes(n: int) -> str:
    return f"{n / 1_000_000:.1f} MB" if n >= 100_000 else f"{n} bytes"


def _safe_name(name: Any) -> str:
    """A file's name fit to show: no control characters (a NUL among them), at most 80 characters."""
    return re.sub(r"[\x00-\x1f\x7f\ud800-\udfff]", "?", str(name).replace("\n", " "))[:80] or "the file"


def _later(seconds: float, fn: Callable[..., None], *args: Any) -> None:
    """Run ``fn(*args)`` in ``seconds`` on the server's event loop, where messages are checked (no
    thread of its own); outside a loop (a test calling the inbox directly), at once."""
    try:
        asyncio.get_running_loop().call_later(seconds, fn, *args)
    except RuntimeError:
        fn(*args)
