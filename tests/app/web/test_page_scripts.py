"""The scripts a page gets at connect for what viser lacks (issue 41, item 5): a finger clicks as a
mouse does (sandbox.app.web.page_touch), a phone's panel is a drawer and viser's software-rendering notice
goes (sandbox.app.web.page_layout). What they do is tested in the real page (tests/browser/test_browser_phone.py);
here, that every page gets them, once, as the gate sends them."""

from __future__ import annotations

from sandbox.app.web.page_layout import LAYOUT_JS, NOTICE_SECONDS, SOFTWARE_NOTICE
from sandbox.app.web.page_touch import LAMP_LIT_LABEL, TOUCH_JS
from sandbox.app.panel import lamp
from tests.app.web.test_security import app, connected, own_page  # noqa: F401 - the fixture
from tests.viser_wire import RawClient


def test_every_page_gets_the_touch_and_layout_scripts_at_connect(app):
    client = RawClient(app.port, own_page(app))
    connected(app, client)
    sources = []
    for message in client._messages(20.0):
        if message.get("type") == "RunJavascriptMessage":
            sources.append(message["source"])
            if TOUCH_JS in sources and LAYOUT_JS in sources:
                break
    assert sources.count(TOUCH_JS) == 1 and sources.count(LAYOUT_JS) == 1
    client.close()


def test_the_scripts_name_what_the_panel_and_viser_show():
    """The touch script knows the lamp is lit by its button's label, the layout script finds viser's
    notice by its title: both must be what the page shows."""
    assert f'"{LAMP_LIT_LABEL}"' in TOUCH_JS
    panel_source = open(lamp.__file__).read()
    assert f'"{LAMP_LIT_LABEL}"' in panel_source
    assert f'"{SOFTWARE_NOTICE}"' in LAYOUT_JS and f"{round(NOTICE_SECONDS * 1000)}" in LAYOUT_JS
    import viser

    bundle = (viser.__file__.rsplit("/", 1)[0] + "/client/src/BrowserWarning.tsx")
    try:
        assert SOFTWARE_NOTICE in open(bundle).read()
    except FileNotFoundError:  # a viser installed without its client's sources: the browser test checks it
        pass
