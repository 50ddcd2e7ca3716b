"""Compare mode (issue 25, item 1): two worlds from the same seed, held on the same step, drawn side by
side; and the runner's hold and run-to that carry the lockstep."""

from __future__ import annotations

from concurrent.futures import Future

import numpy as np
import pytest

from sandbox.app.web.events import EventQueue
from sandbox.app.world.lockstep import COMPARE_CASES, LEAD_FRAMES, SAME, Lockstep, partner_config, side_config
from sandbox.app.world.orders import Hold, Reset, RunTo, SetLamp, SetPlaying, SetSpeed
from sandbox.app.world.runner import Runner
from sandbox.app.world.snapshot import LAMP_PROGRAM, PAPER_PROGRAM
from sandbox.model.config import CASES, Config, ConfigError
from tests.shown import shown
from tests.waiting import wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)


def started(config: Config, **kwargs) -> Runner:
    return Runner(config, fps=60, steps_per_frame=5, **kwargs).start()


def test_a_held_runner_stops_at_the_held_step_and_runs_to_a_step_while_paused():
    runner = started(SMALL, playing=False)  # held before it plays: a runner that played first had passed 40
    try:
        runner.submit(Hold(40))
        runner.submit(SetPlaying(True))
        wait_until(lambda: runner.latest.step == 40, what="the runner to reach the held step")
        frame = runner.latest.frame
        wait_until(lambda: runner.latest.frame >= frame + 5, what="five more frames")
        assert runner.latest.step == 40  # playing, but held
        runner.submit(SetPlaying(False))
        runner.ask(RunTo(73))
        wait_until(lambda: runner.latest.step == 73, what="the runner to run to step 73")
        runner.ask(RunTo(50))  # behind it: nothing
        frame = runner.latest.frame
        wait_until(lambda: runner.latest.frame >= frame + 3, what="three more frames")
        assert runner.latest.step == 73
    finally:
        runner.stop()


def test_steps_allowed_by_a_hold_are_counted_by_hand():
    runner = Runner(SMALL, steps_per_frame=25)
    assert runner._steps_allowed(25) == 25  # no hold
    runner.submit(Hold(10))
    assert runner._steps_allowed(25) == 10  # at step 0: ten to go
    runner.advance(10)
    assert runner._steps_allowed(25) == 0
    runner.submit(Hold(None))
    assert runner._steps_allowed(25) == 25


def test_the_lead_is_six_frames_of_steps_by_hand():
    """The target lies LEAD_FRAMES (6) frames ahead of the slower world: 6 x 25 = 150 steps at the default
    speed; at the fastest setting, 6 frames at the measured rate (3,000 steps/s at 30 frames/s: 600),
    and never under two chunks of 10."""

    class Main:
        steps_per_frame, fps = 25, 30.0

        def subscribe(self, listener):
            pass

        def steps_per_second(self):
            return 3000.0

    main = Main()
    lockstep = Lockstep(main, EventQueue())
    assert lockstep._lead() == 150
    main.steps_per_frame = 100  # FASTEST
    assert lockstep._lead() == 600
    main.steps_per_second = lambda: 10.0
    assert lockstep._lead() == 20


class World:
    """A runner as the lockstep sees it: its frames' listeners, its newest frame, what it was sent."""

    def __init__(self, step: int):
        from types import SimpleNamespace

        self.latest = SimpleNamespace(step=step, world_key=0)
        self.listeners, self.submitted = [], []
        self.playing, self.steps_per_frame = True, 5

    def subscribe(self, listener):
        self.listeners.append(listener)

    def submit(self, command):
        self.submitted.append(command)


class Posted:
    """The app's event queue, held: what waits on it, the newest of each kind only (as post_latest)."""

    def __init__(self):
        self.waiting = {}

    def post_latest(self, key, fn, *args):
        self.waiting[key] = (fn, args)


