"""The app without a browser: the simulation thread, snapshots, colours and
the panel's logic (upload validation, CSV), on a small population."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from sandbox.app.view import palette
from sandbox.app.world.orders import Apply, Follow, Reset, SetPlaying, SetShape, ShowEvery, StepOnce, WantField
from sandbox.app.world.runner import Runner, frames_owed, next_frame_due
from sandbox.model.config import Config
from tests.waiting import frames_pass, paused_step, wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)


@pytest.fixture
def runner():
    r = Runner(SMALL, shape=None, fps=60, steps_per_frame=2)
    r.start()
    yield r
    r.stop()


def test_commands_run_in_the_simulation_thread(runner):
    names = runner.call(Apply(lambda sim: threading.current_thread().name))
    assert names == "phototaxis-simulation"
    assert runner.call(Apply(lambda sim: sim is runner.sim))  # the runner's own simulation, and the answer comes back
    before = runner.call(Apply(lambda sim: sim.steps_done))
    wait_until(lambda: runner.latest.step > before)
    shown = runner.latest.step
    assert runner.call(Apply(lambda sim: sim.steps_done)) >= shown  # the running world, at least as far as it was shown


def test_runs_pauses_steps_and_resets(runner):
    wait_until(lambda: runner.sim.steps_done > 10)
    runner.submit(SetPlaying(False))
    steps = paused_step(runner)
    frames_pass(runner)
    assert runner.call(Apply(lambda sim: sim.steps_done)) == steps == runner.latest.step
    runner.ask(StepOnce(3))
    wait_until(lambda: runner.latest.step == steps + 3)
    runner.ask(Reset(7))
    wait_until(lambda: runner.latest.seed == 7 and runner.latest.step == 0)
    assert [s.step for s in runner.series()] == [0]


def test_snapshots_are_copies_the_gui_can_keep(runner):
    snap = runner.latest
    assert snap.robot_positions.shape == (12, 2) and snap.box_positions.shape == (20, 2)
    assert snap.intensities.shape == (64, 64) and snap.field is None  # the heat map is off
    runner.submit(WantField(True))
    wait_until(lambda: runner.latest.field is not None)
    assert runner.latest.field.shape == (257, 257) and runner.latest.field.dtype == np.float32
    assert runner.latest.field.max() > 0
    before = snap.robot_positions.copy()
    wait_until(lambda: runner.latest.step > snap.step + 10)
    np.testing.assert_array_equal(snap.robot_positions, before)  # old snapshot untouched


def test_errors_go_back_to_whoever_posted(runner):
    seen = []
    runner.ask(Apply(lambda sim: sim.update_config(robots=-1)), on_error=seen.append)
    wait_until(lambda: seen)
    assert "robots" in str(seen[0])
    start = runner.latest.step
    wait_until(lambda: runner.latest.step > start)  # still running


def test_shape_change_and_selection(runner):
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    runner.ask(SetShape(square, "sq"))
    wait_until(lambda: runner.latest.shape_name == "sq" and runner.latest.goal_vertices is not None)
    assert len(runner.latest.goal_vertices) == 4
    runner.submit(Follow((7, 3)))  # two viewers' robots
    wait_until(lambda: len(runner.latest.followed) == 2)
    robot = runner.latest.robot(3)
    assert robot.index == 3 and robot.sensors.shape == (4,) and robot.sensor_points.shape == (4, 2)
    assert [r.index for r in runner.latest.followed] == [3, 7] and runner.latest.robot(5) is None
    assert np.array_equal(runner.latest.robot(7).position, runner.latest.robot_positions[7])
    runner.submit(Follow(()))
    wait_until(lambda: runner.latest.followed == ())


def test_speed_is_measured(runner):
    wait_until(lambda: runner.steps_per_second() > 0 and runner.frames_per_second() > 0)


def test_a_late_frame_takes_the_steps_it_missed_and_a_long_stall_is_let_go():
    # Frames every 0.1 s. A frame due at 1.0 s catches up on at most 0.1 s more than its own:
    assert frames_owed(1.0, now=0.98, interval=0.1, most_behind=0.1) == 1  # early (a command woke the loop)
    assert frames_owed(1.0, now=1.05, interval=0.1, most_behind=0.1) == 1  # on time
    assert frames_owed(1.0, now=1.23, interval=0.1, most_behind=0.25) == 3  # 0.23 s late: 2 frames missed
    assert frames_owed(1.0, now=2.0, interval=0.1, most_behind=0.1) == 2  # 1 s late: one more frame now
    # The frame after: due 0.1 s after the last frame stepped for. That frame, due at 1.0 s, stepped
    # for 3 frames (1.0, 1.1, 1.2); at 1.25 s the next is due at 1.3 s.
    assert next_frame_due(1.0 + 2 * 0.1, now=1.25, interval=0.1, most_behind=2.0) == pytest.approx(1.3)
    # Done at 1.5 s with one frame stepped (it stalled): the next is due at 1.1 s, 0.4 s ago, and the
    # frames that follow catch up (it was due at 1.5 s: all 0.4 s let go, which lost the live default
    # 0.6-1.3 % of its steps on a busy machine).
    assert next_frame_due(1.0, now=1.5, interval=0.1, most_behind=2.0) == pytest.approx(1.1)
    # 3 s behind: due 2 s ago at most, the rest let go (a machine that cannot keep up does not race).
    assert next_frame_due(1.0, now=4.1, interval=0.1, most_behind=2.0) == pytest.approx(2.1)
    # Nothing owed (paused, a new world): due one interval after, or now.
    assert next_frame_due(1.0, now=1.5, interval=0.1, most_behind=0.0) == 1.5
    assert next_frame_due(1.0, now=1.05, interval=0.1, most_behind=0.0) == pytest.approx(1.1)


def _clock_and_step(sim) -> tuple[float, int]:
    return time.perf_counter(), sim.steps_done


def _stall(sim, seconds: float = 0.6) -> None:
    time.sleep(seconds)  # the loop held up inside a frame (a busy machine, a collection)


@pytest.mark.slow  # on the clock; test_a_late_frame_... and test_a_frame_that_built_a_new_world_... decide it
def test_the_world_makes_up_for_a_stall_and_keeps_its_speed():
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2).start()  # 60 steps/s
    try:
        wait_until(lambda: r.latest.step > 10)
        t0, s0 = r.call(Apply(_clock_and_step))
        r.call(Apply(_stall))  # 0.6 s: 36 steps behind

        def caught_up() -> bool:  # read without a command (a command would wake the loop)
            t, s = time.perf_counter(), r.sim.steps_done
            return s >= s0 + 60 * (t - t0) - 8  # within 4 frames of the schedule
        wait_until(caught_up, timeout=10, what="the steps the stall cost")
    finally:
        r.stop()


def _nothing(sim) -> None:
    return None


@pytest.mark.slow  # a second of commands on the clock; test_a_command_between_frames_takes_no_steps decides it
def test_commands_do_not_make_the_world_run_faster():
    # A page that sends commands faster than frames (a drag moving the lamp) woke the loop into a
    # frame of steps each time: 60 steps/s ran at several hundred while commands came.
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2).start()  # 60 steps/s
    try:
        wait_until(lambda: r.latest.step > 10)
        t0, s0 = r.call(Apply(_clock_and_step))
        answered = 0
        while time.perf_counter() < t0 + 1.0:  # commands back to back for a second
            r.call(Apply(_nothing))
            answered += 1
        t1, s1 = r.call(Apply(_clock_and_step))
        assert answered > 60, "the commands were not answered between frames"
        assert s1 - s0 <= 60 * (t1 - t0) + 8
    finally:
        r.stop()


@pytest.mark.slow  # on the clock; test_a_frame_that_built_a_new_world_owes_nothing_for_it decides it
def test_a_new_world_starts_on_the_clock_and_owes_nothing_for_its_build():
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2).start()
    try:
        wait_until(lambda: r.latest.step > 10)
        r.ask(Apply(_stall))  # the same turn as the reset below: as if the build took 0.6 s
        r.call(Reset(3))
        t1, s1 = r.call(Apply(_clock_and_step))
        frames_pass(r, 10)
        t2, s2 = r.call(Apply(_clock_and_step))
        assert s2 - s1 <= 60 * (t2 - t1) + 8, "the new world raced to make up for the time its build took"
    finally:
        r.stop()


@pytest.mark.slow  # 48 frames on the clock; test_a_frame_is_shown_every_kth_and_takes_its_steps decides it
def test_a_world_shown_every_third_frame_keeps_its_speed():
    # sandbox.app.web.pacing: when every page draws fewer frames than are sent, the world takes a snapshot
    # at every k-th frame only; it steps on the same schedule. Counted by the loop's own counters (a
    # command, as the reading itself, shows its effect at once: one snapshot more).
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2).start()

    def counts() -> tuple[int, int, int]:  # frames run, snapshots taken, steps
        return r.call(Apply(lambda sim: (r._frames_run, r._frame, sim.steps_done)))

    try:
        wait_until(lambda: r.latest.step > 10)
        r.submit(ShowEvery(3))
        frames0, shots0, steps0 = counts()
        wait_until(lambda: r._frames_run >= frames0 + 36, what="36 frames")
        frames1, shots1, steps1 = counts()
        frames, shots = frames1 - frames0, shots1 - shots0
        assert shots <= frames // 3 + 2, (frames, shots)  # every third, and the readings' own
        assert steps1 - steps0 >= 2 * frames  # each frame its 2 steps (or more, catching up): the same speed
        r.submit(ShowEvery(1))
        frames0, shots0, _ = counts()
        wait_until(lambda: r._frames_run >= frames0 + 12, what="12 frames")
        frames1, shots1, _ = counts()
        assert shots1 - shots0 >= frames1 - frames0, "every frame shown again"
    finally:
        r.stop()


# The loop's decisions, one frame at a time on a runner that was not started (the tests above, marked
# slow, measure the same on the clock).
def test_a_command_between_frames_takes_no_steps():
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2)
    steps, shots, due = r.sim.steps_done, r._frame, time.perf_counter() + 10.0
    for _ in range(50):  # a drag's commands, faster than frames
        r.submit(Apply(_nothing))
        assert r._commands_between_frames(due) == due  # the next frame stays when it was due
    assert r.sim.steps_done == steps and r._frame == shots + 50  # no step, and each command's effect shown


def test_a_frame_that_built_a_new_world_owes_nothing_for_it():
    interval = 1 / 30
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2)
    late = time.perf_counter() - 0.6  # 0.6 s behind: a stall
    assert r._frame_on_schedule(late, interval) < time.perf_counter() - 0.3  # the frames after it catch up
    r.submit(Reset(seed=3))  # taken by the next frame: as if its build took the 0.6 s
    late = time.perf_counter() - 0.6
    before = time.perf_counter()
    assert r._frame_on_schedule(late, interval) >= before  # the new world starts on the clock: nothing owed
    assert r.sim.seed == 3


def test_a_frame_is_shown_every_kth_and_takes_its_steps():
    r = Runner(SMALL, shape=None, fps=30, steps_per_frame=2)
    r.submit(ShowEvery(3)).result(10)
    steps, shots = r.sim.steps_done, r._frame
    for _ in range(12):
        r._frame_of_steps(deadline=0.0)
    assert r._frame - shots == 4 and r.sim.steps_done - steps == 24  # every third shown, every one stepped
    r._frame_of_steps(deadline=0.0, frames=3)  # a late frame: the steps of the two it missed too
    assert r.sim.steps_done - steps == 30
    r.submit(ShowEvery(1)).result(10)
    shots = r._frame
    for _ in range(5):
        r._frame_of_steps(deadline=0.0)
    assert r._frame - shots == 5, "every frame shown again"


def test_headless_advance_without_threads():
    r = Runner(SMALL, shape=None, playing=False)
    snap = r.advance(25)
    assert snap.step == 25 and r.call(Apply(lambda sim: sim.steps_done)) == 25


# ------------------------------------------------------------------ palette
def test_light_grid_orientation_and_colours():
    inten = np.zeros((64, 64))
    inten[0, 63] = 1.0  # the light at the top-left corner (x smallest, y largest)
    img = palette.light_grid_image(inten, cell_pixels=4)
    assert img.shape == (256, 256, 3)
    assert tuple(img[2, 2]) == palette.LIGHT_ON
    assert tuple(img[254, 254]) == palette.LIGHT_OFF
    bottom_first = palette.light_grid_image(inten, cell_pixels=4, top_first=False)
    assert tuple(bottom_first[254, 2]) == palette.LIGHT_ON


def test_charge_and_box_colours():
    c = palette.robot_colours(np.array([0.0, 20.0]), 20.0)
    assert c[0, 0] > c[0, 1] and c[1, 1] > c[1, 0]  # red empty, green full
    b = palette.box_colours(np.array([True, False]))
    assert tuple(b[0]) == palette.BOX_IN and tuple(b[1]) == palette.BOX_OUT


def test_closed_segments_join_the_last_vertex_to_the_first():
    segs = palette.closed_segments(np.array([[0, 0], [1, 0], [0, 1]]), z=0.5)
    assert segs.shape == (3, 2, 3)
    np.testing.assert_allclose(segs[-1, 1], [0, 0, 0.5])


def test_floor_point():
    from sandbox.app.view.floor import floor_point

    assert floor_point((1, 2, 10), (0, 0, -1)) == (1.0, 2.0)
    x, y = floor_point((0, 0, 10), (1, 1, -10))
    assert (x, y) == pytest.approx((1.0, 1.0))
    assert floor_point((0, 0, 10), (1, 0, 0)) is None  # parallel to the floor
    assert floor_point((0, 0, 10), (0, 0, 1)) is None  # looking up


# ------------------------------------------------------- the app, no browser
class FakeClient:
    def __init__(self):
        self.client_id = -1  # never one of the server's: what the app starts for a page ends at once
        self.notes = []
        self.camera = type("Camera", (), {"update_timestamp": 1.0, "aspect": 1.0, "position": None,
                                          "look_at": None, "fov": None})()

    def atomic(self):
        import contextlib

        return contextlib.nullcontext()

    def add_notification(self, title, body, **kwargs):
        self.notes.append((title, body, kwargs.get("color")))


@pytest.fixture
def app():
    from sandbox.commands.serve import App, free_port

    # The simulation in this process: what these tests check does not depend on where it runs
    # (test_the_simulation_runs_in_another_process does), and a child costs 1.3 s of CPU to start.
    a = App(SMALL, port=free_port(), fps=60, steps_per_frame=2, process=False)
    a.start()
    yield a
    a.stop()


def test_upload_validation_leaves_the_simulation_alone(app):
    client = FakeClient()
    assert not app.panel.shape.use_shape_file("bowtie.txt", b"0 0\n1 1\n1 0\n0 1\n", client)
    assert client.notes[-1][0] == "File received, shape not used" and "crosses itself" in client.notes[-1][1]
    assert not app.panel.shape.use_shape_file("two.txt", b"0 0\n1 1\n", client)
    assert "at least 3" in client.notes[-1][1]
    assert not app.panel.shape.use_shape_file("bin.txt", b"\x00\xff", client)
    assert not app.panel.shape.use_shape_file("deep.json", b"[" * 100_000 + b"]" * 100_000, client)
    assert client.notes[-1][0] == "File received, shape not used" and client.notes[-1][1].startswith("deep.json")
    assert not app.panel.shape.use_shape_file("huge.txt", b"0 0\n1e308 0\n0 1e308\n", client)
    assert "too large" in client.notes[-1][1]
    assert app.runner.latest.shape_name == "circle"
    step = app.runner.latest.step
    wait_until(lambda: app.runner.latest.step > step)
    assert app.panel.shape.use_shape_file("../../tri.geojson",
                                    b'{"type": "Polygon", "coordinates": [[[0,0],[2,0],[1,2],[0,0]]]}', client)
    wait_until(lambda: app.runner.latest.shape_name == "tri.geojson")
    assert len(app.runner.latest.goal_vertices) == 3
    svg = b'<svg xmlns="http://www.w3.org/2000/svg"><polygon points="0,0 10,0 10,4 0,4"/></svg>'
    assert app.panel.shape.use_shape_file("box.svg", svg, client)
    assert app.panel.shape.use_shape_file("t.wkt", b"POLYGON((0 0, 4 0, 4 3, 0 0))", client)
    wait_until(lambda: app.runner.latest.shape_name == "t.wkt")


def test_using_a_goal_starts_it_afresh_with_the_same_seed(app):
    """Issue 40, item 1: a goal used (drawn, a template, an upload, a pick) starts a new world on it
    from step 0 with the same seed; the outline and strategies go back to auto and off unless kept."""
    runner, shape, strategies = app.runner, app.panel.shape, app.panel.strategies
    client = FakeClient()
    app.events.call(strategies.controls["switch"][0].__setattr__, "value", True)  # a strategy on, by hand
    wait_until(lambda: runner.latest.strategies["switch"] > 0, what="switch on")
    wait_until(lambda: runner.latest.step > 100, what="a while of the circle")  # past a new world's 50
    seed, world = runner.latest.seed, runner.latest.world_key
    square = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])
    app.events.call(shape.use, square, "square.txt", client)
    snap = wait_until(lambda: runner.latest.world_key != world and runner.latest, what="a new world")
    assert snap.shape_name == "square.txt" and snap.seed == seed and snap.step < 50
    assert snap.strategies["switch"] == 0 and snap.config.outline == "auto"
    assert not strategies.controls["switch"][0].value and strategies.outline.value == "auto"
    wait_until(lambda: client.notes, what="the notice")
    title, body = client.notes[-1][:2]
    assert title == "Goal changed" and f"from step 0 with seed {seed}" in body and "strategies off" in body
    assert app.panel.metrics.marks[-1] == (0, "shape square.txt")
    # Kept: the strategies stay as the user set them.
    app.events.call(strategies.controls["switch"][0].__setattr__, "value", True)
    wait_until(lambda: runner.latest.strategies["switch"] > 0, what="switch on again")
    app.events.call(shape.keep.__setattr__, "value", True)
    world = runner.latest.world_key
    app.events.call(shape.use, square * 1.5, "bigger.txt", client)
    snap = wait_until(lambda: runner.latest.world_key != world and runner.latest, what="another new world")
    assert snap.shape_name == "bigger.txt" and snap.strategies["switch"] > 0 and snap.seed == seed
    wait_until(lambda: "kept" in client.notes[-1][1], what="the notice saying so")
    # A goal refused (it does not fit the arena) leaves the running world alone.
    world = runner.latest.world_key
    sliver = np.array([[0.0, 0.0], [1000.0, 0.0], [1000.0, 0.01], [0.0, 0.01]])  # too long for the arena
    app.events.call(shape.use, sliver, "sliver.txt", client)
    wait_until(lambda: client.notes[-1][0] == "Shape not used", what="the refusal")
    assert runner.latest.world_key == world and runner.latest.shape_name == "bigger.txt"


def test_a_paper_case_starts_the_case_and_the_dropdown_shows_what_runs(app):
    """Issue 24, item 2: picking a case resets the world with it (same seed, step 0); the dropdown
    shows the case that runs, or custom."""
    from sandbox.app.panel.strategies import CUSTOM

    runner, folder = app.runner, app.panel.strategies
    client = FakeClient()
    assert folder.case.value == "circle"
    wait_until(lambda: runner.latest.step > 100, what="the circle to run a while")  # past a new world's 50
    seed, world = runner.latest.seed, runner.latest.world_key
    folder.use_case("star-switch", client)
    snap = wait_until(lambda: runner.latest.world_key != world and runner.latest, what="a new world")
    assert snap.shape_name == "star" and snap.strategies["switch"] == 0.25 and snap.seed == seed
    assert snap.step < 50, "a case starts from step 0"
    refresh = lambda: app.events.call(app.panel.update, runner.latest, True)  # noqa: E731
    wait_until(lambda: refresh() or folder.case.value == "star-switch")
    # The chart's mark comes with the reset's answer, which can follow the new world's first frame.
    wait_until(lambda: app.panel.metrics.marks[-1:] == [(0, "case star-switch")], what="the case's mark")
    # A strategy changed by hand: no longer one of the seven.
    folder.controls["no_corners"][0].value = True
    wait_until(lambda: refresh() or folder.case.value == "star-switch-nocorners",
               what="the case with no corners")
    folder.controls["switch"][0].value = False
    wait_until(lambda: refresh() or folder.case.value == CUSTOM, what="custom")
    assert not client.notes, client.notes


def test_one_parameter_group_and_the_charts_picked_are_on_the_page(app):
    """Issue 41, first visit: a new page builds every control it is sent before it shows anything, so
    only one group of parameters and the charts picked are shown (viser sends hidden ones, but its page
    builds nothing for them); a chart shown while paused gets the whole run at once."""
    parameters, metrics, runner = app.panel.parameters, app.panel.metrics, app.runner

    def groups_shown() -> list[str]:
        return [title for title, folder in parameters.group_folders.items() if folder.visible]

    def charts_shown() -> list[str]:
        return [attr for attr in ("chart_goal", "chart_dist", "chart_charged") if getattr(metrics, attr).visible]

    assert groups_shown() == ["Population and bodies"] and parameters.group.value == "Population and bodies"
    assert len(parameters.group_folders) == 8 and len(parameters.controls) == 62
    app.events.call(parameters.group.__setattr__, "value", "Robot: gains and energy")
    wait_until(lambda: groups_shown() == ["Robot: gains and energy"], what="the robot's group alone")
    assert charts_shown() == ["chart_goal"]
    wait_until(lambda: len(runner.series()) >= 3, what="a few samples")
    app.events.call(app.comparison.lockstep.set_playing, False)
    wait_until(lambda: not runner.latest.playing, what="paused")
    assert metrics.chart_charged.data[0].tolist() == [0.0, 0.0]  # hidden: never sent
    app.events.call(metrics.choice.__setattr__, "value", "all three")
    wait_until(lambda: charts_shown() == ["chart_goal", "chart_dist", "chart_charged"], what="three charts")
    samples = runner.series()
    wait_until(lambda: metrics.chart_charged.data[0][-1] == samples[-1].step, what="the run on the new chart")
    assert len(metrics.chart_charged.data[0]) == len(samples)
    app.events.call(metrics.choice.__setattr__, "value", "none")
    wait_until(lambda: charts_shown() == [], what="no chart")
    with pytest.raises(ValueError, match="no chart choice"):
        metrics.show_charts("pie")
    with pytest.raises(ValueError, match="no parameter group"):
        parameters.show_group("Colours")


def test_metrics_csv_and_frames(app):
    wait_until(lambda: app.frames_drawn > 5 and len(app.runner.series()) >= 2)
    lines = app.panel.metrics.csv().splitlines()
    assert lines[0] == "step,fraction_in_goal,mean_outside_distance,boxes_escaped,charged_robots,cycle,phase,time"
    assert len(lines) >= 3
    assert not app.runner.errors


def test_recording_from_the_panel(app):
    app.events.call(app.panel.record.start)
    assert app.panel.record._floor_legend is not None  # the replay's legend, on the floor while recording
    frames = app.frames_drawn
    wait_until(lambda: app.frames_drawn > frames + 5)
    html = app.events.call(app.panel.record.stop)
    assert "__VISER_EMBED_DATA__" in html
    assert app.panel.record.recorder is None and app.panel.record._floor_legend is None


def test_serve_command_line_checks_its_flags(capsys):
    from sandbox.commands import main

    assert main(["serve", "--port", "70000"]) == 2
    assert "--port" in capsys.readouterr().err
    assert main(["serve", "--shape", "no-such-shape"]) == 2
    assert "not a built-in shape" in capsys.readouterr().err


def test_serve_defaults_to_this_machine_only():
    from sandbox.commands import build_parser

    args = build_parser("serve").parse_args(["serve"])
    assert args.host == "127.0.0.1" and args.port == 8080


# ------------------------------------------------- the simulation's own process
def where_am_i(sim) -> int:
    """A command: the id of the process it runs in."""
    import os

    return os.getpid()


@pytest.fixture(scope="module")
def process_runner():
    from sandbox.app.world.child import ProcessRunner

    r = ProcessRunner(SMALL, shape=None, fps=60, steps_per_frame=2)
    r.start()
    yield r
    r.stop()


def sandbox_modules_loaded(sim) -> set[str]:
    """The modules loaded in the process that runs ``sim`` (a module-level function: it pickles)."""
    import sys

    return {name for name in sys.modules if name.startswith("sandbox")}


def test_the_simulation_runs_in_another_process(process_runner):
    import functools
    import os

    from sandbox.model.simulation import Simulation

    r = process_runner
    assert r.call(Apply(where_am_i)) == r.process.pid != os.getpid()
    step = r.latest.step
    wait_until(lambda: r.latest.step > step + 10)
    seen = []
    r.ask(Apply(functools.partial(Simulation.update_config, robots=-1)), on_error=seen.append)
    wait_until(lambda: seen)
    assert "robots" in str(seen[0])
    r.submit(SetPlaying(False))
    wait_until(lambda: not r.latest.playing)
    paused_at = r.latest.step
    r.ask(StepOnce(3))
    wait_until(lambda: r.latest.step == paused_at + 3)
    r.ask(Reset(5))
    wait_until(lambda: r.latest.seed == 5 and r.latest.step == 0)
    wait_until(lambda: [s.step for s in r.series()] == [0])
    r.submit(SetPlaying(True))
    wait_until(lambda: len(r.series()) >= 2)


def test_ctrl_c_is_for_the_app_not_its_simulation_process(process_runner):
    """A terminal's Ctrl-C reaches the whole process group: the simulation process goes on (the app
    stops it), instead of dying with a KeyboardInterrupt traceback."""
    import os
    import signal

    r = process_runner
    os.kill(r.process.pid, signal.SIGINT)
    step = r.latest.step
    wait_until(lambda: r.latest.step > step + 10)
    assert r.process.is_alive()


def test_simulation_processes_are_forked_from_one_warmed_up_server(process_runner):
    """On Linux the app's simulation processes come from multiprocessing's fork server, which
    imported the model and loaded the compiled kernels once (sandbox.warm)."""
    import sys

    from sandbox.processes import simulation_context

    if sys.platform != "linux":
        pytest.skip("the fork server is what Linux offers; elsewhere a fresh interpreter starts")
    assert simulation_context().get_start_method() == "forkserver"
    assert process_runner.process._popen.__class__.__module__ == "multiprocessing.popen_forkserver"
    assert "sandbox.warm" in process_runner.call(Apply(sandbox_modules_loaded))


def test_a_crashed_simulation_process_is_reported_and_restarted(process_runner):
    import os
    import signal

    r = process_runner
    crashes = []
    r.on_crash(crashes.append)
    r.submit(Follow((2,)))
    r.ask(Reset(9))
    wait_until(lambda: r.latest.seed == 9 and r.latest.robot(2) is not None)
    old, world = r.process.pid, r.latest.world_key
    os.kill(old, signal.SIGKILL)  # as a crash in the engine would end it
    wait_until(lambda: crashes, timeout=30)
    assert "exit code" in crashes[0]
    wait_until(lambda: r.process.pid != old and r.process.is_alive(), timeout=60)
    step = r.latest.step
    wait_until(lambda: r.latest.step > step + 10 or r.latest.step < step, timeout=30)  # running again
    assert r.latest.seed == 9 and r.restarts == 1
    assert r.latest.world_key > world  # the restarted world is a newer one (what waits on a world can tell)
    wait_until(lambda: r.latest.robot(2) is not None)  # what was followed came back


def test_with_no_viewer_for_a_while_the_app_pauses_and_a_viewer_resumes_it():
    from sandbox.commands.serve import App, free_port

    a = App(SMALL, port=free_port(), fps=60, steps_per_frame=2, idle_pause_seconds=1.0, process=False)
    a.start()
    try:
        wait_until(lambda: a.auto_paused and not a.runner.playing, timeout=15)
        step = paused_step(a.runner)  # a frame already on its way from the engine may still land
        frames_pass(a.runner)
        assert a.runner.latest.step == step
        from tests.viser_wire import RawClient

        page = RawClient(a.port)  # a browser's websocket: viser calls the app's on-connect
        try:
            page.say_hello()
            wait_until(lambda: a.runner.playing and a.runner.latest.step > step)
            assert set(a.panel.inspector.viewers) == set(a.server.get_clients())  # its own inspector
        finally:
            page.close()
        wait_until(lambda: not a.panel.inspector.viewers, what="the page's inspector gone with it")
    finally:
        a.stop()


def test_charts_are_sent_only_when_new_and_thinned():
    from types import SimpleNamespace

    from sandbox.app.panel.metrics import CHART_POINTS, MetricsFolder, chart_indices

    assert chart_indices(5, 300).tolist() == [0, 1, 2, 3, 4]
    thinned = chart_indices(10_000, 300)
    assert len(thinned) == 300 and thinned[0] == 0 and thinned[-1] == 9_999

    class Chart:
        sends = 0

        def __setattr__(self, name, value):
            Chart.sends += 1
            object.__setattr__(self, name, value)

    series = [SimpleNamespace(step=100 * k, fraction_in_goal=0.5, mean_outside_distance=1.0, charged_robots=3)
              for k in range(5000)]
    runner = SimpleNamespace(series=lambda: series)
    folder = MetricsFolder(None, runner)
    folder.text, folder.chart_goal, folder.chart_dist, folder.chart_charged = Chart(), Chart(), Chart(), Chart()
    snap = SimpleNamespace(sample=SimpleNamespace(fraction_in_goal=0.5, mean_outside_distance=1.0, charged_robots=3,
                                                  boxes_escaped=0), world_config=SimpleNamespace(robots=10, capacity=20.0),
                           robot_charges=np.array([0.0, 5.0, 15.0]))
    folder.update(snap)
    sent = Chart.sends
    assert len(folder.chart_goal.data[0]) == CHART_POINTS and folder.chart_goal.data[0][-1] == 499_900
    folder._charted_at = 0.0  # as if a period had passed: the same series is not sent again
    folder.update(snap)
    assert Chart.sends == sent + 1  # only the text


def test_the_live_app_runs_without_a_deadline():
    r = Runner(SMALL, shape=None, playing=False)
    assert r.sim.controller.deadline is None


def test_a_recording_is_named_after_what_runs_and_when():
    from datetime import datetime
    from types import SimpleNamespace

    from sandbox.app.panel.recording import recording_name

    when = datetime(2026, 12, 1, 9, 5)
    case = SimpleNamespace(shape_name="star", strategies={"switch": 0.25, "flare": 0.0}, family="scaled")
    assert recording_name(case, when) == "phototaxis-star-switch-2026-12-01-0905.html"
    drawn = SimpleNamespace(shape_name="my L (v2).svg", strategies={"chase": 2.0}, family="offset")
    assert recording_name(drawn, when) == "phototaxis-my-L-v2-chase-2026-12-01-0905.html"
    assert recording_name(None, when) == "phototaxis-run-2026-12-01-0905.html"


def test_strategy_tooltips_are_short_plain_words():
    """Issue 24, item 8: at most two lines (about 200 characters) and no config names."""
    from sandbox.model.config import STRATEGIES, param_names

    for s in STRATEGIES:
        assert 0 < len(s.tip) <= 200, s.name
        assert s.label in s.tip, f"{s.name}: the tip names the panel's label"
        assert not any(name in s.tip for name in param_names() if "_" in name), s.tip


def test_classroom_waits_at_step_0_and_lays_pages_out_for_a_projector():
    """Issue 24, item 5: serve --classroom starts paused at step 0; a new page gets the presenter
    layout (its panel folded, the construction area framed with the legend on its floor); the View
    buttons lay one page out as the construction area, the whole arena or the presenter's."""
    from sandbox.app.panel.framing import CONSTRUCTION, PRESENTER, WHOLE_ARENA
    from sandbox.app.view.scene import presenter_camera, top_down_camera
    from sandbox.commands.serve import App, free_port
    from tests.viser_wire import RawClient

    app = App(SMALL, port=free_port(), fps=60, steps_per_frame=2, playing=False, whole_arena=False,
              process=False).start()
    first = second = None
    try:
        frames_pass(app.runner, 10)
        assert app.runner.latest.step == 0 and not app.runner.latest.playing
        whole_height = top_down_camera(SMALL)[0][2]
        assert app.server.initial_camera.position[2] < 0.5 * whole_height  # the 16 m area, not the 64 m arena
        first, second = RawClient(app.port), RawClient(app.port)  # as two browsers, 800 x 600 each
        first.say_hello()
        second.say_hello()
        clients = wait_until(lambda: len(app.server.get_clients()) == 2 and app.server.get_clients())
        a, b = (clients[i] for i in sorted(clients))
        framing = app.panel.framing
        assert framing.of(a.client_id) == framing.of(b.client_id) == PRESENTER
        folded = "GuiSetPanelCollapsedMessage"
        assert folded in first.received_types(20.0, until=frozenset({folded}))  # its panel folds to its bar
        wait_until(lambda: a.client_id in framing._legends, what="the legend on the first page's floor")
        # The page's camera is framed by the server's fit thread as the page reports its shape: wait
        # for it to land, or the camera read below may still be the one the page said hello with.
        _, look_at, _ = presenter_camera(app.runner.latest.world_config, a.camera.aspect, framing._legend_aspect)
        wait_until(lambda: np.allclose(a.camera.look_at, look_at), what="the presenter's camera")
        left = framing._legends[a.client_id][0].position[0]
        assert left < SMALL.centre - SMALL.construction_size / 2  # beside the construction area
        presenter_x = a.camera.look_at[0]
        assert presenter_x < SMALL.centre  # centred between the legend and the construction area
        app.events.call(app.panel.run.frame, a, WHOLE_ARENA)
        assert a.camera.position[2] == pytest.approx(top_down_camera(SMALL, a.camera.aspect)[0][2])
        assert a.client_id not in framing._legends and framing.of(b.client_id) == PRESENTER  # b keeps its own
        app.events.call(app.panel.run.frame, a, CONSTRUCTION)
        assert a.camera.position[2] == pytest.approx(top_down_camera(SMALL, a.camera.aspect, whole=False)[0][2])
        assert a.camera.position[2] < 0.5 * whole_height
        app.events.call(framing.toggle_presenter, a)  # the P key
        assert framing.of(a.client_id) == PRESENTER and a.client_id in framing._legends
        assert a.camera.look_at[0] == pytest.approx(presenter_x)
    finally:
        for page in (first, second):
            if page is not None:
                page.close()
        app.stop()


