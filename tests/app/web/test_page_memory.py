"""Pages that come and go leave no memory behind (issue 39, hole 8).

20 pages connecting and dropping, 5 rounds: the server grew about 6 MB a round with no plateau. The
departed connections' coroutines stayed in reference cycles (with the last window of messages each
had sent) until Python's next full collection, and glibc's malloc kept what was freed
(:mod:`sandbox.app.web.memory`). Here the app serves the paper's default world, as ``serve`` does, with
its simulation in its own process; the pages are raw websocket clients in a process of their own,
so that what is measured is the server.
"""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import pytest

from sandbox.model.config import Config
from tests.waiting import wait_until

ROOT = Path(__file__).resolve().parents[3]
PAGES, ROUNDS = 20, 5
#: Growth allowed after the first round (which pays once for what a page's arrival loads).
MOST_GROWTH_MB = 10.0

#: Pages in a process of their own: each line on stdin opens PAGES of them (each reads all it is
#: sent), the next line closes them all.
PAGES_PROCESS = """
import sys, threading
from tests.viser_wire import RawClient

port, count = int(sys.argv[1]), int(sys.argv[2])

def read_all(page):
    try:
        while True:
            page.ws.recv()
    except Exception:
        pass

for line in sys.stdin:
    pages = [RawClient(port, {"Origin": f"http://127.0.0.1:{port}"}) for _ in range(count)]
    for page in pages:
        threading.Thread(target=read_all, args=(page,), daemon=True).start()
        page.say_hello()
    print("opened", flush=True)
    sys.stdin.readline()
    for page in pages:
        page.close()
    print("closed", flush=True)
"""


def resident_mb() -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024


@pytest.mark.slow
@pytest.mark.skipif(sys.platform != "linux", reason="reads the resident size from /proc")
def test_twenty_pages_coming_and_going_five_times_leave_no_memory_behind():
    from sandbox.commands.serve import App, free_port

    app = App(Config(), port=free_port(), keep_running=True).start()
    pages = subprocess.Popen([sys.executable, "-c", PAGES_PROCESS, str(app.port), str(PAGES)], cwd=ROOT,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    sizes = []
    try:
        for _ in range(ROUNDS):
            pages.stdin.write("open\n")
            pages.stdin.flush()
            assert pages.stdout.readline().strip() == "opened"
            wait_until(lambda: len(app.server.get_clients()) == PAGES, what=f"{PAGES} pages to connect")
            drawn = app.frames_drawn
            wait_until(lambda: app.frames_drawn >= drawn + 10, what="10 frames sent to the pages")
            returned = app.memory.returns
            pages.stdin.write("close\n")
            pages.stdin.flush()
            assert pages.stdout.readline().strip() == "closed"
            wait_until(lambda: not app.server.get_clients(), what="the pages to be gone")
            wait_until(lambda: app.memory.returns > returned, what="the memory they used to be handed back")
            # The first page's arrival loads the drawing preview's compiled geometry, once, aside.
            wait_until(lambda: not any(t.name == "draw-preview-warm-up" for t in threading.enumerate()),
                       what="the drawing preview to be warmed up")
            sizes.append(resident_mb())
        growth = max(sizes[1:]) - sizes[0]
        assert growth < MOST_GROWTH_MB, f"resident size after each round (MB): {[round(s, 1) for s in sizes]}"
    finally:
        pages.stdin.close()
        pages.wait(30)
        app.stop()
