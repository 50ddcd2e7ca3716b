"""Names arrive as text in a real page (issue 54, attack A): a design file whose goal is named with
markup, opened with ``serve --design`` and with the page's *Open design*; an uploaded file so named; a light program's file so named;
a challenge player so named. Each shows its characters on the page, and none becomes an element, a
style, a picture, a link or a dialog. One server, one page, in this order.

The names are the issue's: ``<iframe srcdoc="<img src=x onerror=alert(document.domain)>">`` ran
script in every viewer's page, ``<style>*{display:none}`` blanked every page."""

from __future__ import annotations

import dataclasses
import re

import pytest

from sandbox.app.panel.plain import WORD_JOINER
from tests.browsing import BROWSER_MARKS, playwright_api  # noqa: F401 - playwright_api: skips without it
from tests.drawing_page import open_page
from tests.waiting import wait_until

pytestmark = BROWSER_MARKS

#: Runs script where it is HTML: the issue's upload name.
SCRIPT_NAME = '<iframe srcdoc="<img src=x onerror=alert(document.domain)>">.txt'
#: The design's goal: script, a picture from elsewhere and a link, if it were markdown.
#: (At most 80 characters: a design's names are bounded, sandbox/model/design.py.)
DESIGN_NAME = '<iframe srcdoc="<img src=x onerror=alert(1)>"> ![](//evil/beacon) [go](//evil)'
#: The goal of a design opened with the page's *Open design* (Result folder), and its file's name.
OPENED_NAME = '<img src=x onerror=alert(2)> <style>*{display:none} **b** [go](//evil/2)'
OPENED_FILE = '<img src=x onerror=alert(3)> [go](javascript:alert(3)).npz'  # no slash: a file's name holds none
#: A light program's file (a file name holds no slash).
PROGRAM_FILE = "<img src=x onerror=alert(document.domain)> [go](javascript:alert(1)) `x`.py"
#: Blanks every page if it is HTML.
PLAYER = "<style>*{display:none}"
SQUARE = b"0 0\n4 0\n4 4\n0 4\n"


def design_named(name: str):
    """A small recorded design whose ``config.shape`` (and so its header's ``goal.name``) is ``name``."""
    from sandbox.model.config import Config
    from sandbox.model.design import PatternRecorder
    from sandbox.model.simulation import Simulation

    config = Config(robots=40, boxes=80, update_every=20, hold_steps=5, shape="square", steps=40)
    sim = Simulation(config)
    recorder = PatternRecorder().attach(sim)
    sim.step(40)
    design = recorder.design(sim, "the paper's controller")
    return dataclasses.replace(design, config=design.config.replace(shape=name))


@pytest.fixture(scope="module")
def hostile_design(tmp_path_factory):
    from sandbox.model.design import save

    path = tmp_path_factory.mktemp("names") / "hostile-design.npz"
    save(design_named(DESIGN_NAME), path)
    return path


@pytest.fixture(scope="module")
def app(hostile_design):
    """``phototaxis serve --design FILE``, as the command line builds it."""
    from sandbox.commands.serve import _app_from_args, free_port
    from sandbox.commands import build_parser

    args = build_parser().parse_args(["serve", "--design", str(hostile_design), "--port", str(free_port()),
                                      "--steps-per-frame", "4", "--fps", "15"])
    app = _app_from_args(args).start()
    yield app
    app.stop()


@pytest.fixture(scope="module")
def page(app, browser):
    def count_dialogs(page) -> None:  # from the first load on: a name's script would run as the page loads
        page.dialogs = []
        page.on("dialog", lambda dialog: (page.dialogs.append(dialog.message), dialog.dismiss()))

    context, page, page.client = open_page(app, browser, 1600, 1000, prepare=count_dialogs)
    yield page
    context.close()


#: Anything the names would have made, were they markup.
INJECTED = """() => [...document.querySelectorAll(
    'iframe, img[src="x"], img[src*="beacon"], [onerror], a[href*="evil"], a[href^="javascript"]')]
    .map(e => e.outerHTML.slice(0, 400))
    .concat([...document.querySelectorAll('style')].filter(s => s.textContent.includes('*{display:none'))
             .map(s => '<style>' + s.textContent.slice(0, 40)))"""