def test_a_page_is_framed_by_events_in_the_order_they_come(monkeypatch):
    """The app's fit of a page's camera and a View button both frame a page, each in one event of the
    app's event thread, from reading the page's view to moving its camera: the view chosen last is the
    one left, whichever came first. Stress run 5 of issue 39 saw the fit's presenter camera land after
    the whole arena chosen meanwhile, when the fit ran in a thread of its own."""
    from types import SimpleNamespace

    from sandbox.app.panel import framing as module
    from sandbox.app.web.events import EventQueue

    framing = module.Framing(SimpleNamespace(latest=SimpleNamespace(world_config=SMALL)), default=module.PRESENTER)
    moves = []
    monkeypatch.setattr(module, "aim_camera", lambda client, *camera: moves.append(
        ("presenter", threading.current_thread().name)))
    monkeypatch.setattr(module, "frame_arena", lambda client, config, whole: moves.append(
        ("whole arena" if whole else "construction area", threading.current_thread().name)))
    monkeypatch.setattr(module, "add_floor_legend", lambda *args, **kwargs: SimpleNamespace(remove=lambda: None))
    panel = SimpleNamespace(minimize=lambda: None, expand=lambda: None)
    page = SimpleNamespace(client_id=1, camera=SimpleNamespace(aspect=800 / 600), scene=None,
                           gui=SimpleNamespace(main_panel=panel))
    events = EventQueue(name="the-event-thread")
    events.post(framing.apply, page)  # the fit, as the page reports its shape
    events.post(framing.choose, page, module.WHOLE_ARENA)  # the View button
    events.post(framing.apply, page)  # the fit again: it reads the view chosen
    events.open()
    try:
        events.call(lambda: None)  # every event before this one has run
    finally:
        events.stop()
    assert moves == [("presenter", "the-event-thread"), ("whole arena", "the-event-thread"),
                     ("whole arena", "the-event-thread")]


