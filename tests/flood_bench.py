"""How floods treat the other pages: ``python -m tests.flood_bench [KIND ...]`` (issue 54, attack F).

Starts ``phototaxis serve`` (the default world, with a token, under a 3 GB memory cap) in a process of
its own, connects a paced page (:class:`tests.flooding.PacedPage`) and, for each kind of flood, prints
the page's frames a second and the server's memory (RSS) for 5 s before, during the flood (``SECONDS``
of it from ``CONNECTIONS`` connections at full speed) and 10 s after it ended, and what the flood sent.

Kinds: ``camera`` (watchers' cameras), ``camera-zero`` (cameras with ``image_height`` 0), ``control``
(watchers' refused control messages), ``mixed`` (cameras and refused controls), ``values`` (a page with
the token moving a slider), ``malformed``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from typing import Any

from sandbox.commands.serve import free_port
from tests.flooding import REPO, PacedPage, flood_result, rss, start_flood
from tests.viser_wire import RawClient
from tests.waiting import wait_until

TOKEN = "flood-bench-token"
KINDS = ("camera", "camera-zero", "control", "values", "malformed")  # (and "mixed", on request)


def start_server(port: int, log: Any) -> subprocess.Popen:
    """``phototaxis serve`` writing to ``log`` (a file: a pipe nobody reads would stop a server that logs
    much)."""
    args = ["prlimit", "--as=3000000000", "--", sys.executable, "-m", "sandbox", "serve", "--port", str(port),
            "--token", TOKEN, "--keep-running"]
    return subprocess.Popen(args, cwd=REPO, stdout=log, stderr=subprocess.STDOUT,
                            env={**os.environ, "PYTHONPATH": str(REPO)})


def wait_for_server(port: int, timeout: float = 120.0) -> None:
    def answers() -> bool:
        try:
            RawClient(port, {"Origin": f"http://127.0.0.1:{port}"}).close()
            return True
        except Exception:  # noqa: BLE001 - not listening yet
            return False

    wait_until(answers, timeout=timeout, what="the server to start", poll=0.3)


def slider_uuid(port: int, label: str = "Steps per frame") -> str:
    client = RawClient(port, {"Origin": f"http://127.0.0.1:{port}", "Authorization": f"token {TOKEN}"})
    client.say_hello()
    for message in client._messages(30.0):
        if message.get("type") == "GuiSliderMessage" and message["props"]["label"] == label:
            client.close()
            return message["uuid"]
    raise SystemExit(f"no slider {label!r}")


def sample(page: PacedPage, pid: int, seconds: float) -> tuple[float, float, int]:
    """Frames a second, the largest gap between frames and the largest RSS over ``seconds``."""
    start, peak = time.monotonic(), rss(pid)
    while time.monotonic() - start < seconds:
        time.sleep(0.1)
        peak = max(peak, rss(pid))
    end = time.monotonic()
    return page.rate(start, end), page.largest_gap(start, end), peak


def bench(kind: str, port: int, pid: int, page: PacedPage, connections: int, seconds: float) -> None:
    own = {"Origin": f"http://127.0.0.1:{port}"}
    headers = {**own, "Authorization": f"token {TOKEN}"} if kind == "values" else own
    uuid = slider_uuid(port) if kind == "values" else ""
    fps0, gap0, _ = sample(page, pid, 5.0)
    before = rss(pid)
    flooding = start_flood(port, kind, 1 if kind == "values" else connections, seconds, headers, uuid)
    fps1, gap1, peak = sample(page, pid, seconds)
    sent, closed = flood_result(flooding)
    fps2, gap2, _ = sample(page, pid, 10.0)
    after = rss(pid)
    print(f"{kind:12s} before {fps0:5.1f} fps (gap {gap0:.2f} s) | flood {fps1:5.1f} fps (gap {gap1:.2f} s) "
          f"| 10 s after {fps2:5.1f} fps (gap {gap2:.2f} s) | RSS {before / 1e6:.0f} MB, peak {peak / 1e6:.0f}, "
          f"after {after / 1e6:.0f} ({(after - before) / 1e6:+.0f}) | sent {sent} ({sent / seconds:.0f}/s), "
          f"closed {closed}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("kinds", nargs="*", default=list(KINDS), metavar="KIND",
                        help=f"floods to measure, of {', '.join(KINDS)} and mixed (default: all but mixed)")
    parser.add_argument("--connections", type=int, default=4)
    parser.add_argument("--seconds", type=float, default=5.0)
    options = parser.parse_args()
    unknown = [kind for kind in options.kinds if kind not in (*KINDS, "mixed")]
    if unknown:  # (argparse's choices refuse a list default with nargs="*" on Python 3.11)
        parser.error(f"no flood of {', '.join(map(repr, unknown))}: choose from {', '.join(KINDS)} or mixed")
    port, log = free_port(), tempfile.TemporaryFile()
    server = start_server(port, log)  # (prlimit execs the server: its pid is the server's)
    try:
        wait_for_server(port)
        page = PacedPage(port, {"Origin": f"http://127.0.0.1:{port}"})
        for kind in options.kinds:
            bench(kind, port, server.pid, page, options.connections, options.seconds)
        page.close()
    finally:
        server.terminate()
        try:
            server.wait(timeout=30)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()
        log.seek(0)
        text = log.read().decode(errors="replace")
        lines = text.splitlines()
        print(f"server log: {len(lines)} lines, {len(text)} bytes; tracebacks: {text.count('Traceback')}")
        for line in lines[:6]:
            print("  " + line[:200])

if __name__ == "__main__":
    main()