def test_frames_only_post_the_lockstep_to_the_event_queue():
    """Issue 55: the lockstep ran on both worlds' receiving threads under a lock of its own. Their frames
    now post its work to the app's event queue, where it owns its state: no lock, and nothing done on a
    runner's thread."""
    import threading

    events, main, partner = Posted(), World(100), World(90)
    lockstep = Lockstep(main, events)
    lockstep.pair(partner)
    main.submitted.clear(), partner.submitted.clear()
    for world in (main, partner, main):  # frames, as the runners' threads hand them over
        world.listeners[0](world.latest)
    assert lockstep.target == 0 and not main.submitted and not partner.submitted
    assert list(events.waiting) == [lockstep]  # one raise of the target waits, however many frames came
    fn, args = events.waiting.pop(lockstep)
    fn(*args)  # the event thread runs it
    assert lockstep.target == 90 + LEAD_FRAMES * 5  # a lead ahead of the slower world
    assert main.submitted == partner.submitted == [Hold(120)]
    locks = (type(threading.Lock()), type(threading.RLock()))
    assert not [name for name, value in vars(lockstep).items() if isinstance(value, locks)]


def test_the_right_curve_is_read_at_the_left_worlds_steps_by_hand():
    """Each world samples at the end of its own frames: the right one's samples at 0, 100 and 210 (values
    0, 10, 32), read at the left's 0, 105, 205 and 305: 0; 10 + 22 x 5/110 = 11; 10 + 22 x 105/110 = 31;
    and nothing past its last sample."""
    from sandbox.app.panel.metrics import curve_at

    read = curve_at(np.array([0, 105, 205, 305], np.float32), np.array([0, 100, 210]), np.array([0.0, 10.0, 32.0]))
    assert np.allclose(read[:3], [0.0, 11.0, 31.0]) and np.isnan(read[3])
    assert np.isnan(curve_at(np.array([0.0, 5.0]), np.array([]), np.array([]))).all()


def test_partner_config_takes_the_cases_goal_and_strategies_and_nothing_else():
    base = Config(robots=50, flare=1.5, chase=2.0, outline="offset", seed=7)
    switch = partner_config(base, "star-switch")
    assert (switch.shape, switch.switch, switch.flare, switch.chase, switch.no_corners) == ("star", 0.25, 0, 0, 0)
    assert switch.outline == "auto" and switch.robots == 50 and switch.seed == 7  # the rest as it was
    assert partner_config(base, "star + chase").chase == 2.0
    assert partner_config(base, SAME) is base
    with pytest.raises(ConfigError, match="cannot compare with 'hexagon'"):
        partner_config(base, "hexagon")
    assert set(CASES) < set(COMPARE_CASES)


def test_a_side_is_a_case_or_a_config_file(tmp_path):
    values = tmp_path / "crowd.toml"
    values.write_text("robots = 90\nflare = 1.2\n")
    side = side_config(str(values), Config(boxes=300))
    assert (side.robots, side.flare, side.boxes) == (90, 1.2, 300)
    assert side_config("square-flare", Config()).flare == 1.75
    with pytest.raises(ConfigError, match="neither"):
        side_config(str(tmp_path / "missing.toml"), Config())


class OnTheQueue:
    """The lockstep as the app drives it: every call, and every read, on the app's event thread."""

    def __init__(self, lockstep: Lockstep, events: EventQueue):
        self._lockstep, self._events = lockstep, events

    def __getattr__(self, name: str):
        value = self._events.call(getattr, self._lockstep, name)
        if not callable(value):
            return value
        return lambda *args, **kwargs: self._events.call(lambda: value(*args, **kwargs))


@pytest.fixture
def pair():
    events = EventQueue().open()  # the runners' answers come there too, as in the app
    main = started(SMALL.replace(shape="star"), deliver=events.post)
    partner = started(partner_config(SMALL.replace(shape="star"), "star-switch"), seed=main.latest.seed,
                      playing=False, deliver=events.post)
    lockstep = Lockstep(main, events)
    events.call(lockstep.pair, partner)
    yield OnTheQueue(lockstep, events), main, partner
    events.stop()
    main.stop()
    partner.stop()


