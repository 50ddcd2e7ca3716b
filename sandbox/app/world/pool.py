"""The app's side of the world hosts (sandbox.app.world.host): host processes up to the number of cores,
each world placed on the least loaded, and each world's place in its host seen as a child process of its
own (a :class:`Slot`), so that a process runner drives it unchanged (sandbox.app.world.hosted).
Called from any thread of the app (opening a world: the event thread, a runner's receiving thread after a
crash); one receiving thread per host reads the host's messages and hands each to its world's slot.

A slot offers what :class:`~sandbox.app.world.child.ProcessRunner` uses of a
:class:`~sandbox.app.world.child.Child`: ``send``, ``read``, ``end`` and a ``process`` that is alive
while its host is (``pid`` and ``exitcode`` are the host's). Ending a slot never ends its host: it
leaves the world, which pauses; a slot opened later with the same key finds the world again while the
host keeps it (:data:`~sandbox.app.world.host.FREE_AFTER`). A host that dies ends all its slots at once;
each proxy then restarts its world, on a host of the pool (a new one replaces the dead).
"""

from __future__ import annotations

import itertools
import logging
import os
import queue
import threading
from typing import Any

from sandbox.app.world import faults
from sandbox.app.world.host import FREE_AFTER, Closed, Freed, Leave, Open, host_main
from sandbox.processes import simulation_context

log = logging.getLogger("sandbox.app.world.pool")


class HostProcess:
    """One host process, its two channels, the worlds it holds and its receiving thread."""

    def __init__(self, context: Any, free_after: float):
        self.orders = context.Queue()
        self.receive, send = context.Pipe(duplex=False)
        self.process = context.Process(target=host_main, name="phototaxis-host", daemon=True,
                                       args=(dict(free_after=free_after, faults=faults.from_environment()),
                                             self.orders, send))
        self.process.start()
        send.close()  # the host holds the sending end
        # shared by the threads that open and end slots (the event thread, the runners' receiving threads)
        # and this host's receiving thread
        self._lock = threading.Lock()
        self.slots: dict[str, Slot] = {}  # key -> the slot attached to it
        self.kept: set[str] = set()  # the keys of the worlds it holds, attached or not
        self.dead = False
        self._thread = threading.Thread(target=self._receive_loop, name="phototaxis-host-receiver", daemon=True)
        self._thread.start()

    @property
    def load(self) -> int:
        """How many worlds it holds."""
        return len(self.kept)

    def send(self, key: str | None, message: Any) -> bool:
        if self.dead:
            return False
        try:
            self.orders.put((key, message))
            return True
        except (OSError, ValueError, AssertionError):
            return False

    def attach(self, slot: "Slot", settings: dict) -> None:
        with self._lock:
            self.slots[slot.key] = slot
            self.kept.add(slot.key)
        self.send(slot.key, Open(settings, slot.visit))

    def detach(self, slot: "Slot") -> None:
        with self._lock:
            if self.slots.get(slot.key) is slot:
                del self.slots[slot.key]
        self.send(slot.key, Leave(slot.visit, slot.free))

    def _receive_loop(self) -> None:
        while True:
            try:
                key, visit, message = self.receive.recv()
            except (EOFError, OSError):
                break
            except Exception:  # noqa: BLE001 - one message that cannot be read must not end the host's worlds
                log.exception("a message from a world host could not be read")
                continue
            self._hand(key, visit, message)
        self._died()

    def _hand(self, key: str | None, visit: int | None, message: Any) -> None:
        """Hand a message to its world's slot: the slot of the visit it was sent to (one sent to a slot
        that has left is for nobody: a frame of the world it left must not be a new slot's first)."""
        with self._lock:
            if isinstance(message, Freed):
                self.kept.discard(key)
                return
            if isinstance(message, Closed):
                self.kept.discard(key)
            slots = list(self.slots.values()) if key is None else [self.slots.get(key)]
        for slot in slots:  # (key None: the host's last words, for all its worlds)
            if slot is None or (key is not None and slot.visit != visit):
                continue
            if isinstance(message, Closed):  # read as a child that ended (its last words came before)
                slot.closed = True
                slot.inbox.put(_WAKE)
            else:
                slot.inbox.put(message)

    def _died(self) -> None:
        """The host ended (killed, or stopped): every slot reads as a process that ended."""
        self.process.join(1.0)  # its pipe closes a moment before its exit code is known
        with self._lock:
            self.dead = True
            self.kept.clear()
            slots = list(self.slots.values())
        for slot in slots:  # whoever waits to read hears it at once, as a child's closed pipe says
            slot.inbox.put(_WAKE)

    def stop(self, timeout: float = 5.0) -> None:
        self.send(None, None)
        self.process.join(timeout)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(timeout)
        self._thread.join(timeout)
        for close in (self.receive.close, self.orders.close, self.orders.cancel_join_thread):
            try:
                close()
            except (OSError, ValueError):
                pass


