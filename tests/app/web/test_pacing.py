"""Each page gets the shared scene no faster than it draws it (sandbox.app.web.pacing, issue 24 item 2),
and the address a page reports at is behind the gate like the page itself."""

from __future__ import annotations

import re
import time

import pytest

from sandbox.app.web.pacing import CALM, MOST_WAIT, PATH, Pacer, drawing_rate, frames_per_snapshot
from tests.app.web.test_security import app, connected, http_status, own_page, shared_app  # noqa: F401 - fixtures
from tests.viser_wire import RawClient
from tests.waiting import wait_until


def page_with_token(app) -> tuple[RawClient, int, str]:
    """A page of this machine that connected, its client id, and the token its script reports under."""
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    script = client.first("RunJavascriptMessage", 30.0)
    assert script is not None, "the page got no reporting script"
    token = re.search(re.escape(PATH) + r"([A-Za-z0-9_-]+)", script["source"]).group(1)
    return client, cid, token


def report(app, token: str, host: str | None = None) -> int:
    return http_status(app.port, host or f"127.0.0.1:{app.port}", PATH + token).status


def test_a_page_reports_drawn_frames_under_its_own_token_only(app):
    client, cid, token = page_with_token(app)
    pacer = app.gate.pacer
    assert cid not in pacer.paced  # not paced before it reports
    assert report(app, token) == 204 and pacer.reports[cid] == 1 and cid in pacer.paced
    assert report(app, "not-a-token") == 404
    for bad in ("", "../" + token, token + "/x", token[:-1], "%00", "x" * 4000):  # nothing but the token itself
        assert report(app, bad) in (404, 414), bad
    assert report(app, token, host=f"rebind.evil.example:{app.port}") == 403  # the gate's checks come first
    assert pacer.reports[cid] == 1
    client.close()
    wait_until(lambda: cid not in app.server.get_clients(), what="the page to leave")
    wait_until(lambda: report(app, token) == 404, what="its token to be forgotten")


def test_a_paced_page_is_held_after_each_window_until_it_draws_or_the_wait_runs_out(monkeypatch):
    """What the next test (slow) measures through a server, on the pacer alone: a page that reports drawn
    frames gets its next window once it has drawn the last, or after MOST_WAIT; a full window's rest, a
    page that never reported and a page that keeps up again wait for nothing. Told apart by turns of the
    event loop, not by the clock: a window that waits for nothing comes within a few."""
    import asyncio

    from sandbox.app.web import pacing

    pacer = Pacer()
    token = pacer.script_for(1).split(PATH)[1].split('"')[0]

    async def windows():
        for k in range(100):
            yield ["message"] * (4 if k == 5 else 1)  # viser cuts a window at 4 messages here: the sixth is full

    async def run() -> None:
        held = pacer.hold_windows(windows(), 1, full=4)

        async def next_window(report=None) -> bool:
            """Whether the next window came at once; ``report``, made if it did not, must then let it go."""
            task = asyncio.ensure_future(held.__anext__())
            for _ in range(5):
                await asyncio.sleep(0)
            at_once = task.done()
            if not at_once and report is not None:
                report()
                for _ in range(5):
                    await asyncio.sleep(0)
                assert task.done(), "the report did not let the window go"
            await asyncio.wait_for(task, 10)
            return at_once

        monkeypatch.setattr(pacing, "MOST_WAIT", 30.0)
        assert all([await next_window() for _ in range(4)])  # not paced (no report yet): no wait
        assert pacer.drawn(token) and 1 in pacer.paced
        assert await next_window()  # the report came after the last window: the next goes at once
        assert not await next_window(report=lambda: pacer.drawn(token))  # held until the page draws it
        assert await next_window()  # that one was full: its rest follows at once
        monkeypatch.setattr(pacing, "MOST_WAIT", 0.05)
        assert not await next_window()  # no report: the next after MOST_WAIT
        pacer.drawn(token + CALM)  # it keeps up again
        monkeypatch.setattr(pacing, "MOST_WAIT", 30.0)
        assert all([await next_window() for _ in range(3)])
        assert pacer.windows[1] == 11
        await held.aclose()

    asyncio.run(run())