def test_parameter_tooltips_are_short_plain_words():
    """Issue 24, item 8: every control of Population and physics has a tooltip of at most two lines
    (about 200 characters) that names no config field; the full reference stays in --help."""
    from sandbox.app.panel.parameters import NOT_IN_PARAMETER_FOLDERS
    from sandbox.app.panel.tips import TIPS, tip
    from sandbox.model.config import param_names, params

    shown = {p.name: p for p in params() if p.name not in NOT_IN_PARAMETER_FOLDERS}
    assert set(TIPS) == set(shown), "a tooltip for every control, and none for a control that is gone"
    config_names = [name for name in param_names() if "_" in name]
    for name, p in shown.items():
        text = tip(name, p.rebuild)
        assert len(text) <= 200, (name, len(text))
        assert not any(config_name in text for config_name in config_names), (name, text)
        assert text.endswith("Applies on Reset." if p.rebuild else "Applies at once.")


def test_the_inspector_says_which_dot_is_which_photocell_and_what_doing_means(runner):
    """Issue 24, item 8: the panel maps the four dots on the floor to the photocells, in their order."""
    from sandbox.app.view import palette as pal
    from sandbox.app.panel.inspector import InspectorFolder

    runner.submit(Follow((0,)))
    snap = wait_until(lambda: runner.latest.robot(0) is not None and runner.latest)
    text = InspectorFolder._text(snap, snap.robot(0))
    rows = [line for line in text.splitlines() if line.startswith("| front") or line.startswith("| back")]
    assert [row.split("|")[1:3] for row in rows] == [
        [f" {name} ", f" {colour} "] for name, colour in zip(("front-left", "front-right", "back-left", "back-right"),
                                                            pal.SENSOR_COLOUR_NAMES)]
    assert len(pal.SENSOR_COLOUR_NAMES) == len(pal.SENSOR_COLOURS) == 4
    assert "**Commanded**" in text and "how it really moves" in text


