"""The gate in real Chromium: another site's page cannot open the sandbox's
websocket, and a control disabled on the page stays refused when a script on
the page's own origin (someone at its console) sends its click anyway."""

from __future__ import annotations

import http.server
import threading

import pytest

from tests.browsing import BROWSER_MARKS
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS


@pytest.fixture(scope="module")
def app():
    from sandbox.commands.serve import App, free_port
    from sandbox.model.config import Config

    app = App(Config(robots=12, boxes=20), port=free_port(), steps_per_frame=2, fps=15, process=False)
    app.start()
    yield app
    app.stop()


@pytest.fixture
def other_site(app):
    """A page on another origin (another port) whose script opens the sandbox's websocket."""
    import viser

    from sandbox.commands.serve import free_port

    script = f"""<!doctype html><title>waiting</title><script>
      const ws = new WebSocket("ws://127.0.0.1:{app.port}/", ["viser-v{viser.__version__}"]);
      ws.onopen = () => {{ document.title = "open"; }};
      ws.onerror = () => {{ document.title = "refused"; }};
    </script>""".encode()

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.end_headers()
            self.wfile.write(script)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", free_port()), Page)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}/"
    server.shutdown()


def test_a_page_of_another_site_cannot_open_the_websocket(app, browser, other_site):
    page = browser.new_page()
    page.goto(other_site)
    wait_until(lambda: page.title() != "waiting", what="the websocket to open or fail")
    assert page.title() == "refused" and app.server.get_clients() == {}
    page.close()


#: A devtools-sized msgpack encoder (maps, strings, booleans): what a person at the console would paste.
MSGPACK_JS = """
const enc = new TextEncoder();
function pack(v) {
  if (v === true) return [0xc3];
  if (v === false) return [0xc2];
  if (typeof v === "string") { const b = [...enc.encode(v)]; return [0xd9, b.length, ...b]; }
  const keys = Object.keys(v);
  return [0x80 | keys.length, ...keys.flatMap(k => [...pack(k), ...pack(v[k])])];
}
"""


def test_a_disabled_button_clicked_from_the_pages_own_console_is_refused(app, browser, tmp_path):
    """The page's own origin passes the gate; its disabled button still does nothing, whoever sends the click."""
    import viser

    marker = tmp_path / "ran.txt"
    program = tmp_path / "p.py"
    program.write_text(f"open({str(marker)!r}, 'w').write('ran')\nclass P:\n    def update(self, o): return None\n")
    folder = app.panel.program
    folder.path.value = f"{program}:P"
    folder.use.disabled = True
    page = browser.new_page(viewport={"width": 1100, "height": 760})
    page.goto(f"http://127.0.0.1:{app.port}/")
    wait_until(lambda: app.server.get_clients(), what="the page to connect")
    page.get_by_text("Light program", exact=True).first.click()
    assert page.get_by_role("button", name="Use this program").is_disabled()
    before = sum(app.gate.inbox._refusals.values())
    sent = page.evaluate(MSGPACK_JS + """([uuid, protocol]) => new Promise(done => {
        const ws = new WebSocket(location.origin.replace("http", "ws") + "/", [protocol]);
        ws.binaryType = "arraybuffer";
        ws.onopen = () => {
          for (const updates of [{disabled: false}, {value: true}])
            ws.send(new Uint8Array(pack({type: "GuiUpdateMessage", uuid: uuid, updates: updates})));
          done("sent");
        };
        ws.onerror = () => done("refused");
    })""", [folder.use._impl.uuid, f"viser-v{viser.__version__}"])
    assert sent == "sent"  # the page's own origin is let in ...
    wait_until(lambda: sum(app.gate.inbox._refusals.values()) >= before + 2, what="both messages to be refused")
    assert folder.use.disabled and not marker.exists()  # ... and its disabled button still does nothing
    assert app.runner.latest.program == "the paper's controller"
    page.close()
