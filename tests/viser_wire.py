"""A raw websocket client that speaks viser's wire format, as an attacker's script would:
no browser, no page, any headers. Used by the attack tests."""

from __future__ import annotations

import time
import uuid
from typing import Any

import msgspec
import viser
import websockets.sync.client
import zstandard

SUBPROTOCOL = f"viser-v{viser.__version__}"
#: The bytes of one part of an upload (a page's file, sent in parts).
UPLOAD_PART = 512 * 1024


class RawClient:
    """Connect to ``ws://127.0.0.1:port/`` with the given headers; ``send`` messages as dicts."""

    def __init__(self, port: int, headers: dict[str, str] | None = None, host: str = "127.0.0.1", path: str = "/"):
        self.ws = websockets.sync.client.connect(f"ws://{host}:{port}{path}", additional_headers=headers or {},
                                                 subprotocols=[SUBPROTOCOL], origin=None, max_size=None,
                                                 open_timeout=10,
                                                 # Unbounded: a test that reads nothing for a while must not
                                                 # stall the reader, or close() waits 10 s for a close
                                                 # frame stuck behind unread frames.
                                                 max_queue=None)

    def send(self, message_type: str, **fields: Any) -> None:
        self.ws.send(msgspec.msgpack.encode({"type": message_type, **fields}))

    def say_hello(self) -> None:
        """The first camera message: viser counts a client as connected only after it."""
        self.send("ViewerCameraMessage", wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 10.0), fov=1.0,
                  near=0.01, far=1000.0, image_height=600, image_width=800, look_at=(0.0, 0.0, 0.0),
                  up_direction=(0.0, 0.0, 1.0))

    def click(self, uuid_: str) -> None:
        self.send("GuiUpdateMessage", uuid=uuid_, updates={"value": True})

    def set_value(self, uuid_: str, value: Any) -> None:
        self.send("GuiUpdateMessage", uuid=uuid_, updates={"value": value})

    def start_upload(self, component: str, size: int, parts: int, name: str = "shape.txt") -> str:
        transfer = str(uuid.uuid4())
        self.send("FileTransferStartUpload", source_component_uuid=component, transfer_uuid=transfer,
                  filename=name, mime_type="text/plain", part_count=parts, size_bytes=size)
        return transfer

    def upload_part(self, component: str, transfer: str, index: int, content: bytes) -> None:
        self.send("FileTransferPart", source_component_uuid=component, transfer_uuid=transfer, part_index=index,
                  content=content)

    def upload(self, component: str, name: str, content: bytes) -> None:
        """``content`` sent to the upload control ``component`` as a page sends a file: in parts of
        :data:`UPLOAD_PART` bytes."""
        parts = [content[i:i + UPLOAD_PART] for i in range(0, len(content), UPLOAD_PART)]
        transfer = self.start_upload(component, size=len(content), parts=len(parts), name=name)
        for index, part in enumerate(parts):
            self.upload_part(component, transfer, index, part)

    def _messages(self, seconds: float):
        """The messages the server sends within ``seconds``, as they come."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                raw = self.ws.recv(timeout=left)
            except TimeoutError:
                return
            yield from decode(raw)

    def received_types(self, seconds: float, until: frozenset[str] = frozenset()) -> list[str]:
        """The types of the messages the server sends within ``seconds``, or until every type in
        ``until`` has come (a wait on a condition; without ``until``, a window for what must not come)."""
        types: list[str] = []
        for message in self._messages(seconds):
            types.append(message.get("type", "?"))
            if until and until <= set(types):
                break
        return types

    def first(self, message_type: str, seconds: float) -> dict | None:
        """The first message of ``message_type`` the server sends within ``seconds``."""
        return next((m for m in self._messages(seconds) if m.get("type") == message_type), None)

    def close(self) -> None:
        self.ws.close()


def decode(raw: bytes) -> list[dict]:
    """A server frame: [8 bytes inner size][8 bytes compressed size][zstd msgpack][binary buffers]."""
    inner_size = int.from_bytes(raw[0:8], "little")
    compressed_size = int.from_bytes(raw[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(raw[16:16 + compressed_size], max_output_size=inner_size)
    return list(msgspec.msgpack.decode(inner)["messages"])