def test_explain_the_result_says_where_the_strays_lie_and_rings_them(app):
    """Issue 40, item 5: on demand, the share, where the boxes outside the goal lie, what 100 % means,
    what ran; the boxes outside are ringed on the floor until a new world starts."""
    folder = app.panel.result
    wait_until(lambda: app.runner.latest.step > 50, what="a few steps")
    snap = app.runner.latest
    text = app.events.call(folder.explain, snap)
    outside = int((~snap.box_in_goal).sum())
    assert f"({len(snap.box_in_goal) - outside} of {len(snap.box_in_goal)})" in text
    assert f"Of the {outside} boxes outside the goal" in text and "perfect packing" in text
    assert "**Ran:** circle" in text and folder.highlight.value
    assert folder.rings.visible and len(folder.rings.points) == outside
    world = snap.world_key
    app.runner.ask(Reset())
    wait_until(lambda: app.runner.latest.world_key != world, what="a new world")
    wait_until(lambda: not folder.highlight.value and not folder.rings.visible, what="the rings off")
    assert "press *Explain the result* again" in folder.text.content


def test_run_to_the_end_skips_without_frames_then_explains(app):
    """Issue 40, item 4: Run to the end steps to the step asked without frames (progress on the status
    line, which every page shares), then the Result folder explains the final state."""
    folder, result = app.panel.run, app.panel.result
    client = FakeClient()
    app.events.call(app.lockstep.set_playing, False)
    start = paused_step(app.runner)
    seen: list[int] = []
    app.runner.subscribe(lambda snap: seen.append(snap.step))
    app.events.call(folder.skip_ahead, start + 3000, client)
    wait_until(lambda: app.runner.latest.step == start + 3000, what="the end step")
    assert not [step for step in seen if start < step < start + 3000], "no frame on the way"
    wait_until(lambda: result.highlight.value and f"at step {start + 3000:,}" in result.text.content,
               what="the explanation")
    wait_until(lambda: any(note[0] == "Run to the end" for note in client.notes), what="the notice")
    assert not folder.cancel.visible and not folder.run_to_end.disabled
    # Cancelled: the world stays where it got to.
    app.events.call(folder.skip_ahead, 10**7, client)
    wait_until(lambda: (folder._build_fraction or 0) > 0 and "without drawing" in folder.status.content,
               what="the progress line, past the first chunk")
    app.events.call(app.lockstep.cancel)  # the Cancel button: the run to the end it asked for
    wait_until(lambda: folder._skipping is None, what="the stop")
    assert start + 3000 < app.runner.latest.step < 10**7
    # (the notice comes on the event thread just after the run is marked over: waited for, not read at once)
    wait_until(lambda: any(note[0] == "Stopped" for note in client.notes), what="the notice that it stopped")