def _reset(lockstep: OnTheQueue, seed=None) -> None:
    done = []
    lockstep.reset(seed, on_done=done.append, on_error=done.append)
    wait_until(lambda: done, what="both worlds rebuilt")
    assert not isinstance(done[0], BaseException), done[0]


def test_both_worlds_start_from_the_same_layout(pair):
    lockstep, main, partner = pair
    lockstep.set_playing(False)
    _reset(lockstep)
    wait_until(lambda: main.latest.step == partner.latest.step == 0
               and main.latest.world_key == partner.latest.world_key == 1, what="both new worlds drawn")
    a, b = main.latest, partner.latest
    assert a.seed == b.seed
    assert np.array_equal(a.robot_positions, b.robot_positions) and np.array_equal(a.box_positions, b.box_positions)
    assert a.strategies["switch"] == 0 and b.strategies["switch"] == 0.25  # what differs: the strategy
    _reset(lockstep, seed=1234)  # a new seed: both get it
    wait_until(lambda: main.latest.seed == partner.latest.seed == 1234 and main.latest.world_key == 2
               and partner.latest.world_key == 2, what="both worlds with the new seed")
    assert np.array_equal(main.latest.robot_positions, partner.latest.robot_positions)


def test_playing_worlds_stay_within_the_lead_and_pause_on_the_same_step(pair):
    lockstep, main, partner = pair
    _reset(lockstep)
    lockstep.set_playing(True)
    lead = LEAD_FRAMES * main.steps_per_frame
    gaps = []
    for _ in range(30):
        frame = main.latest.frame
        wait_until(lambda: main.latest.frame > frame, what="a frame")
        gaps.append(abs(main.latest.step - partner.latest.step))
    assert main.latest.step > 50 and max(gaps) <= lead + main.steps_per_frame
    lockstep.set_playing(False)
    wait_until(lambda: main.latest.step == partner.latest.step == lockstep.target and not main.latest.playing,
               what="both paused on the target step")
    paused_at = main.latest.step
    lockstep.step_once(10)
    wait_until(lambda: main.latest.step == partner.latest.step == paused_at + 10, what="both stepped 10")


def test_worlds_shown_every_third_frame_go_on_in_step(pair):
    # Both worlds' snapshots thinned (sandbox.app.web.pacing: every page draws slowly): each frame of either
    # still raises the target, so neither stalls for the other's rarer frames, and a pause lands both on
    # one step.
    lockstep, main, partner = pair
    _reset(lockstep)
    lockstep.show_every(3)
    assert main.controls.show_every == partner.controls.show_every == 3
    lockstep.set_playing(True)
    wait_until(lambda: min(main.latest.step, partner.latest.step) >= 20 * main.steps_per_frame,
               what="both worlds twenty frames on")
    lockstep.set_playing(False)
    wait_until(lambda: main.latest.step == partner.latest.step == lockstep.target and not main.latest.playing,
               what="both paused on the target step")
    lockstep.show_every(1)
    assert main.controls.show_every == partner.controls.show_every == 1


def test_a_slow_world_sets_the_pace(pair):
    lockstep, main, partner = pair
    _reset(lockstep)
    partner.submit(SetSpeed(1))  # as if its machine were five times slower
    lockstep.set_playing(True)
    wait_until(lambda: partner.latest.step >= 40, what="the slow world to step")
    assert main.latest.step <= partner.latest.step + LEAD_FRAMES * main.steps_per_frame + main.steps_per_frame


def test_unpaired_the_running_world_goes_on_alone(pair):
    lockstep, main, partner = pair
    lockstep.set_playing(True)
    assert lockstep.unpair() is partner and main.hold_at is None
    step = main.latest.step
    wait_until(lambda: main.latest.step > step + 100, what="the running world to go on")


# ------------------------------------------------------------------ in the app
@pytest.fixture
def comparing_app():
    from sandbox.commands.serve import App, free_port

    app = App(SMALL.replace(shape="star"), port=free_port(), fps=60, steps_per_frame=5, process=False,
              compare=(partner_config(SMALL, "star-switch"), "star-switch")).start()
    yield app
    app.stop()