@pytest.mark.slow  # 60 frames of a server on the clock; the test above decides it on the pacer alone
def test_a_paced_page_gets_a_window_per_drawn_frame_and_while_silent_one_a_second(app):
    pacer = app.gate.pacer
    paced, cid, token = page_with_token(app)
    silent = RawClient(app.port, own_page(app))  # a client that runs no script: never paced
    other = connected(app, silent)
    assert report(app, token) == 204
    wait_until(lambda: pacer.windows[cid] > 0 and pacer.windows[other] > 0, what="windows for both")
    frames, mine, theirs = app.frames_drawn, pacer.windows[cid], pacer.windows[other]
    wait_until(lambda: app.frames_drawn >= frames + 60, timeout=120, what="60 frames")  # 2 s at 30 frames/s
    seconds = (app.frames_drawn - frames) / 30
    got, unpaced = pacer.windows[cid] - mine, pacer.windows[other] - theirs
    # Without reports: the window it was waiting with, then one each MOST_WAIT (and one of slack).
    assert got <= 2 + seconds / MOST_WAIT + 1, (got, unpaced, seconds)
    assert unpaced >= got + 10, (got, unpaced)
    # Each report lets one more window go.
    before = pacer.windows[cid]
    for _ in range(5):
        sent = pacer.windows[cid]
        assert report(app, token) == 204
        wait_until(lambda: pacer.windows[cid] > sent, what="the next window after a report")
    assert pacer.windows[cid] - before >= 5
    # A page that keeps up again says so once, and is sent everything without reporting.
    assert report(app, token + CALM) == 204 and cid not in pacer.paced
    calm, theirs = pacer.windows[cid], pacer.windows[other]
    wait_until(lambda: pacer.windows[other] >= theirs + 20, timeout=120, what="20 more windows to the unpaced")
    assert pacer.windows[cid] - calm >= 10, (pacer.windows[cid] - calm, pacer.windows[other] - theirs)
    paced.close()
    silent.close()


def test_a_watching_page_on_a_shared_server_is_paced_too(shared_app):
    # Without the token a page only watches (test_security), but it draws like any page: its reports count.
    watcher, wid, token = page_with_token(shared_app)
    assert shared_app.gate.grant(wid).controls is False
    assert report(shared_app, token) == 204 and wid in shared_app.gate.pacer.paced
    watcher.close()


# ---------------------------------------------------------------- snapshots as often as pages draw
def test_the_worlds_snapshot_rate_follows_the_fastest_page():
    # fps 30; the fastest page's rate x 1.5, at least 10 a second: every floor(30 / that) frames
    assert frames_per_snapshot(30, [7.0]) == 2  # 10.5 wanted: 15 a second
    assert frames_per_snapshot(30, [7.0, 3.0]) == 2  # the fastest page counts
    assert frames_per_snapshot(30, [10.0]) == 2  # 15 wanted: 15 a second
    assert frames_per_snapshot(30, [11.0]) == 1  # 16.5 wanted: every frame
    assert frames_per_snapshot(30, [4.0]) == 3  # 6 wanted, 10 at least: 10 a second
    assert frames_per_snapshot(30, [0.5]) == 3
    assert frames_per_snapshot(30, [7.0, None]) == 1  # a page that keeps up (or has not said) sees them all
    assert frames_per_snapshot(30, []) == 1  # nobody looking: as before
    assert frames_per_snapshot(60, [7.0]) == 5  # 60 / 10.5


