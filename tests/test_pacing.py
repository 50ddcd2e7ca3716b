"""Each page gets the shared scene no faster than it draws it (sandbox.app.pacing, issue 24 item 2),
and the address a page reports at is behind the gate like the page itself."""

from __future__ import annotations

import re

from sandbox.app.pacing import CALM, MOST_WAIT, PATH
from tests.test_security import app, connected, http_status, own_page, shared_app  # noqa: F401 - fixtures
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