def test_run_to_the_end_pauses_so_the_floor_stays_on_the_explained_state(app):
    folder = app.panel.run
    client = FakeClient()
    app.events.call(app.lockstep.set_playing, True)
    wait_until(lambda: app.runner.playing, what="playing")
    start = app.runner.latest.step
    app.events.call(folder.skip_ahead, start + 2000, client)
    wait_until(lambda: any(note[0] == "Run to the end" for note in client.notes), what="the notice")
    assert not app.runner.playing and folder.play.label == "Play"
    assert app.runner.latest.step == start + 2000  # where it was sent, and no further


def test_run_to_the_end_right_after_a_reset_explains_the_new_world(app):
    """*Use and run to the end* asks for a reset, then a run to the end: the runner takes both in one turn
    and takes a frame only after them, so the page may hear the run's answer while the last frame is still
    the old world's (on a loaded machine it did). CI failed on this once: the explanation waited on the
    old world and never came."""
    folder, result = app.panel.run, app.panel.result
    client = FakeClient()
    app.events.call(app.lockstep.set_playing, False)
    old = paused_step(app.runner)
    old_world = app.runner.latest.world_key

    arrived = threading.Event()

    def reset_then_run() -> None:  # queued together: the runner takes them in one turn, with no frame
        app.runner.ask(Reset(None))
        folder.skip_ahead(old + 2000, client)
        app.runner.ask(Apply(lambda sim: arrived.wait(30)))  # and its frame only after the page heard the answer

    app.events.call(reset_then_run)
    wait_until(lambda: folder._skipping is None, what="the answer, heard before any frame of the new world")
    arrived.set()
    wait_until(lambda: app.runner.latest.world_key != old_world and app.runner.latest.step == old + 2000,
               what="the new world at the end step")
    wait_until(lambda: f"at step {old + 2000:,}" in result.text.content, what="the explanation")
    assert result.highlight.value
    wait_until(lambda: any(note[0] == "Run to the end" for note in client.notes), what="the notice")


