"""The app's one event queue (sandbox/app/web/events.py): one thread, in order, timers on it too."""

from __future__ import annotations

import ast
import re
import threading
import time
from pathlib import Path

import pytest

from sandbox.app.web.events import EventQueue, QueueStopped
from tests.waiting import wait_until


@pytest.fixture
def events():
    q = EventQueue()
    yield q
    q.stop()


def hold(events: EventQueue) -> threading.Event:
    """Keep the event thread busy until the returned event is set."""
    release, busy = threading.Event(), threading.Event()

    def blocked() -> None:
        busy.set()
        release.wait(10)

    events.post(blocked)
    busy.wait(10)
    return release


def test_nothing_runs_before_open_then_everything_in_order(events):
    ran = []
    for i in range(5):
        events.post(ran.append, i)
    assert not events.serving and ran == []
    events.open()
    assert events.submit(lambda: list(ran)).result(10) == [0, 1, 2, 3, 4]


def test_every_event_runs_on_the_one_thread_and_never_two_at_once(events):
    events.open()
    threads, inside, overlaps = set(), [0], []

    def event() -> None:
        inside[0] += 1
        overlaps.append(inside[0] > 1)
        threads.add(threading.current_thread().name)
        inside[0] -= 1

    posters = [threading.Thread(target=lambda: [events.post(event) for _ in range(200)]) for _ in range(4)]
    for t in posters:
        t.start()
    for t in posters:
        t.join()
    events.submit(lambda: None).result(10)
    assert len(overlaps) == 800 and not any(overlaps)
    assert threads == {"phototaxis-events"}


