"""One seam to viser (sandbox/app/web/viser_seam.py): only it names viser's private code, its table covers
every use, a missing piece refuses the start in one line, and viser's callbacks can be routed."""

from __future__ import annotations

import ast
import concurrent.futures
import functools
import re
import sys
from pathlib import Path

import viser

from tests.private_names import is_private, is_private_module, is_self, private_names_defined_in

SANDBOX = Path(__file__).resolve().parents[3] / "sandbox"
SEAM = SANDBOX / "app" / "web" / "viser_seam.py"
#: getattr and friends: a private name in a string is still a private name.
ATTRIBUTE_BUILTINS = {"getattr", "setattr", "hasattr", "delattr"}


@functools.cache
def visers_private_names() -> frozenset[str]:
    """Every private name viser's own code defines: its private modules, the module- and class-level
    names (functions, classes, assignments, imports) of the modules ``import viser`` loads, and every
    ``self._x`` they assign. Read from the installed viser, so a new viser brings its new names."""
    names: set[str] = set()
    root = Path(viser.__file__).resolve().parent
    names.update(part for path in root.rglob("*.py") for part in path.relative_to(root).with_suffix("").parts
                 if is_private(part))
    loaded = [Path(module.__file__) for name, module in list(sys.modules.items())
              if (name == "viser" or name.startswith("viser.")) and getattr(module, "__file__", None)]
    names.update(private_names_defined_in(loaded))
    return frozenset(names)


def trespasses(source: str, private: frozenset[str]) -> list[str]:
    """Where ``source`` imports a private viser module or names one of viser's private names on an
    object other than its own (``self``/``cls``), as an attribute or as a string."""
    if "viser" not in source and not private.intersection(re.findall(r"_\w+", source)):
        return []  # (no name to find: not worth parsing)
    found, exempt = [], set()  # exempt: docstrings, and names looked up on self
    for node in ast.walk(ast.parse(source)):  # (a node comes before its children)
        where = f"line {getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Expr):
            exempt.add(id(node.value))
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ATTRIBUTE_BUILTINS
              and len(node.args) >= 2 and is_self(node.args[0])):
            exempt.add(id(node.args[1]))
        elif isinstance(node, ast.Import):
            found += [f"{where}: import {a.name}" for a in node.names if is_private_module(a.name, "viser")]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if is_private_module(node.module, "viser"):
                found.append(f"{where}: from {node.module} import ...")
            elif node.module.split(".")[0] == "viser":
                found += [f"{where}: from {node.module} import {a.name}" for a in node.names if is_private(a.name)]
        elif isinstance(node, ast.Attribute) and node.attr in private and not is_self(node.value):
            found.append(f"{where}: .{node.attr}")
        elif (isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in private
              and id(node) not in exempt):
            found.append(f"{where}: {node.value!r}")
    return found


def test_visers_private_names_are_read_from_viser_itself():
    private = visers_private_names()
    # what the app needs from viser, so what the guard below must know to be private
    assert {"_websock_server", "_live_connections", "_broadcast_buffer", "_handle_incoming_message", "_impl",
            "_gui_input_handle_from_uuid", "_command_handle_from_uuid", "_current_file_upload_states",
            "_finish_file_upload", "_websock_connection", "_thread_executor", "_messages", "_infra",
            "_async_message_buffer", "_gui_api", "_gui_handles", "_icons"} <= private
    assert not {"_", "__init__", "gui", "scene", "queue_message"} & private


def test_the_guard_sees_every_way_to_reach_visers_private_code():
    private = visers_private_names()
    samples = {"import viser.infra._infra": 1, "from viser import _messages": 1, "from viser._gui_api import X": 1,
               "from viser.infra import _async_message_buffer as b": 1, "server._websock_server.x = 1": 1,
               "handle._impl.props": 1, "getattr(gui, '_command_handle_from_uuid')": 1,
               "table = '_gui_input_handle_from_uuid'": 1,
               # our own private state, and viser's public API, are fine
               "self._impl = 1\ngetattr(self, '_thread', None)": 0, "import viser\nviser.Icon.X": 0,
               "def f():\n    '''_impl'''": 0, "from viser.uplot import Series": 0}
    for source, count in samples.items():
        assert len(trespasses(source, private)) == count, source


def test_only_the_seam_names_visers_private_code():
    private = visers_private_names()
    found = {str(path.relative_to(SANDBOX.parent)): where for path in sorted(SANDBOX.rglob("*.py")) if path != SEAM
             for where in [trespasses(path.read_text(encoding="utf-8"), private)] if where}
    assert not found, f"viser's private code outside sandbox/app/web/viser_seam.py: {found}"