def test_a_run_to_the_end_shows_the_world_it_starts_from(app):
    """A reset and a run to the end taken in one turn publish no frame between them: the run shows its
    starting state first, so the pages show the new goal while it runs, not the old world."""
    folder = app.panel.run
    app.events.call(app.lockstep.set_playing, False)
    old = paused_step(app.runner)
    old_world = app.runner.latest.world_key
    release = threading.Event()

    def reset_then_run() -> None:
        app.runner.ask(Reset(None))
        folder.skip_ahead(old + 1000, FakeClient())
        app.runner.ask(Apply(lambda sim: release.wait(30)))  # no frame after the run until released

    try:
        app.events.call(reset_then_run)
        wait_until(lambda: app.runner.latest.world_key != old_world, what="a frame of the new world")
        assert app.runner.latest.step < old + 1000
    finally:
        release.set()
    wait_until(lambda: folder._skipping is None, what="the end of the run")


def test_a_live_worlds_design_downloads_and_plays_back_bit_for_bit():
    """Issue 40, item 6: the page's design of a live world (its light program as it ran) replays it
    exactly: the same state at the same step (serve --design plays it the same way)."""
    from sandbox.app.world.orders import DesignOf, PlayDesign, SetLamp
    from sandbox.app.world.snapshot import DESIGN_PROGRAM

    live = Runner(SMALL.replace(chase=0.5), shape=None, seed=4)
    live.advance(0)
    live.submit(SetLamp((31.0, 30.0), 3.0))
    live.advance(700)  # a live change of program half-way: the lamp, then back to the paper's lights
    live.submit(SetLamp(None))
    live.advance(500)
    asked = live.submit(DesignOf())
    live.advance(0)
    design = asked.result(10)
    assert design.steps_run == 1200 and len(design.steps) > 3
    replay = Runner(Config(), shape=None, seed=0)
    played = replay.submit(PlayDesign(design))
    replay.advance(0)
    assert played.result(10) == DESIGN_PROGRAM and replay.sim.config == design.config
    replay.advance(1200)
    assert replay.sim.state_digest() == live.sim.state_digest() == design.result["state_digest"]