def test_a_failing_event_is_kept_and_the_others_go_on(events):
    events.open()
    future = events.submit(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        future.result(10)
    assert events.submit(lambda: 42).result(10) == 42
    assert isinstance(events.errors[-1], ZeroDivisionError)


def test_only_the_newest_of_a_kind_runs_when_the_thread_is_behind(events):
    events.open()
    drawn = []
    release = hold(events)
    for frame in range(1, 6):
        events.post_latest("frame", drawn.append, frame)
    release.set()
    events.submit(lambda: None).result(10)
    assert drawn == [5]
    events.post_latest("frame", drawn.append, 6)  # and the next one runs again
    wait_until(lambda: drawn == [5, 6], timeout=10, what="the next frame")


def test_after_runs_once_when_due_and_cancel_drops_it(events):
    events.open()
    ran = []
    start = time.monotonic()
    events.after(0.05, lambda: ran.append(time.monotonic() - start))
    dropped = events.after(0.05, ran.append, "cancelled")
    dropped.cancel()
    wait_until(lambda: ran, timeout=10, what="the timer")
    assert ran[0] >= 0.05
    events.after(0.1, ran.append, "last").cancel()
    marker = events.after(0.15, ran.append, "marker")
    wait_until(lambda: "marker" in ran, timeout=10, what="the later timer")
    assert "cancelled" not in ran and "last" not in ran and len(ran) == 2 and not marker.cancelled


def test_every_repeats_on_the_event_thread_until_cancelled(events):
    events.open()
    ticks = []
    timer = events.every(0.02, lambda: ticks.append(threading.current_thread().name))
    wait_until(lambda: len(ticks) >= 3, timeout=10, what="three ticks")
    events.submit(timer.cancel).result(10)  # on the event thread: no tick can be running meanwhile
    count = len(ticks)
    marker = threading.Event()
    events.after(0.1, marker.set)  # five periods later
    assert marker.wait(10)
    assert len(ticks) == count and set(ticks) == {"phototaxis-events"}
    with pytest.raises(ValueError):
        events.every(0, lambda: None)


def test_a_timer_waits_behind_no_event_and_an_event_behind_no_timer(events):
    """Timers and events share the thread: a timer due while events keep coming still runs."""
    events.open()
    fired = threading.Event()
    events.after(0.05, fired.set)
    deadline = time.monotonic() + 5
    while not fired.is_set() and time.monotonic() < deadline:
        events.post(lambda: None)
    assert fired.wait(10)


def test_stop_fails_every_waiting_event_and_refuses_new_ones(events):
    events.open()
    release = hold(events)
    waiting = [events.submit(lambda: "late") for _ in range(3)]
    stopper = threading.Thread(target=events.stop)
    stopper.start()
    wait_until(lambda: events.stopping, timeout=10, what="the stop")
    release.set()
    stopper.join(10)
    for future in waiting:
        with pytest.raises(QueueStopped):
            future.result(10)
    with pytest.raises(QueueStopped):
        events.submit(lambda: None).result(10)
    assert not events.serving


def test_stop_of_a_queue_never_opened_fails_what_waits(events):
    future = events.submit(lambda: 1)
    events.stop()
    with pytest.raises(QueueStopped):
        future.result(10)


def test_call_from_an_event_runs_inline_instead_of_waiting_for_itself(events):
    events.open()
    assert events.call(lambda: events.call(lambda: "inner") + " outer") == "inner outer"


# ------------------------------------------------- who shares a lock (docs/code.md, "Threads")
#: The rooms whose classes the event thread owns: a lock there is for state another thread shares.
OWNED_BY_THE_EVENT_THREAD = ("panel", "view")
#: The room where viser's event loop meets the app's threads: a lock there says which threads share it too.
WHERE_THREADS_MEET = ("web", "world")
#: A lock's comment says it is shared, and by which thread: one of the Threads table's.
LOCK = re.compile(r"(threading\.)?R?Lock")
SHARED_BY = re.compile(r"\bshared\b.*\b(main thread|event thread|event loop|receiver|workers?|threads)\b",
                       re.IGNORECASE | re.DOTALL)


def locks_without_their_sharers(source: str) -> list[int]:
    """The lines of ``source`` whose statement makes a ``threading.Lock`` or ``RLock`` without a comment
    (on the statement's lines, or the comment lines just above it) saying which threads share it."""
    lines = source.splitlines()
    missing = []
    for statement in ast.walk(ast.parse(source)):
        if not isinstance(statement, (ast.Assign, ast.AnnAssign, ast.Expr)):
            continue
        if not any(isinstance(node, ast.Call) and LOCK.fullmatch(ast.unparse(node.func))
                   for node in ast.walk(statement)):
            continue
        first, last = statement.lineno - 1, statement.end_lineno - 1
        comment = " ".join(line.partition("#")[2] for line in lines[first:last + 1])
        while first > 0 and lines[first - 1].lstrip().startswith("#"):
            first -= 1
            comment = lines[first].lstrip()[1:] + " " + comment
        if not SHARED_BY.search(comment):
            missing.append(statement.lineno)
    return missing


def test_the_lock_check_finds_a_lock_without_its_sharers():
    assert locks_without_their_sharers("import threading\nlock = threading.Lock()\n") == [2]
    assert locks_without_their_sharers("lock = RLock()  # one at a time\n") == [1]
    assert locks_without_their_sharers("lock = threading.Lock()  # shared by the receiver and the event thread\n") == []
    assert locks_without_their_sharers("# Shared by the workers: one at a time.\nlock = threading.Lock()\n") == []


def locks_without_their_sharers_in(rooms: tuple[str, ...]) -> list[str]:
    """``path:line`` of each lock in these rooms of sandbox/app without a comment naming its sharers."""
    import sandbox.app

    app = Path(sandbox.app.__file__).parent
    return [f"{path.relative_to(app.parent.parent)}:{line}"
            for room in rooms for path in sorted((app / room).rglob("*.py"))
            for line in locks_without_their_sharers(path.read_text(encoding="utf-8"))]


def test_a_lock_in_a_room_the_event_thread_owns_says_which_threads_share_it():
    """No state the event thread owns needs a lock (sandbox/app/web/events.py): a lock in the panel or
    the view guards something another thread really shares, and says which (issue 55)."""
    missing = locks_without_their_sharers_in(OWNED_BY_THE_EVENT_THREAD)
    assert not missing, f"a lock without a comment saying which threads share it: {', '.join(missing)}"


def test_a_lock_in_web_says_which_threads_share_it():
    """web/ runs on viser's event loop, but for what the app's threads ask of it (a page's grant, the
    drawing rates, the queue itself): a lock there guards what another thread really shares, and says
    which; state the loop alone touches has none (the inbox, the refusal logs)."""
    missing = locks_without_their_sharers_in(WHERE_THREADS_MEET)
    assert not missing, f"a lock without a comment saying which threads share it: {', '.join(missing)}"


def test_the_tests_stand_in_has_the_queues_ways_in_with_the_same_arguments():
    """tests/inline_events.InlineEvents stands in for the queue where a test builds a folder without a
    server: a folder that works with it must work with the queue."""
    import inspect

    from tests.inline_events import InlineEvents

    for name in ("post", "post_latest", "submit", "call", "after", "every", "on_event_thread"):
        assert inspect.signature(getattr(InlineEvents, name)) == inspect.signature(getattr(EventQueue, name)), name
