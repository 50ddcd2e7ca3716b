"""How a simulation gets a process of its own: the live app's simulation, the world it is compared
with, a challenge's reference run, advice and sweep workers.

Where the operating system offers it (Linux, macOS), a fork server: started once per program with a
fresh interpreter, it imports the model and loads numba's compiled kernels (:mod:`sandbox.warm`),
then forks each new simulation process from itself. A child so started skips what a fresh
interpreter pays again every time: measured 0.80 s of imports and kernel loading against 0.05 s
to build the paper's world. The fork server is single-threaded and holds no world, no sockets and
no pymunk space, so a fork of it inherits nothing a simulation could trip on. Elsewhere (Windows),
every process is a fresh interpreter (spawn), as before.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
from multiprocessing import forkserver
from multiprocessing.context import BaseContext

#: What the fork server imports before it forks anything (see sandbox/warm.py).
PRELOAD = ["sandbox.warm"]


def simulation_context() -> BaseContext:
    """The multiprocessing context to start simulation processes and pools with."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)  # read when the fork server starts, with the first child
        return context
    return multiprocessing.get_context("spawn")


def start_fork_server() -> None:
    """Start this program's fork server now and wait until it has loaded the model, which the first
    simulation process would otherwise wait for (1-3 s): for a program that wants the wait where it
    chooses. ``serve`` waits here where a stop may interrupt it: a simulation process interrupted while
    it is being started would be left to start alone, and the semaphores of its queues, gone with the
    program, make it fail with a traceback; the process started here to wait on has none."""
    context = simulation_context()
    if context.get_start_method() != "forkserver":
        return
    process = context.Process(target=_nothing, name="phototaxis-fork-server-ready")
    process.start()  # returns once the fork server, the model loaded, has forked it
    process.join()


def _nothing() -> None:
    """What the process that waits for the fork server runs."""


def stop_fork_server() -> None:
    """End this program's fork server, if it started one, and reap it: for a program that stops.

    Left alone, it ends once every process holding its "alive" pipe has (this one and the forks it
    made), but only after it has loaded the model if it was still doing so (seconds on a busy
    machine): a server stopped during its start-up left it running that long, with the resource
    tracker waiting for it. A later simulation process would start a new one.
    """
    server = forkserver._forkserver  # the stdlib's own, private: the only handle on its process id
    pid = getattr(server, "_forkserver_pid", None)
    if pid is None:
        return
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGTERM)
    server._stop()  # closes the alive pipe and reaps it