def test_download_design_sends_one_file_the_cli_can_load(app, tmp_path):
    from sandbox.model.design import load

    sent = []
    client = FakeClient()
    client.send_file_download = lambda name, data, save_immediately=False: sent.append((name, data))
    wait_until(lambda: app.runner.latest.step > 100, what="a few steps")
    app.events.call(app.panel.result.send_design, client)
    wait_until(lambda: sent, what="the file")
    name, data = sent[0]
    assert name.startswith("circle-seed") and name.endswith("-design.npz")
    (tmp_path / name).write_bytes(data)
    design = load(tmp_path / name)
    assert design.steps_run >= 100 and design.patterns.shape[1:] == (64, 64)


def test_the_advisors_best_runs_afresh_to_the_end(app):
    """Issue 40, item 4: Use the best and run to the end: the winner's strategies in a new world with the
    same seed, run to the Run folder's end step without frames, then explained."""
    from sandbox.experiments.advise import Candidate, Ranked

    client = FakeClient()
    advice, run = app.panel.advice, app.panel.run
    best = Candidate("scaled", (("switch", 0.25),))
    advice.results = [Ranked(best, [0.5], [0.1])]
    app.events.call(setattr, run.end_step, "value", 1500)
    world, seed = app.runner.latest.world_key, app.runner.latest.seed
    assert app.events.call(advice.apply_best, client)  # as the button does: the best, then to the end
    app.events.call(advice.run_to_the_end, client)
    snap = wait_until(lambda: app.runner.latest.world_key != world and app.runner.latest.step >= 1500
                      and app.runner.latest, what="a new world at the end step")
    assert snap.seed == seed and snap.strategies["switch"] == 0.25
    wait_until(lambda: "perfect packing" in app.panel.result.text.content, what="the result explained")


