"""The pool of world hosts (sandbox.app.world.pool): hosts up to the number asked, each world on the least
loaded; a world found again on the host that keeps it; a dead host replaced."""

from __future__ import annotations

import os
import signal
import threading

import pytest

from sandbox.app.world.hosted import HostedRunner
from sandbox.app.world.pool import HostPool, HostProcess, Slot
from tests.app.world.test_host import SMALL
from tests.waiting import wait_until


@pytest.fixture
def pool():
    pool = HostPool(hosts=2)
    yield pool
    pool.stop()


def test_worlds_go_to_the_least_loaded_host_up_to_the_number_of_hosts(pool):
    runners = [HostedRunner(SMALL, pool=pool, shape=None, key=f"w{i}") for i in range(3)]
    try:
        assert len(pool.hosts) == 2 and sorted(host.load for host in pool.hosts) == [1, 2]
        assert len({r.process.pid for r in runners}) == 2
        runners[2].stop()
        again = HostedRunner(SMALL, pool=pool, shape=None, key="w2")  # kept where it was
        assert again.process.pid == runners[2].process.pid and pool.worlds() == 3
        again.stop()
    finally:
        for r in runners:
            r.stop()


def test_a_dead_host_is_replaced(pool):
    first = HostedRunner(SMALL, pool=pool, shape=None)
    try:
        dead = first.process.pid
        first.stop()
        os.kill(dead, signal.SIGKILL)
        wait_until(lambda: all(host.dead for host in pool.hosts if host.process.pid == dead), what="the host to die")
        later = HostedRunner(SMALL, pool=pool, shape=None, key=first.key)  # its world went with its host
        assert later.process.pid != dead and later.latest.step < 100
        later.stop()
    finally:
        first.stop()


def test_a_message_sent_to_a_slot_that_left_reaches_no_other():
    """A reopen raced the frames of the world sent to the slot that had left: one became the new slot's
    first frame, before the controls it found (every message now says which visit it is for)."""
    host = HostProcess.__new__(HostProcess)  # its routing alone, no process
    host._lock, host.kept, host.dead = threading.Lock(), {"k"}, False
    host.slots = {"k": Slot(host, "k", visit=2)}
    host._hand("k", 1, "a frame sent to visit 1")
    host._hand("k", 2, "its own")
    host._hand(None, None, "the host's last words")
    slot = host.slots["k"]
    assert [slot.read(0), slot.read(0), slot.read(0)] == ["its own", "the host's last words", None]