def test_the_app_draws_both_worlds_and_charts_both(comparing_app):
    app = comparing_app
    partner = app.comparison.runner
    assert partner is not None and app.panel.framing.offset == (SMALL.arena_size + 6.0, 0.0)
    wait_until(lambda: app.panel.compare.choice.value == "star-switch", what="the dropdown to show the comparison")
    names = {handle.name for handle in app.comparison.view.handles.values()}
    assert {"/compare", "/compare/swarm/robots", "/compare/caption", "/compare/goal"} <= names
    wait_until(lambda: partner.latest.step >= 300 and app.runner.latest.step >= 300, what="both worlds to run")
    app.panel.metrics._charted_at = 0.0
    app.events.call(app.panel.update, app.runner.latest, True)
    labels = [series["label"] for series in app.panel.metrics._series_shown["chart_goal"]]
    assert labels == ["step", "in goal: star (left)", "star-switch (right)", "change"]
    data = app.panel.metrics.chart_goal.data
    assert len(data) == 4 and np.isfinite(data[2]).sum() >= 2  # the right world's curve, at the same steps
    assert "**Right** star-switch" in shown(app.panel.compare.status.content)
    assert "**Right** (star-switch): **in goal**" in shown(app.panel.metrics.text.content)
    # The CSV holds both worlds' samples, each row led by its world.
    rows = app.panel.metrics.csv().splitlines()
    assert rows[0].startswith("world,step,") and rows[0].endswith(",time")
    worlds = {row.split(",")[0] for row in rows[1:]}
    assert worlds == {"left: star", "right: star-switch"}
    app.events.call(app.panel.compare.choose, "nothing", None)
    wait_until(lambda: app.comparison.runner is None and app.panel.framing.offset is None,
               what="the comparison to end and the pages to frame one world")
    assert app.runner.hold_at is None and partner.stopped and not app.comparison.view
    app.panel.metrics._charted_at = 0.0
    app.events.call(app.panel.update, app.runner.latest, True)
    assert [s["label"] for s in app.panel.metrics._series_shown["chart_goal"]] == ["step", "in goal", "change"]
    assert app.panel.metrics.csv().startswith("step,") and "Right" not in app.panel.metrics.text.content


def test_learns_show_me_runs_the_case_without_and_with_the_strategy(comparing_app):
    app = comparing_app
    app.events.call(app.panel.show_me, "square", "square-flare", None)
    wait_until(lambda: app.comparison.label == "square-flare" and app.runner.latest.shape_name == "square",
               what="square beside square-flare")
    a, b = app.runner.latest, app.comparison.runner.latest
    assert (a.strategies["flare"], b.strategies["flare"], b.shape_name) == (0.0, 1.75, "square")
    assert app.panel.compare.choice.value == "square-flare"
    # The compared world steps only in step with this one: once it has played, both run from the same
    # start (this world's square may have run alone for a moment, between the case and the comparison).
    wait_until(lambda: app.comparison.runner.latest.step > 100, what="the worlds to play")
    apart = abs(app.runner.latest.step - app.comparison.runner.latest.step)
    assert apart <= (LEAD_FRAMES + 1) * app.runner.steps_per_frame


def test_compare_with_the_same_world_under_the_papers_lights():
    from sandbox.commands.serve import App, free_port

    app = App(SMALL, port=free_port(), fps=60, steps_per_frame=5, process=False).start()
    try:
        app.runner.ask(SetLamp((32.0, 32.0), 6.0))
        app.events.call(app.panel.compare.choose, SAME, None)
        wait_until(lambda: app.comparison.runner is not None, what="the second world")
        wait_until(lambda: app.comparison.runner.latest.world_key == app.runner.latest.world_key == 1,
                   what="both worlds restarted")
        a, b = app.runner.latest, app.comparison.runner.latest
        assert (a.program, b.program) == (LAMP_PROGRAM, PAPER_PROGRAM)  # the player's lamp against the paper
        assert b.config == a.config and b.shape_name == a.shape_name and b.seed == a.seed
    finally:
        app.stop()


