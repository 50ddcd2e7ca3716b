"""``phototaxis serve`` stops cleanly whenever it is told to, start-up included (issue 39, hole 4).

A SIGTERM 2.5-4 s into start-up (while the app was being built) ended the process with -15 and left
its fork server and simulation process running, and the resource tracker warned of leaked
semaphores. Here real ``python -m sandbox serve`` processes are stopped at moments of their start-up
that the test sees for itself (the process taking SIGTERM, its fork server running, its simulation
process running, its address printed): each exits with 0, says "stopped", warns of nothing, and
every process it started is gone.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.waiting import wait_until

ROOT = Path(__file__).resolve().parent.parent
START_SECONDS = 180  # several servers start at once, on a loaded machine
pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="reads the process tree from /proc")


# ------------------------------------------------------------------ /proc
def _read(path: str) -> str | None:
    try:
        with open(path, "rb") as f:
            return f.read().decode(errors="replace")
    except OSError:
        return None


def children(pid: int) -> list[int]:
    found = []
    for tid in os.listdir(f"/proc/{pid}/task") if os.path.isdir(f"/proc/{pid}/task") else ():
        found += [int(c) for c in (_read(f"/proc/{pid}/task/{tid}/children") or "").split()]
    return found


def identity(pid: int) -> tuple[int, str] | None:
    """(pid, start time): a pid the kernel gives to a new process later is not taken for this one."""
    stat = _read(f"/proc/{pid}/stat")
    return None if stat is None else (pid, stat.rsplit(")", 1)[1].split()[19])


def running(process: tuple[int, str]) -> bool:
    """The process is there and not a zombie (an orphan's zombie waits for init, not for us)."""
    stat = _read(f"/proc/{process[0]}/stat")
    if stat is None:
        return False
    fields = stat.rsplit(")", 1)[1].split()
    return fields[19] == process[1] and fields[0] != "Z"


def catches(pid: int, number: int) -> bool:
    status = _read(f"/proc/{pid}/status") or ""
    caught = re.search(r"^SigCgt:\s*([0-9a-f]+)", status, re.M)
    return bool(caught) and bool(int(caught.group(1), 16) >> (number - 1) & 1)


def command_line(pid: int) -> str:
    return (_read(f"/proc/{pid}/cmdline") or "").replace("\0", " ")


# ---------------------------------------------------------------- servers
class Server:
    """``python -m sandbox serve --port 0`` in a session of its own, and every process it starts."""

    def __init__(self) -> None:
        guard = ["setpriv", "--pdeathsig", "TERM", "--"] if shutil.which("setpriv") else []
        self.proc = subprocess.Popen([*guard, sys.executable, "-m", "sandbox", "serve", "--port", "0"], cwd=ROOT,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     start_new_session=True)
        self.out: list[str] = []
        self.err: list[str] = []
        self.readers = [threading.Thread(target=lambda s=s, into=into: into.extend(s), daemon=True)
                        for s, into in ((self.proc.stdout, self.out), (self.proc.stderr, self.err))]
        for reader in self.readers:
            reader.start()
        #: Every process seen under it (pid, start time) -> what it runs (read again while it runs).
        self.started: dict[tuple[int, str], str] = {}

    def look(self) -> None:
        """Note the processes under it now (its fork server's children included)."""
        todo = [self.proc.pid]
        while todo:
            for pid in children(todo.pop()):
                process = identity(pid)
                if process is not None:
                    self.started[process] = command_line(pid)  # a fork shows its parent's until it execs
                todo.append(pid)

    def fork_server(self) -> tuple[int, str] | None:
        return next((p for p, line in self.started.items() if "multiprocessing.forkserver" in line), None)

    def simulation_running(self) -> bool:
        server = self.fork_server()
        return server is not None and any(identity(pid) for pid in children(server[0]))

    def left(self) -> list[str]:
        return [f"{pid}: {line[:100]}" for (pid, start), line in self.started.items() if running((pid, start))]

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(10)
        for process in self.started:
            if running(process):
                os.kill(process[0], signal.SIGKILL)


#: The moments of start-up a server is stopped at, each a condition the test sees.
MOMENTS = {
    "loading its modules": lambda s: catches(s.proc.pid, signal.SIGTERM),
    "its fork server started": lambda s: s.fork_server() is not None,
    "its simulation process started": Server.simulation_running,
    "serving": lambda s: any("running at" in line for line in s.out),
}
#: moment, signal, to the whole process group (a terminal's Ctrl+C) or the server alone
CASES = [(moment, signal.SIGTERM, False) for moment in MOMENTS] + [
    ("its simulation process started", signal.SIGINT, True), ("loading its modules", signal.SIGINT, True)]


@pytest.mark.slow
def test_serve_stopped_at_any_moment_of_its_start_up_stops_cleanly():
    """All cases at once: each server is signalled as soon as its moment comes."""
    servers = [Server() for _ in CASES]
    try:
        told = [False] * len(CASES)
        deadline = time.monotonic() + START_SECONDS
        while not all(s.proc.poll() is not None for s in servers):
            assert time.monotonic() < deadline, f"not all stopped: {[(c[0], s.out, s.err) for c, s in zip(CASES, servers)]}"
            for i, ((moment, number, group), server) in enumerate(zip(CASES, servers)):
                server.look()
                if not told[i] and server.proc.poll() is None and MOMENTS[moment](server):
                    (os.killpg if group else os.kill)(server.proc.pid, number)
                    told[i] = True
            time.sleep(0.01)
        assert all(told), [c for c, t in zip(CASES, told) if not t]
        for (moment, number, _), server in zip(CASES, servers):
            what = f"{signal.Signals(number).name} when {moment}"
            wait_until(lambda: not server.left(), timeout=20, what=f"the processes started to end ({what})")
            for reader in server.readers:
                reader.join(20)
            err = "".join(server.err)
            assert server.proc.returncode == 0, f"{what}: exit code {server.proc.returncode}; {err[-2000:]}"
            assert "stopped" in "".join(server.out), f"{what}: {server.out}"
            assert "leaked" not in err and "Traceback" not in err, f"{what}: {err[-2000:]}"
    finally:
        for server in servers:
            server.kill()


@pytest.mark.slow
def test_a_simulation_process_ends_when_its_app_is_killed(tmp_path):
    """An app killed outright (SIGKILL: nothing can tidy up) leaves no simulation process behind,
    even one not yet told to start. Its parent is the fork server, which stays as long as the child
    does: the child watches the app's process itself (the fork server is no sign of it)."""
    code = ("from sandbox.app.process import ProcessRunner; from sandbox.model.config import Config; import time; "
            "r = ProcessRunner(Config(robots=30, boxes=60), shape=None); print(r.process.pid, flush=True); "
            "time.sleep(600)")
    guard = ["setpriv", "--pdeathsig", "KILL", "--"] if shutil.which("setpriv") else []
    err = tmp_path / "stderr"  # (the killed app's resource tracker rightly warns of its leaked semaphores)
    app = subprocess.Popen([*guard, sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, text=True,
                           stderr=err.open("w"), start_new_session=True)
    simulation = None
    try:
        line = app.stdout.readline()  # once its first frame has come
        assert line.strip().isdigit(), err.read_text()[-2000:]
        simulation = identity(int(line))
        assert simulation is not None and running(simulation), line
        app.kill()
        app.wait(10)
        wait_until(lambda: not running(simulation), timeout=20, what="the orphaned simulation process to end")
    finally:
        if app.poll() is None:
            os.killpg(app.pid, signal.SIGKILL)
        if simulation is not None and running(simulation):
            os.kill(simulation[0], signal.SIGKILL)
