"""A design file opened in the page (issue 56, item 7), uploaded over the wire as a page sends it: the world
starts from the design's goal, settings and seed, lit by its recorded light program, as ``serve --design``
starts it; a damaged file is refused in one line and the world goes on; a page that only watches cannot
open one (the gate refuses its upload)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.app.panel.opening import REFUSED
from sandbox.app.web.access import Access
from sandbox.app.world.snapshot import DESIGN_PROGRAM, PAPER_PROGRAM
from sandbox.model.config import Config
from tests.app.web.test_security import TOKEN, connected, make_app, refusals
from tests.app.web.test_upload_files import notice
from tests.viser_wire import RawClient
from tests.waiting import wait_until

#: The design's world: another goal, other counts and another seed than the running one (the tests' SMALL).
DESIGNED = Config(robots=10, boxes=16, update_every=10, hold_steps=3, shape="star", seed=3)
DESIGN_STEPS = 120


@pytest.fixture(scope="module")
def design_file() -> bytes:
    from sandbox import Simulation
    from sandbox.model.design import PatternRecorder, file_bytes

    sim = Simulation(DESIGNED, seed=DESIGNED.seed)
    recorder = PatternRecorder().attach(sim)
    sim.step(DESIGN_STEPS)
    return file_bytes(recorder.design(sim, "paper"))


def upload(app, client: RawClient, name: str, content: bytes) -> None:
    client.upload(app.panel.result.open_design._impl.uuid, name, content)


def own_page(app) -> RawClient:
    client = RawClient(app.port, {"Origin": f"http://127.0.0.1:{app.port}"})
    client.id = connected(app, client)
    return client


@pytest.fixture(scope="module")
def app():
    a = make_app()
    yield a
    a.stop()


def test_a_design_uploaded_starts_its_world_lit_by_its_recorded_program(app, design_file):
    page = own_page(app)
    try:
        upload(app, page, "star-seed3.npz", design_file)
        said = notice(page, "Design opened")
        snap = wait_until(lambda: app.runner.latest if app.runner.latest.program == DESIGN_PROGRAM else None,
                          what="the design's world")
        assert said.startswith("star-seed3.npz: its goal (star), settings and seed 3, from step 0"), said
        assert snap.seed == 3 and snap.shape_name == "star" and snap.world_config == DESIGNED
        assert snap.step < DESIGN_STEPS  # from step 0
        parameters = app.panel.parameters.controls
        assert parameters["robots"].value == 10 and parameters["boxes"].value == 16  # the panel shows its settings
        # Its recorded lights were made for its goal: a new goal hands the floor back to the paper's controller.
        app.events.call(lambda: app.panel.shape.use(np.array([(0, 0), (6, 0), (3, 5)], float), "triangle", None))
        wait_until(lambda: app.runner.latest.shape_name == "triangle" and app.runner.latest.program == PAPER_PROGRAM,
                   what="the triangle lit by the paper's controller")
    finally:
        page.close()


@pytest.mark.parametrize("name, cut, says", [
    ("cut.npz", lambda data: data[: len(data) // 2], "cut.npz is damaged"),
    ("picture.npz", lambda data: b"\x89PNG\r\n\x1a\n" + data, "picture.npz is not a design file: it is a PNG image"),
])
def test_a_damaged_design_is_refused_in_one_line_and_the_world_goes_on(app, design_file, name, cut, says):
    page = own_page(app)
    try:
        world = app.runner.latest.world_key
        upload(app, page, name, cut(design_file))
        said = notice(page, REFUSED)
        assert said.startswith(says) and "\n" not in said, said
        step = app.runner.latest.step
        wait_until(lambda: app.runner.latest.step > step, what="the world going on")
        assert app.runner.latest.world_key == world
    finally:
        page.close()


def test_a_page_that_only_watches_cannot_open_a_design(design_file):
    shared = make_app(access=Access.for_server("127.0.0.1", token=TOKEN))
    watcher = RawClient(shared.port, {"Origin": f"http://127.0.0.1:{shared.port}"})
    try:
        watcher.id = connected(shared, watcher)
        world = shared.runner.latest.world_key
        upload(shared, watcher, "star-seed3.npz", design_file)
        wait_until(lambda: refusals(shared, watcher.id) >= 1, what="the watching page's upload refused")
        step = shared.runner.latest.step
        wait_until(lambda: shared.runner.latest.step > step + 10, what="the world going on")
        assert shared.runner.latest.world_key == world and shared.runner.latest.program != DESIGN_PROGRAM
    finally:
        watcher.close()
        shared.stop()
