"""The page scripts' seam onto viser's client (sandbox/app/web/client_seam.py): every row of every script's
table is found in the installed viser's client bundle, each table holds everything its script takes from
viser's client and nothing else, a row removed or a piece gone from the bundle fails, and viser stays
pinned to the release these tests pass on."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pytest
import viser

from sandbox.app.web import client_seam, pacing, page_keys, page_layout, page_open, page_sends, page_touch
from sandbox.app.web.client_seam import MANTINE, PATTERN, RUNS_SCRIPTS, TEXT, Relies
from sandbox.app.web.viser_seam import WRITTEN_FOR

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[3]
#: Each page script as a page is sent it, and its table.
SCRIPTS = {
    "keys.js": (page_keys.KEYS_JS, page_keys.CLIENT),
    "layout.js": (page_layout.LAYOUT_JS, page_layout.CLIENT),
    "sends.js": (page_sends.SENDS_JS, page_sends.CLIENT),
    "touch.js": (page_touch.TOUCH_JS, page_touch.CLIENT),
    "report.js": (pacing.report_js(pacing.PATH + "token"), pacing.CLIENT),
    "open.js": (page_open.open_folder_js("Result", "Explain"), ()),
}
EVERY_ROW = [pytest.param(name, row, id=f"{name}:{row.uses}") for name, (_, rows) in SCRIPTS.items() for row in rows]


# ------------------------------------------------------------ against viser's client
def test_the_installed_viser_shows_every_row():
    rows = [RUNS_SCRIPTS, *(row for _, table in SCRIPTS.values() for row in table)]
    for row in rows:
        assert row.uses and row.why and row.how in (TEXT, PATTERN, MANTINE), row
        assert row.found or row.how != PATTERN, row
    assert client_seam.missing(tuple(rows)) == []


def test_the_bundle_is_unpacked_as_the_page_unpacks_it():
    page = client_seam.CLIENT_PAGE.read_text(encoding="utf-8")
    sizes = re.search(r'data-ss="(\d+)" data-cs="(\d+)"', page)
    assert len(client_seam.bundle().encode("utf-8")) == int(sizes.group(1)) + int(sizes.group(2))
    # viser's base-88: 5 characters for 4 bytes, 2 for a last byte ("!" is 0, "n" 71, "\" 54, "P" 42, "e" 62,
    # "U" 47, "h" 65 in its alphabet; 71 * 88^4 + 54 * 88^3 + 42 * 88^2 + 62 * 88 + 47 = 2^32 - 1)
    assert client_seam._from_base88("n\\PeU!h") == b"\xff\xff\xff\xff\x41"


def without_evidence(row: Relies, client: str) -> str:
    """``client`` without what shows ``row``: its first pattern's matches, its text, or its Mantine component."""
    if row.how == TEXT:
        return client.replace((row.found or (row.uses,))[0], "")
    if row.how == MANTINE:
        component = row.uses.split("-")[1]
        return re.sub(client_seam.regex(f"@mantine/core/{component}`"), "@mantine/core/Gone`", client)
    return re.sub(client_seam.regex(row.found[0]), "", client)


@pytest.mark.parametrize("name, row", EVERY_ROW)
def test_a_viser_without_what_a_row_relies_on_fails(name, row):
    client = without_evidence(row, client_seam.bundle())
    assert client_seam.missing((row,), client), f"{name}: {row.uses} still found"


@pytest.mark.parametrize("before, after, row, says", [
    # Mantine renames a part of a component's classes
    ("closeButton:`m_919a4d88`", "close:`m_919a4d88`", ".mantine-Notification-closeButton",
     "Notification's classes have no closeButton"),
    # Mantine's class names get another prefix
    ("classNamesPrefix:c=`mantine`", "classNamesPrefix:c=`mnt`", ".mantine-Paper-root", "classNamesPrefix mantine"),
    # viser's notice is retitled
    ("title:`Software WebGL rendering detected`", "title:`Rendering in software`", page_layout.SOFTWARE_NOTICE,
     "no 'Software WebGL rendering detected'"),
    # a throttle of 80 ms
    ("RL(t,50)", "RL(t,80)", str(page_sends.MOST_MS), "the numbers are [20, 50, 80], not [20, 50]"),
    # the sheet's animation slows down
    ("transition:`height 0.3s linear`", "transition:`height 0.5s linear`", "350", "nothing matches"),
    # the camera's keys change
    ("`KeyQ`,`KeyE`,`ArrowUp`", "`KeyQ`,`KeyE`,`ArrowUp`,`KeyZ`", "KeyS", "nothing matches"),
])
def test_what_a_new_viser_may_change_fails_its_row(before, after, row, says):
    client = client_seam.bundle()
    assert client.count(before) == 1, before  # (the pieces of viser 1.1.1's bundle these cases change)
    rows = {row.uses: row for _, table in SCRIPTS.values() for row in table}
    found = client_seam.missing((rows[row],), client.replace(before, after))
    assert len(found) == 1 and found[0].startswith(f"{row}: ") and says in found[0], found