# ------------------------------------------------------------------ the table and its check
def test_the_installed_viser_has_every_piece_of_the_table():
    from sandbox.app.web import viser_seam

    assert viser_seam.missing() == []
    for use in viser_seam.USES:
        assert use.what and use.why and use.where.split(".")[0] in ("viser", "asyncio"), use
    viser_seam.check()


def test_each_way_of_checking_finds_a_missing_piece():
    from sandbox.app.web.viser_seam import ASSIGNED, FIELDS, KEYS, Use, missing

    rows = {
        Use("-", "viser._no_such_module", "-"): "viser._no_such_module",
        Use("-", "viser._viser:NoSuchClass.attribute", "-"): "viser._viser:NoSuchClass",
        Use("-", "viser._messages", "-", names=("GuiUpdateMessage", "NoSuchMessage")): "viser._messages:NoSuchMessage",
        Use("-", "viser._viser:ViserServer._no_such_state", "-", ASSIGNED): "viser._viser:ViserServer._no_such_state",
        Use("-", "viser.infra._async_message_buffer:AsyncMessageBuffer", "-", FIELDS, names=("event_loop", "gone")):
            "viser.infra._async_message_buffer:AsyncMessageBuffer.gone",
        Use("-", "viser._gui_api:_FileUploadState", "-", KEYS, names=("parts", "gone")):
            "viser._gui_api:_FileUploadState.gone",
        Use("-", "viser._gui_api:GuiApi._finish_file_upload", "-", arguments=4):
            "viser._gui_api:GuiApi._finish_file_upload (taking 4 arguments)",
    }
    for row, piece in rows.items():
        assert missing((row,)) == [piece], row
    present = (Use("-", "viser._viser:ViserServer._websock_server", "-", ASSIGNED),
               Use("-", "viser._gui_api:GuiApi._finish_file_upload", "-", arguments=3))
    assert missing(present) == []


def test_serve_refuses_in_one_line_on_a_viser_without_a_piece(monkeypatch, capsys):
    from viser import _gui_handles

    from sandbox.commands import main

    # _gui_api holds its own name for it, and _gui_handles uses it only in annotations: nothing running breaks
    monkeypatch.delattr(_gui_handles, "_CommandHandleState")
    assert main(["serve", "--port", "0"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert f"viser {viser.__version__} lacks" in err and "viser._gui_handles:_CommandHandleState" in err, err
    assert "install viser==1.1.1" in err, err


# ------------------------------------------------------------------ route_callbacks
def test_routed_callbacks_of_a_click_a_page_of_its_own_and_a_connect_go_through_submit():
    import contextlib
    import io

    from sandbox.app.web import viser_seam
    from sandbox.app.web.access import Access
    from sandbox.app.web.gate import start_server
    from sandbox.commands.serve import free_port
    from tests.viser_wire import RawClient
    from tests.waiting import wait_until

    pool = concurrent.futures.ThreadPoolExecutor(2)
    submitted, ran = [], []

    def submit(fn, *args):
        submitted.append(getattr(fn, "__name__", fn))
        return pool.submit(fn, *args)

    server, _ = start_server(Access.for_server("127.0.0.1"), host="127.0.0.1", port=free_port(), label="seam")
    try:
        viser_seam.route_callbacks(server, submit)
        shared = server.gui.add_button("shared")
        shared.on_click(lambda event: ran.append("shared click"))
        server.on_client_connect(lambda client: ran.append("connect"))
        client = RawClient(server.get_port(), {"Origin": f"http://127.0.0.1:{server.get_port()}"})
        client.say_hello()
        page = wait_until(lambda: next(iter(server.get_clients().values()), None), what="the page to connect")
        own = page.gui.add_button("own")
        own.on_click(lambda event: ran.append("own click"))
        client.click(viser_seam.handle_uuid(shared))
        client.click(viser_seam.handle_uuid(own))
        wait_until(lambda: {"connect", "shared click", "own click"} <= set(ran), what="the three callbacks")
        assert submitted.count("<lambda>") == 3, submitted  # each of them through submit
        client.close()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
        pool.shutdown(wait=False)


def test_a_callback_the_stopping_app_will_not_run_ends_quietly():
    """A page's last messages arrive while the app stops: viser would log each failed callback as
    "Task failed with exception". A callback the stopped queue refuses ends with None; any other
    failure is still the callback's."""
    from sandbox.app.web.events import EventQueue
    from sandbox.app.web.viser_seam import _Routed

    events = EventQueue().open()
    routed = _Routed(events.submit, concurrent.futures.ThreadPoolExecutor(1))
    assert routed.submit(lambda x: x + 1, 1).result(5) == 2
    failing = routed.submit(lambda: 1 / 0)
    assert isinstance(failing.exception(5), ZeroDivisionError)
    events.stop()
    assert routed.submit(lambda: 1 / 0).result(5) is None
    routed.shutdown()