def page_text(page) -> str:
    """The page's text as a reader sees it (without the invisible word joiners that keep a name's
    ``https://`` from becoming a link: sandbox/app/panel/plain.py)."""
    return page.evaluate("document.body.innerText").replace(WORD_JOINER, "")


def shows_as_text(page, name: str) -> None:
    """``name`` is on the page as its characters, nothing of it became markup, no dialog opened."""
    flat = re.sub(r"\s+", " ", name)
    wait_until(lambda: flat in re.sub(r"\s+", " ", page_text(page)), timeout=60, what=f"{name!r} shown as text")
    assert page.evaluate(INJECTED) == []
    assert page.dialogs == []


def text_field(page, label: str):
    """viser's text inputs are not tied to their label (its for= names another id): the row's input."""
    row = page.locator(f"label:text-is('{label}')").locator(
        "xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]")
    return row.locator("input").first


def test_a_designs_goal_name_is_text(app, page):
    """``serve --design``: the Run folder's status names the design's goal."""
    assert app.runner.latest.shape_name == DESIGN_NAME
    shows_as_text(page, DESIGN_NAME)
    page.get_by_text("Result", exact=True).first.click()
    page.get_by_role("button", name="Explain the result", exact=True).click()
    wait_until(lambda: "Ran:" in page_text(page), what="the result explained")
    shows_as_text(page, DESIGN_NAME)  # (the explanation names the goal by the part after its last slash)


def test_a_design_opened_in_the_page_shows_its_goals_name_as_text(app, page):
    """The page's *Open design* (Result folder, open since the test above): the *Design opened* notice names
    the file and the design's goal, and the Run folder the goal; each as its characters."""
    from sandbox.model.design import file_bytes

    page.locator("input[type=file][accept='.npz']").set_input_files(
        files=[{"name": OPENED_FILE, "mimeType": "application/octet-stream",
                "buffer": file_bytes(design_named(OPENED_NAME))}])
    wait_until(lambda: app.runner.latest.shape_name == OPENED_NAME, what="the opened design's world")
    notice = page.locator(".mantine-Notification-root").filter(has_text="Design opened")
    notice.first.wait_for(timeout=60_000)
    said = re.sub(r"\s+", " ", notice.first.inner_text())
    assert f"its goal ({OPENED_NAME})" in said and OPENED_FILE in said, said
    shows_as_text(page, OPENED_NAME)
    shows_as_text(page, OPENED_FILE)


def test_an_uploaded_files_name_is_text(app, page):
    page.locator("input[type=file]:not([accept='.npz'])").set_input_files(  # the polygon file's, not Open design's
        files=[{"name": SCRIPT_NAME, "mimeType": "text/plain", "buffer": SQUARE}])
    wait_until(lambda: app.runner.latest.shape_name == SCRIPT_NAME, what="the uploaded goal")
    shows_as_text(page, SCRIPT_NAME)


def test_a_light_programs_file_name_is_text(app, page, tmp_path):
    program = tmp_path / PROGRAM_FILE
    program.write_text("class P:\n    def update(self, observation):\n        return None\n")
    spec = f"{program}:P"
    page.get_by_text("Light program", exact=True).first.click()
    field = text_field(page, "Program")
    field.fill(spec)
    field.press("Tab")
    wait_until(lambda: app.panel.program.path.value == spec, what="the program's path")
    page.get_by_role("button", name="Use this program", exact=True).click()
    wait_until(lambda: app.runner.latest.program == spec, what="the program in use")
    shows_as_text(page, spec)


def test_a_challenge_players_name_is_text(app, page):
    page.get_by_text("Challenge", exact=True).first.click()
    field = text_field(page, "Your name")
    field.fill(PLAYER)
    field.press("Tab")
    wait_until(lambda: app.panel.challenge.name.value == PLAYER, what="the name")
    page.get_by_role("button", name="Start a round", exact=True).click()
    wait_until(lambda: app.panel.challenge.round is not None, what="the round")
    shows_as_text(page, PLAYER)
    assert page.get_by_role("button", name="Start a round", exact=True).is_visible()  # the page is not blank
