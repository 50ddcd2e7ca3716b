"""Floods over the network, as a hostile script sends them (issue 54, attack F), and a page that counts
the frames it gets meanwhile.

- :class:`PacedPage`: a raw websocket page that behaves as a browser's does: it says hello, and after
  each window of the scene it gets it reports a drawn frame at ``/__drawn/<token>`` (the address the
  page's script is given, :mod:`sandbox.app.web.pacing`), so the server paces it as it paces a browser. It
  keeps the time of every window that carries a frame (the scene's node updates).
- :func:`start_flood`: ``connections`` websocket connections, in a process of their own (so that the
  flood does not share this process's interpreter lock with the server under test), each sending one
  message (or a cycle of them) as fast as the socket takes them: the frames are built once and written
  straight to the socket, hundreds at a time, so the sender is never what limits the rate.

Run as a script it is the flood itself: ``python -m tests.flooding PORT KIND CONNECTIONS SECONDS
[HEADER=VALUE ...]`` prints one line (``sent N closed C``) when done.
"""

from __future__ import annotations

import http.client
import math
import select
import subprocess
import sys
import threading
import time
from pathlib import Path

import msgspec
from websockets.frames import OP_BINARY, Frame

from tests.viser_wire import RawClient, decode

REPO = Path(__file__).resolve().parents[1]

CAMERA = dict(type="ViewerCameraMessage", wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 10.0), fov=1.0,
              near=0.01, far=1000.0, image_height=600, image_width=800, look_at=(0.0, 0.0, 0.0),
              up_direction=(0.0, 0.0, 1.0))


def flood_messages(kind: str, uuid: str = "") -> list[dict]:
    """The messages a flood of ``kind`` cycles through (``uuid``: the control a value flood sets)."""
    if kind == "camera":  # a watcher's one message, turning (each a new camera)
        return [{**CAMERA, "position": (math.cos(a / 10), math.sin(a / 10), 10.0)} for a in range(63)]
    if kind == "camera-zero":  # image_height 0: the aspect's division by zero
        return [{**CAMERA, "image_height": 0, "image_width": 800 + a} for a in range(2)]
    if kind == "control":  # what a watcher may not send: each one refused
        return [{"type": "GuiUpdateMessage", "uuid": "some-control", "updates": {"value": a}} for a in range(2)]
    if kind == "mixed":  # a watcher's cameras and, between them, controls it may not touch
        return [m for pair in zip(flood_messages("camera"), flood_messages("control") * 32) for m in pair]
    if kind == "values":  # a page with the token moving a slider back and forth
        return [{"type": "GuiUpdateMessage", "uuid": uuid, "updates": {"value": 2 + a % 2}} for a in range(2)]
    if kind == "malformed":  # fields that are not the message's, of the wrong type, an unknown kind
        return [{**CAMERA, "fov": "wide"}, {"type": "GuiFormDirtyMessage", "uuid": "x", "extra": 1},
                {"type": "NoSuchMessage"}, {**CAMERA, "near": float("nan")}]
    raise ValueError(f"no flood of {kind!r}")


def client_frames(messages: list[dict]) -> bytes:
    """The messages as one run of masked websocket frames, as a client sends them."""
    return b"".join(Frame(OP_BINARY, msgspec.msgpack.encode(m)).serialize(mask=True, extensions=[])
                    for m in messages)