def test_serve_compare_refuses_what_it_cannot_compare():
    from tests.commands.test_cli import phototaxis

    unknown = phototaxis("serve", "--compare", "star", "hexagon", "--port", "0")
    assert unknown.returncode == 2 and "--compare takes two case names" in unknown.stderr
    assert len(unknown.stderr.strip().splitlines()) == 1
    both = phototaxis("serve", "--compare", "star", "star-switch", "--case", "circle", "--port", "0")
    assert both.returncode == 2 and "leave out --case" in both.stderr
    missing = phototaxis("serve", "--compare", "star")
    assert missing.returncode == 2 and "--compare" in missing.stderr


def test_bench_live_compare_with_refuses_what_is_not_a_case():
    from tests.commands.test_cli import phototaxis

    result = phototaxis("bench", "--live", "--compare-with", "hexagon")
    assert result.returncode == 2 and "--compare-with takes a case" in result.stderr


def test_when_the_compared_worlds_process_dies_compare_mode_ends_and_says_so():
    import os
    import signal

    from sandbox.commands.serve import App, free_port

    app = App(SMALL, port=free_port(), fps=30, steps_per_frame=5, keep_running=True,
              compare=(partner_config(SMALL, "square-flare"), "square-flare")).start()
    try:
        told = []
        app.comparison._on_crash = lambda why: (told.append(why), app._on_partner_crash(why))
        partner = app.comparison.runner
        os.kill(partner.process.pid, signal.SIGKILL)
        wait_until(lambda: app.comparison.runner is None and app.panel.framing.offset is None,
                   what="compare mode to end")
        assert told and partner._stop.is_set() and not partner.process.is_alive() and app.runner.hold_at is None
        wait_until(lambda: app.panel.compare.choice.value == "nothing", what="the dropdown to say so")
        step = app.runner.latest.step
        wait_until(lambda: app.runner.latest.step > step + 50, what="the running world to go on")
    finally:
        app.stop()


def test_a_challenge_round_in_compare_mode_plays_the_paper_beside_the_player():
    """Issue 25, item 3: the round's world and the paper's, side by side from the round's seed; both
    stop together at the round's end."""
    from sandbox.commands.serve import App, free_port
    from sandbox.model.challenge import ROUND_SEED

    app = App(SMALL, port=free_port(), fps=60, steps_per_frame=5, process=False).start()
    try:
        app.events.call(app.panel.compare.choose, SAME, None)
        wait_until(lambda: app.comparison.runner is not None, what="the second world")
        folder, partner = app.panel.challenge, app.comparison.runner
        folder.round_steps = 150
        app.events.call(folder.start, "Ada", None)
        wait_until(lambda: folder.round is not None and folder.round.score is not None, what="the round's end")
        wait_until(lambda: not partner.latest.playing and partner.latest.step == app.runner.latest.step,
                   what="both worlds stopped on one step")
        assert partner.latest.seed == app.runner.latest.seed == ROUND_SEED
        assert (app.runner.latest.program, partner.latest.program) == (LAMP_PROGRAM, PAPER_PROGRAM)
        assert app.runner.latest.step >= 150
        wait_until(lambda: folder.round.paper is not None, what="the paper's reference score")
    finally:
        app.stop()


def test_a_refused_reset_leaves_both_worlds_going_on_in_step(pair):
    lockstep, main, partner = pair
    _reset(lockstep)
    lockstep.set_playing(True)
    wait_until(lambda: partner.latest.step > 60, what="both playing")
    key = partner.latest.world_key
    real_submit = main.submit

    def refusing(command):
        if not isinstance(command, Reset):
            return real_submit(command)
        refused: Future = Future()
        refused.set_exception(RuntimeError("refused"))
        return refused

    main.submit = refusing
    errors = []
    lockstep.reset(None, on_error=errors.append)
    main.submit = real_submit
    wait_until(lambda: errors, what="the refusal")
    assert [str(e) for e in errors] == ["refused"]
    step = partner.latest.step
    wait_until(lambda: partner.latest.step > step + 40, what="the worlds to go on")
    assert partner.latest.world_key == key  # the compared world was not rebuilt alone
    lockstep.set_playing(False)
    wait_until(lambda: main.latest.step == partner.latest.step == lockstep.target and not main.latest.playing, what="paused in step")


