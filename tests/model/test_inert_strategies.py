"""Issue 56, item 8: a strategy that does nothing on the outline the band follows (flare, switch and no
corners on the offset outline) is greyed out in the panel, with a hint that says why, and comes back when
the outline does. Greyed out, it is disabled for the server: a page that sends a tick anyway, over a raw
websocket as a script would, is refused, and the strategy stays off."""

from __future__ import annotations

import pytest

from tests.app.web.test_security import SMALL, connected, own_page, refusals, uuid_of
from tests.viser_wire import RawClient
from tests.waiting import frames_pass, wait_until


def test_the_model_says_which_strategies_do_nothing_on_each_outline():
    from sandbox.model.notes import inert_note, inert_strategies

    assert sorted(inert_strategies("offset")) == ["flare", "no_corners", "switch"]
    assert inert_strategies("scaled") == {}
    assert inert_note("switch", "offset") == ("Switch to circle does nothing with the offset outline: far from the "
                                              "goal its band is nearly a circle already.")
    assert inert_note("chase", "offset") == "" and inert_note("flare", "scaled") == ""


@pytest.fixture
def square_app():
    from sandbox.commands.serve import App, free_port

    app = App(SMALL.replace(shape="square"), port=free_port(), fps=30, steps_per_frame=2, process=False).start()
    yield app
    app.stop()


def test_on_the_offset_outline_flare_switch_and_no_corners_are_greyed_out_and_refused(square_app):
    app = square_app
    folder = app.panel.strategies
    flare, amount = folder.controls["flare"]
    assert not flare.disabled  # the square takes the paper's scaled outline
    client = RawClient(app.port, own_page(app))
    cid = connected(app, client)
    client.set_value(uuid_of(folder.outline), "offset")
    wait_until(lambda: app.runner.latest.family == "offset", what="the offset outline")
    wait_until(lambda: flare.disabled, what="flare greyed out")
    for name in ("flare", "switch", "no_corners"):
        on, slider = folder.controls[name]
        assert on.disabled and slider.disabled and on.hint.startswith("Greyed out. ")
        assert "does nothing with the offset outline" in on.hint
    assert not folder.controls["chase"][0].disabled  # chase lights its own band: it acts here
    assert "Greyed out, as they do nothing with the offset outline" in folder.outline_status.content

    client.set_value(uuid_of(flare), True)  # a tick on a greyed-out control, sent anyway
    client.set_value(uuid_of(amount), 3.0)
    wait_until(lambda: refusals(app, cid) >= 2, what="both refused")
    frames_pass(app.runner)
    assert app.runner.latest.strategies["flare"] == 0.0 and not flare.value

    client.set_value(uuid_of(folder.outline), "scaled")  # back: flare acts again, and a tick reaches it
    wait_until(lambda: not flare.disabled, what="flare back")
    assert not folder.controls["switch"][0].disabled and "Greyed out" not in folder.outline_status.content
    client.set_value(uuid_of(flare), True)
    wait_until(lambda: app.runner.latest.strategies["flare"] == 1.75, what="flare on")
    assert refusals(app, cid) == 2
    client.close()