def test_the_app_stops_the_panels_workers_through_its_event_queue_and_waits_for_them():
    """App.stop called the advisor's and the challenge's stop from the main thread while the queue ran
    (issue 55). Now their stop is an event, and the app waits (bounded) for the workers it returns to
    end, they posting to the queue as they do, before it stops the queue; a second stop does nothing."""
    from types import SimpleNamespace

    from sandbox.app.web.events import EventQueue
    from sandbox.commands.serve import App

    heard, told = [], threading.Event()
    worker = threading.Thread(target=lambda: told.wait(10) and events.post(heard.append, "the worker's end"),
                              name="a-worker")

    def stop_workers():
        heard.append(("stop", threading.current_thread().name))
        told.set()
        return [worker]

    events = EventQueue(name="the-event-thread").open()
    real_stop = events.stop
    events.stop = lambda: heard.append(("queue stops", worker.is_alive())) or real_stop()
    worker.start()
    app = SimpleNamespace(events=events, panel=SimpleNamespace(stop=stop_workers),
                          comparison=SimpleNamespace(end=lambda: heard.append("comparison ends")),
                          runner=SimpleNamespace(stop=lambda: heard.append("runner stops")),
                          server=SimpleNamespace(stop=lambda: heard.append("server stops")))
    App.stop(app)
    assert heard[0] == ("stop", "the-event-thread")
    assert [what for what in heard[1:] if what != "the worker's end"] == [
        ("queue stops", False), "comparison ends", "runner stops", "server stops"]
    App.stop(app)  # again (a failed start, then the command's own stop): the stopped queue runs nothing
    assert heard.count(("stop", "the-event-thread")) == 1
