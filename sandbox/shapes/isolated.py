"""A polygon file read in a process of its own, under a time and a memory limit.

The web server reads the files its pages upload. Read in the server, a file
that is slow to parse holds the interpreter every page's scene is sent from,
and what the parser allocates stays with the server: before the SVG reader
counted its work first, a 780 KB SVG of arcs stalled every viewer's scene
for 5.9 s and grew the server from 78 to 364 MB. A child forked from the
fork server of :mod:`sandbox.processes` reads it instead: the server only
waits on a pipe, the child may use :data:`MEMORY_LIMIT` more bytes and
:data:`TIME_LIMIT` seconds, and whatever it allocated goes with it.
"""

from __future__ import annotations

import logging
import os
import sys
import threading

import numpy as np

from sandbox.shapes.errors import ShapeError, fail
from sandbox.shapes.formats import read_polygon_bytes

#: Seconds a file may take to be read: a polygon of 10,000 vertices takes well under one.
TIME_LIMIT = 5.0
#: Bytes the reading process may allocate beyond what it starts with.
MEMORY_LIMIT = 512 * 1024 * 1024
#: The exit code of a reader that ran out of memory with no memory left to say so.
OUT_OF_MEMORY = 3
#: Files read at once; more wait their turn (each reader is a process on the server's cores).
READERS_AT_ONCE = 2

_readers = threading.BoundedSemaphore(READERS_AT_ONCE)
log = logging.getLogger("sandbox.shapes.isolated")


def read_polygon_isolated(data: bytes, name: str, *, time_limit: float = TIME_LIMIT,
                          memory_limit: int = MEMORY_LIMIT) -> np.ndarray:
    """:func:`~sandbox.shapes.formats.read_polygon_bytes` in a child process: the vertices, or a
    :class:`ShapeError` for a file that is refused, too slow or too large to read."""
    from sandbox.processes import simulation_context  # multiprocessing only where a file is read

    context = simulation_context()
    receiving, sending = context.Pipe(duplex=False)
    with _readers:
        reader = context.Process(target=_read_in_child, args=(sending, data, name, memory_limit),
                                 name="phototaxis-shape-reader", daemon=True)
        try:
            reader.start()
        except (OSError, RuntimeError) as error:  # no process to be had: the counted checks still bound the work
            log.warning("reading %s in this process: no reader process (%s)", name, error)
            receiving.close()
            sending.close()
            return read_polygon_bytes(data, name)
        sending.close()  # the child's end: with it closed here, a child that dies ends the wait
        try:
            if not receiving.poll(time_limit):
                raise fail(name, f"took more than {time_limit:g} s to read; a polygon file is read in "
                           "well under a second (simplify the outline)")
            kind, value = receiving.recv()
        except EOFError:
            reader.join(1.0)
            raise _stopped(name, reader.exitcode, memory_limit) from None
        finally:
            receiving.close()
            if reader.is_alive():
                reader.kill()
            reader.join()
    if kind == "vertices":
        return value
    raise ShapeError(value)


def _read_in_child(sending, data: bytes, name: str, memory_limit: int) -> None:
    """The child: limit its memory, read the file, send ("vertices", array) or ("refused", message).

    A file that used up the memory allowed may leave too little to send even the refusal (its pickle, the
    traceback of a failed send): then the child ends with :data:`OUT_OF_MEMORY`, which needs no memory, and
    the server says the same refusal."""
    too_large = ("refused", str(_too_large(name, memory_limit)))  # made before the limit
    _limit_memory(memory_limit)
    try:
        answer = ("vertices", read_polygon_bytes(data, name))
    except ShapeError as error:
        answer = ("refused", str(error))
    except MemoryError:
        answer = too_large
    except Exception as error:  # the file's fault too: nothing else runs in this process
        if "bad_alloc" in str(error):  # GEOS says it in C++
            answer = too_large
        else:
            answer = ("refused", str(fail(name, f"could not be read ({type(error).__name__}: "
                                               f"{str(error)[:60] or 'no details'})")))
    try:
        sending.send(answer)
        sending.close()
    except MemoryError:
        os._exit(OUT_OF_MEMORY)


def _too_large(name: str, memory_limit: int) -> ShapeError:
    return fail(name, f"needs more than {memory_limit // 2**20} MB to read")


def _stopped(name: str, exitcode: int | None, memory_limit: int) -> ShapeError:
    """What the server says of a reader that ended without an answer."""
    if exitcode == OUT_OF_MEMORY:
        return _too_large(name, memory_limit)
    return fail(name, f"could not be read (the reader stopped with exit code {exitcode})")


def _limit_memory(memory_limit: int) -> None:
    """Address space for what the child has mapped already and ``memory_limit`` bytes more."""
    try:
        import resource
    except ImportError:  # Windows: no limit
        return
    if not sys.platform.startswith("linux"):
        return  # macOS does not enforce RLIMIT_AS
    with open("/proc/self/statm") as statm:
        mapped = int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    limit = mapped + memory_limit
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
