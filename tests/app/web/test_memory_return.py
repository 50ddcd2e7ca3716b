"""Freed memory is handed back once a burst of departures is over (sandbox.app.web.memory), at unit level:
a fake clock's timers and a counting trim. The whole server's growth is test_page_memory's."""

from __future__ import annotations

from sandbox.app.web.memory import FreedMemoryReturn
from tests.inline_events import InlineEvents


def test_a_burst_of_departures_hands_memory_back_once_when_it_is_over():
    timers, trims = InlineEvents(), []
    returner = FreedMemoryReturn(timers.after, quiet=1.0, trim=lambda: trims.append(timers.now))
    for _ in range(20):  # a class closing its laptops, 0.1 s apart
        returner.page_left(object())
        timers.pass_time(0.1)
    assert returner.returns == 0 and trims == []  # each departure put the return off
    timers.pass_time(0.85)
    assert returner.returns == 0
    timers.pass_time(0.1)  # 1 s after the last departure
    assert returner.returns == 1 and trims == [timers.now]
    timers.pass_time(10.0)
    assert returner.returns == 1  # nothing left to do until the next departure
    returner.page_left(object())
    timers.pass_time(1.0)
    assert returner.returns == 2 and len(trims) == 2