#: Put in a slot's inbox when it is left, closed or its host died: a reader waiting on it returns at once.
_WAKE = object()


class SlotProcess:
    """A slot seen as a process: alive while its host is, its world was not closed and it was not left."""

    def __init__(self, slot: "Slot"):
        self._slot = slot

    @property
    def pid(self) -> int | None:
        return self._slot.host.process.pid

    @property
    def exitcode(self) -> int | None:
        return 1 if self._slot.closed else self._slot.host.process.exitcode

    def is_alive(self) -> bool:
        slot = self._slot
        return not (slot.closed or slot.left or slot.host.dead)

    def join(self, timeout: float | None = None) -> None:
        """Waits for nothing: a world ends with its host (or its slot is left, at once)."""

    def kill(self) -> None:
        """Kills nothing: the host's other worlds go on (the slot is left when it ends)."""


class Slot:
    """One world in a host, as a process runner sees a child (sandbox.app.world.child.Child)."""

    def __init__(self, host: HostProcess, key: str, visit: int):
        self.host, self.key, self.visit = host, key, visit
        self.inbox: queue.SimpleQueue = queue.SimpleQueue()
        self.closed = False
        self.left = False
        self.free = False  # left for good: the host frees the world at once
        self.process = SlotProcess(self)

    def send(self, message: Any) -> bool:
        """Send to the world; None: the proxy leaves (the world pauses). False when the host is gone."""
        if message is None:
            self.leave()
            return True
        return not self.left and self.host.send(self.key, message)

    def read(self, timeout: float) -> Any:
        """The next message within ``timeout`` seconds, or None (none came, or the slot was left)."""
        ended = self.left or self.closed or self.host.dead
        try:
            message = self.inbox.get(timeout=timeout) if timeout > 0 and not ended else self.inbox.get_nowait()
        except queue.Empty:
            return None
        return None if message is _WAKE else message

    def leave(self) -> None:
        if not self.left:
            self.left = True
            self.inbox.put(_WAKE)  # whoever waits to read hears it at once, as a child's closed pipe says
            self.host.detach(self)

    def end(self, kill: bool = False, timeout: float = 5.0) -> None:
        """Leave the world (never the host's end: ``kill`` and ``timeout`` are a child's)."""
        self.leave()


class HostPool:
    """Host processes up to ``hosts`` (the number of cores), each world placed on the least loaded."""

    def __init__(self, hosts: int | None = None, free_after: float = FREE_AFTER, context: Any = None):
        self.most_hosts = max(1, int(hosts or os.cpu_count() or 1))
        self.free_after = float(free_after)
        self._context = context or simulation_context()
        # shared by the threads that open worlds (the event thread, runners' receiving threads after a crash)
        self._lock = threading.Lock()
        self.hosts: list[HostProcess] = []
        self._visits = itertools.count(1)
        self._keys = itertools.count(1)
        self.stopped = False

    def new_key(self) -> str:
        return f"world-{next(self._keys)}-{os.urandom(4).hex()}"

    def open(self, key: str, settings: dict) -> Slot:
        """A slot on the world ``key``: the host that keeps it, else the least loaded (a new host while
        there are fewer than ``most_hosts`` and each holds a world)."""
        with self._lock:
            if self.stopped:
                raise RuntimeError("the pool of world hosts was stopped")
            self.hosts = [host for host in self.hosts if not host.dead]
            host = next((host for host in self.hosts if key in host.kept), None) or self._least_loaded()
            slot = Slot(host, key, next(self._visits))
        host.attach(slot, settings)
        return slot

    def _least_loaded(self) -> HostProcess:
        idle = [host for host in self.hosts if host.load == 0]
        if idle:
            return idle[0]
        if len(self.hosts) < self.most_hosts:
            self.hosts.append(HostProcess(self._context, self.free_after))
            return self.hosts[-1]
        return min(self.hosts, key=lambda host: host.load)

    def stop(self, timeout: float = 5.0) -> None:
        with self._lock:
            self.stopped = True
            hosts, self.hosts = self.hosts, []
        for host in hosts:
            host.stop(timeout)

    def worlds(self) -> int:
        return sum(host.load for host in self.hosts if not host.dead)