def _pick_as_viser_does(handle, value, refresh, events) -> None:
    """What viser does with a page's pick: the value is set on its event loop, the callback runs later on
    the app's ``events``. ``refresh()`` is a panel refresh that falls in between."""
    from unittest import mock

    import viser

    handle._impl.value = value
    refresh()
    page = mock.MagicMock(name="the page's client")  # told what happens (notifications); not a browser
    for callback in handle._impl.update_cb:
        events.call(callback, viser.GuiEvent(client=page, client_id=0, target=handle))


def test_a_pick_survives_a_panel_refresh_before_its_callback():
    """Under two test suites at once, a refresh between viser's setting of the value and the callback put
    the old value back; the callback read it, and the pick was lost (Compare with... started no second
    world; Paper case restarted the running case). Both dropdowns now keep a pick on its way."""
    from sandbox.commands.serve import App, free_port

    app = App(SMALL, port=free_port(), fps=30, steps_per_frame=2, process=False).start()
    try:
        panel = app.panel
        refresh = lambda: app.events.call(panel.update, app.runner.latest, True)  # noqa: E731
        _pick_as_viser_does(panel.compare.choice, "star-switch", refresh, app.events)
        wait_until(lambda: app.comparison.label == "star-switch" and app.comparison.runner is not None,
                   what="the second world")
        refresh()
        assert panel.compare.choice.value == "star-switch"
        _pick_as_viser_does(panel.strategies.case, "square", refresh, app.events)
        wait_until(lambda: app.runner.latest.shape_name == "square", what="the square case")
        refresh()
        assert panel.strategies.case.value == "square"
        app.events.call(panel.compare.choose, "nothing", None)  # ended elsewhere: the dropdown follows what runs
        wait_until(lambda: app.comparison.runner is None, what="the comparison to end")
        refresh()
        assert panel.compare.choice.value == "nothing"
        assert not app.runner.errors
    finally:
        app.stop()


def test_the_compare_worker_posts_its_status_and_touches_nothing_of_the_folder():
    """A worker starts the second world (it blocks for a second or two); the folder's status line, its
    flags and the comparison's adoption are the event thread's. The worker wrote the status itself
    (issue 55): now it posts the change, and the event thread makes it, in the order posted."""
    import threading
    from types import SimpleNamespace

    from sandbox.app.panel.compare import NOTHING, CompareFolder
    from sandbox.app.web.events import EventQueue

    writes, began = [], []

    class Status:
        def __init__(self):
            self._content = ""

        @property
        def content(self):
            return self._content

        @content.setter
        def content(self, text):
            writes.append((text, threading.current_thread().name))
            self._content = text

    comparison = SimpleNamespace(runner=None, label=None, stacked=False,
                                 begin=lambda config, shape, label, stacked: began.append(label))
    events = EventQueue(name="the-event-thread")  # not served yet: what the worker posts waits its turn
    folder = CompareFolder(None, SimpleNamespace(latest=SimpleNamespace(config=SMALL)), comparison,
                           on_change=lambda what: writes.append((what, threading.current_thread().name)),
                           events=events)
    folder.status, folder.choice = Status(), SimpleNamespace(value=NOTHING)
    folder._starting = True  # as choose() leaves it, on the event thread
    folder._choose("star-switch", None, False)  # the worker's work, here on the test's thread
    assert began == ["star-switch"] and writes == [] and folder._starting  # started; nothing changed here
    events.open()
    try:
        events.call(lambda: None)  # what the worker posted has run
    finally:
        events.stop()
    assert writes == [("Starting the second world...", "the-event-thread"),
                      ("compare: star-switch", "the-event-thread")]
    assert not folder._starting