def test_the_snapshot_rate_may_be_held_to_at_most_some_frames_a_second():
    # a class's teacher's world: at most 5 snapshots a second, however fast its pages draw
    assert frames_per_snapshot(30, [None], most=5.0) == 6  # a page that keeps up: 5 a second, not 30
    assert frames_per_snapshot(30, [7.0], most=5.0) == 6  # 15 a second wanted: 5
    assert frames_per_snapshot(30, [0.5], most=5.0) == 6  # 10 a second at least, but 5 at most
    assert frames_per_snapshot(30, [0.5], most=20.0) == 3  # a bound above what the pages need changes nothing
    assert frames_per_snapshot(25, [], most=10.0) == 3  # 25 / 10 = 2.5: 8.3 a second, never above 10
    assert frames_per_snapshot(30, [], most=10.0) == 3  # exactly 10 a second


def test_the_pacer_reads_the_rates_of_the_pages_named_only():
    # a class's students draw worlds of their own: only the teacher's pages pace the teacher's world
    pacer = Pacer()
    tokens = [pacer.script_for(cid).split(PATH)[1].split('"')[0] for cid in (1, 2)]
    now = 100.0
    for k in range(8):  # page 1 (the teacher's) draws 7 frames a second
        assert pacer.drawn(tokens[0], now=now - 1.0 + k / 7)
    assert pacer.drawn(tokens[1] + CALM, now=now)  # page 2 (a student's) keeps up
    assert frames_per_snapshot(30, pacer.drawing_rates(now)) == 1  # every page's: every frame
    assert pacer.drawing_rates(now, pages=[1]) == [pytest.approx(7.0)]
    assert frames_per_snapshot(30, pacer.drawing_rates(now, pages=[1])) == 2  # the teacher's: 15 a second
    assert pacer.drawing_rates(now, pages=[]) == []


def test_a_pages_drawing_rate_from_its_reports():
    assert drawing_rate([10.0, 10.1, 10.2, 10.3, 10.4], now=10.4) == pytest.approx(10.0)  # 4 gaps in 0.4 s
    assert drawing_rate([5.0, 10.0, 10.25, 10.5], now=10.5) == pytest.approx(4.0)  # the one at 5 s is old
    assert drawing_rate([10.0, 10.1], now=10.1) is None  # too few to say
    assert drawing_rate([1.0, 1.1, 1.2], now=10.0) is None  # it stopped reporting (a hidden tab)


def test_the_pacer_reads_each_pages_rate_and_a_calm_page_keeps_every_frame():
    pacer = Pacer()
    tokens = [pacer.script_for(cid).split(PATH)[1].split('"')[0] for cid in (1, 2)]
    now = 100.0
    for k in range(8):  # page 1 draws 7 frames a second
        assert pacer.drawn(tokens[0], now=now - 1.0 + k / 7)
    assert pacer.drawing_rates(now) == [pytest.approx(7.0)]  # page 2 has not said how it draws: not counted
    assert pacer.drawn(tokens[1] + CALM, now=now)  # it keeps up (its first second)
    assert sorted(pacer.drawing_rates(now), key=lambda r: r is None) == [pytest.approx(7.0), None]
    pacer.forget(2)
    assert pacer.drawing_rates(now) == [pytest.approx(7.0)]
    pacer.drawn(tokens[0] + CALM, now=now)  # page 1 keeps up again
    assert pacer.drawing_rates(now) == [None]


def test_the_app_takes_fewer_snapshots_while_its_only_page_draws_slowly(app):
    paced, cid, token = page_with_token(app)
    silent = RawClient(app.port, own_page(app))  # runs no script, draws nothing: not counted
    connected(app, silent)
    pacer = app.gate.pacer
    now = time.monotonic()
    for k in range(8):  # 7 frames a second over the last second
        assert pacer.drawn(token, now=now - 1.0 + k / 7)
    app.events.call(app._pace_snapshots)
    assert app.lockstep.shown_every == 2 and app.runner.controls.show_every == 2
    assert report(app, token + CALM) == 204  # it keeps up again: every frame
    app.events.call(app._pace_snapshots)
    assert app.lockstep.shown_every == 1 and app.runner.controls.show_every == 1
    paced.close()
    silent.close()