def flood(port: int, kind: str, connections: int, seconds: float, headers: dict[str, str],
          uuid: str = "", path: str = "/") -> tuple[int, int]:
    """Flood from this process: the messages written to the sockets in all (the server reads what its
    budgets allow; the rest waits in the sockets), and how many connections the server closed while
    the flood went on."""
    clients = [RawClient(port, headers, path=path) for _ in range(connections)]
    for client in clients:
        client.say_hello()
    messages = flood_messages(kind, uuid)
    run = client_frames(messages * max(1, 256 // len(messages)))
    per_run = len(messages) * max(1, 256 // len(messages))
    sent, closed = [0] * connections, [0] * connections
    end = time.monotonic() + seconds

    def send(index: int) -> None:
        sock = clients[index].ws.socket  # (blocking, and shared with the client's reader: no timeout set on it)
        while time.monotonic() < end:
            pending = memoryview(run)
            while pending and time.monotonic() < end:
                if not select.select([], [sock], [], 0.2)[1]:
                    continue  # the server reads no more now: keep pressing until the time is up
                try:
                    pending = pending[sock.send(pending):]
                except OSError:
                    closed[index] = 1
                    return
            if not pending:
                sent[index] += per_run

    threads = [threading.Thread(target=send, args=(i,), daemon=True) for i in range(connections)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for client in clients:
        try:
            client.ws.socket.close()
        except OSError:
            pass
    return sum(sent), sum(closed)


def start_flood(port: int, kind: str, connections: int, seconds: float, headers: dict[str, str],
                uuid: str = "", path: str = "/") -> subprocess.Popen:
    """:func:`flood` in a process of its own (``path``: the page's address, a student's seat);
    ``.communicate()`` gives its line."""
    args = [sys.executable, "-m", "tests.flooding", str(port), kind, str(connections), str(seconds)]
    args += [f"{name}={value}" for name, value in headers.items()]
    if uuid:
        args.append(f"uuid={uuid}")
    if path != "/":
        args.append(f"path={path}")
    return subprocess.Popen(args, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def flood_result(process: subprocess.Popen, timeout: float = 60.0) -> tuple[int, int]:
    """(messages written, connections the server closed) of a :func:`start_flood`."""
    out, err = process.communicate(timeout=timeout)
    words = out.split()
    if process.returncode != 0 or len(words) != 4:
        raise AssertionError(f"the flood failed: {out} {err}")
    return int(words[1]), int(words[3])


class PacedPage:
    """A page that reports each window it gets as drawn, and keeps the times of the frames it got."""

    def __init__(self, port: int, headers: dict[str, str]):
        self.port, self.headers = port, headers
        self.client = RawClient(port, headers)
        self.client.say_hello()
        self.frames: list[float] = []
        self.report_path: str | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="paced-page", daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        reports = http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)
        while not self._stop.is_set():
            try:
                raw = self.client.ws.recv(timeout=0.2)
            except TimeoutError:
                continue
            except Exception:  # noqa: BLE001 - the connection closed: the test is over
                return
            messages = decode(raw)
            if any(m.get("type") == "SceneNodeUpdateMessage" for m in messages):
                self.frames.append(time.monotonic())
            for m in messages:
                if m.get("type") == "RunJavascriptMessage" and "__phototaxisDrawn = \"" in m["source"]:
                    self.report_path = m["source"].split("__phototaxisDrawn = \"", 1)[1].split("\"", 1)[0]
            if self.report_path is not None:
                try:
                    reports.request("GET", self.report_path, headers={"Host": f"127.0.0.1:{self.port}",
                                                                      **self.headers})
                    reports.getresponse().read()
                except (OSError, http.client.HTTPException):
                    reports = http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)

    def rate(self, start: float, end: float) -> float:
        """Frames a second it got between ``start`` and ``end`` (monotonic times)."""
        return sum(1 for t in list(self.frames) if start <= t < end) / (end - start)

    def largest_gap(self, start: float, end: float) -> float:
        inside = [start] + [t for t in list(self.frames) if start < t < end] + [end]
        return max(b - a for a, b in zip(inside, inside[1:]))

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.client.close()


def rss(pid: int | str = "self") -> int:
    """Resident memory of a process (bytes)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS")


if __name__ == "__main__":
    port_, kind_, connections_, seconds_, *pairs = sys.argv[1:]
    options = dict(pair.split("=", 1) for pair in pairs)
    uuid_ = options.pop("uuid", "")
    path_ = options.pop("path", "/")
    total, shut = flood(int(port_), kind_, int(connections_), float(seconds_), options, uuid_, path_)
    print(f"sent {total} closed {shut}")