# --------------------------------------------------------- each table, complete
@pytest.mark.parametrize("name", SCRIPTS)
def test_each_table_holds_what_its_script_takes_from_viser_and_nothing_else(name):
    source, rows = SCRIPTS[name]
    assert client_seam.uncovered(source, rows) == [], f"{name} uses these with no row in its table"
    assert client_seam.stale(source, rows) == [], f"rows of {name}'s table for nothing it uses"
    assert len({row.uses for row in rows}) == len(rows), f"{name}: a row twice"


@pytest.mark.parametrize("name, row", EVERY_ROW)
def test_removing_a_row_fails(name, row):
    source, rows = SCRIPTS[name]
    assert row.uses in client_seam.uncovered(source, tuple(r for r in rows if r is not row))


@pytest.mark.parametrize("added, use", [
    ('document.querySelector(".mantine-Modal-root");', ".mantine-Modal-root"),
    ('document.querySelectorAll("[data-dock-tab]");', "[data-dock-tab]"),
    ('el.closest(".folder-label");', ".folder-label"),
    ('document.querySelectorAll("section");', "section"),
    ('el.getAttribute("data-with-title");', "data-with-title"),
    ('const MESSAGE = {type: "ScenePointerMessage"};', "ScenePointerMessage"),
    ("HTMLCanvasElement.prototype.getContext = wrapped;", "HTMLCanvasElement.prototype"),
    ("window.fetch = wrapped;", "window.fetch"),
])
def test_a_script_that_uses_markup_not_in_its_table_fails(added, use):
    source, rows = SCRIPTS["layout.js"]
    changed = source.replace("  look();\n})();", f"  {added}\n  look();\n}})();")
    assert changed != source
    assert client_seam.uncovered(changed, rows) == [use]


def test_a_value_from_viser_not_in_the_table_fails():
    source, rows = SCRIPTS["layout.js"]
    changed = source.replace("openMs: 350}", 'openMs: 350, handle: "3.5em", fadeMs: 200}')
    assert changed != source
    assert client_seam.uncovered(changed, rows) == ["200", "3.5em"]


def test_what_a_script_takes_from_viser_is_read_from_its_markup_and_its_VISER():
    source = """// a comment's ".mantine-Gone-root" and [role="none"] are not read
(() => {
  const VISER = {title: "Hello", wait: 250, sheet: {place: "fixed"}, keys: ["KeyA"],
                 roles: "[role='tab'],[role='tree']"};
  document.querySelectorAll("div[style*='width: 20em']");  // a selector asked of the DOM, whole
  const css = ".mantine-Paper-root, .a-class { top: 0.5em; } /* not a comment: in a string */";
  const label = "Press Play (space) to start.";  // no markup
  window.__phototaxisOwn = 1;  // ours
  Worker.prototype.postMessage = wrapped;
  window.setTimeout = wrapped;
})();"""
    assert client_seam.relied_on(source) == {
        "Hello", "250", "fixed", "KeyA", '[role="tab"]', '[role="tree"]',
        'div[style*="width: 20em"]', '[style*="width: 20em"]', ".mantine-Paper-root", ".a-class",
        "Worker.prototype", "window.setTimeout"}


def test_every_page_script_is_in_these_tests_and_in_the_wheel():
    folder = resources.files("sandbox.app.web").joinpath("page")
    assert sorted(p.name for p in folder.iterdir() if p.name.endswith(".js")) == sorted(SCRIPTS)
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert "page/*.js" in package_data["sandbox.app.web"]


def test_a_script_takes_each_of_its_settings_and_no_other():
    assert page_open.open_folder_js('A "quoted" </script>', "B").endswith(
        'window.__phototaxisOpenFolder?.("A \\"quoted\\" </script>", ["B"]);\n')
    with pytest.raises(ValueError, match=r"takes the settings \['inside', 'title'\], not \['title'\]"):
        client_seam.script("open.js", title="A")
    with pytest.raises(ValueError, match="not"):
        client_seam.script("open.js", title="A", inside="B", extra=1)


def test_viser_is_pinned_to_the_release_these_tests_pass_on():
    dependencies = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    assert [d for d in dependencies if re.match(r"viser\b", d)] == [f"viser=={WRITTEN_FOR}"]
    assert viser.__version__ == WRITTEN_FOR
