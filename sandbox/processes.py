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

import multiprocessing
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
