"""A challenge that teaches (issue 41, item 6): the score counts the boxes brought into the goal, the
lamp starts where the robots are, and a hint comes after a while without progress."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import numpy as np
import pytest

from sandbox.app.panel.challenge import HINT, ChallengeFolder
from sandbox.app.world.snapshot import LAMP_PROGRAM, PAPER_PROGRAM
from sandbox.model.challenge import Gain, lamp_start, paper_gain
from sandbox.model.config import Config
from tests.inline_events import InlineEvents
from tests.shown import shown
from tests.waiting import wait_until


def test_a_gain_counts_only_the_boxes_brought_in():
    assert Gain(started=27, ended=27, boxes=80).share == 0.0  # doing nothing scores nothing
    gain = Gain(started=20, ended=50, boxes=80)
    assert gain.brought == 30 and gain.share == 0.5
    assert Gain(started=20, ended=15, boxes=80).brought == -5  # pushed out
    assert Gain(started=80, ended=80, boxes=80).share == 0.0  # nothing left to bring


def test_the_lamp_starts_on_the_densest_group_of_robots_not_their_centroid():
    rng = np.random.default_rng(1)
    group = np.array([50.0, 12.0]) + rng.uniform(-1, 1, (12, 2))
    scattered = rng.uniform(0, 64, (30, 2))
    robots = np.vstack([scattered, group])
    x, y = lamp_start(robots, radius=2.5)
    assert np.hypot(x - 50, y - 12) < 1.5, (x, y)
    assert any(np.allclose((x, y), r) for r in robots)  # on a robot
    many = np.vstack([rng.uniform(0, 64, (50_000, 2)), np.array([8.0, 56.0]) + rng.uniform(-1, 1, (5_000, 2))])
    assert np.hypot(*(np.array(lamp_start(many, 2.5)) - [8, 56])) < 1.5  # a large swarm: sampled, in time
    with pytest.raises(ValueError, match="no robots"):
        lamp_start(np.zeros((0, 2)), 2.5)


def test_the_lamp_starts_on_the_floor_every_page_shows():
    """Issue 56, item 13: the densest group lay under the folded panel's bar, or off a phone's edge. Within
    a box, the densest group of the robots in it; with none in it, the densest group's robot moved onto
    its edge."""
    crowd = [(60.0, 30.0), (60.5, 30.0), (61.0, 30.0)]  # out of the box: the densest
    pair = [(30.0, 30.0), (30.5, 30.0)]  # in it
    box = (21.3, 43.7, 21.3, 43.7)
    assert lamp_start(np.array(crowd + pair), 2.5) in crowd
    assert lamp_start(np.array(crowd + pair), 2.5, within=box) in ((30.0, 30.0), (30.5, 30.0))
    assert lamp_start(np.array(crowd + [(45.0, 35.0)]), 2.5, within=box) == (43.7, 35.0)  # within reach: on the edge
    assert lamp_start(np.array(crowd), 2.5, within=box) == (43.7, 30.0)  # none near it: the densest, on its edge


def test_in_the_papers_world_doing_nothing_scores_nothing():
    """Issue 41: 'doing nothing scores about 33 %': a third of the paper's scattered boxes start in the goal."""
    gain = paper_gain(Config(), 0, 0, None)
    assert gain.boxes == 500 and gain.started > 100  # 167 at seed 0
    assert gain.brought == 0 and gain.share == 0.0


class Markdown:
    content = ""


def frame(step, in_goal, world=2, program=LAMP_PROGRAM, robots=((25.0, 25.0), (25.5, 25.0), (38.0, 38.0))):
    """A frame of the default world (its construction view is x and y 21.3-43.7 m; less the lamp's 1 m,
    22.3-42.7): a pair of robots and one alone, all in view."""
    boxes = np.zeros(10, bool)
    boxes[:in_goal] = True
    return SimpleNamespace(step=step, box_in_goal=boxes, world_key=world, program=program,
                           robot_positions=np.array(robots), world_config=Config())


def challenge_folder(reset, playing, events, lamps):
    """A challenge folder over stand-ins: a runner whose last frame is world 1's (the lamp lit at once,
    each centre kept in ``lamps``) and a lockstep whose ``reset`` is given (``playing`` hears play and pause)."""
    runner = SimpleNamespace(latest=frame(500, 0, world=1, program=PAPER_PROGRAM),
                             ask=lambda lamp, on_done, on_error: (lamps.append(lamp.centre), on_done(None)))
    lockstep = SimpleNamespace(set_playing=playing, reset=reset)
    lamp = SimpleNamespace(radius=SimpleNamespace(value=1.0))
    folder = ChallengeFolder(None, runner, lockstep, lamp, on_change=lambda what: None, events=events)
    folder.status, folder.hint, folder.scores = Markdown(), Markdown(), Markdown()
    return folder


def a_round(hint_seconds=10.0):
    """A challenge folder over stand-ins for the runner and the lockstep, a round begun in world 2."""
    timers, lamps, playing = InlineEvents(), [], []
    folder = challenge_folder(lambda seed, on_done, on_error: on_done(2), playing.append, timers, lamps)
    folder.round_steps, folder.hint_seconds = 10_000, hint_seconds
    folder.start("Ada", None)
    assert lamps == [] and playing == [False]  # the old world's frame: nothing begins on it
    folder.update(frame(0, 3, program=PAPER_PROGRAM))  # the round's world, at step 0
    return folder, timers, lamps, playing


def test_a_round_lights_the_robots_counts_from_its_start_and_hints_after_no_progress():
    folder, timers, lamps, playing = a_round(hint_seconds=10.0)
    assert lamps in ([(25.0, 25.0)], [(25.5, 25.0)]) and playing == [False, True]  # on the pair, then playing
    assert folder.round.started == 3
    assert [t.due for t in timers.timers] == [10.0]
    folder.update(frame(100, 3))
    assert "0 boxes brought in" in folder.status.content and folder.hint.content == ""
    assert timers.pass_time() == 1  # ten seconds and no box brought in
    assert folder.hint.content == HINT
    folder.update(frame(200, 5))  # two boxes in: the hint goes and waits again
    assert folder.hint.content == "" and "2 boxes brought in" in shown(folder.status.content)
    folder.update(frame(300, 4))  # one out again: no progress, the wait goes on
    assert len(timers.timers) == 1
    folder.update(frame(400, 6))
    assert len([t for t in timers.timers if not t.cancelled]) == 1  # each progress re-arms one wait
    folder.runner.ask = lambda command, on_done, on_error: None  # the paper's reference run: not here
    folder.update(frame(10_000, 7))  # the round's end: the wait is cancelled
    assert folder.round.score == Gain(3, 7, 10) and timers.pass_time() == 0 and folder.hint.content == ""


def test_a_round_abandoned_takes_its_hint_with_it():
    folder, timers, _, _ = a_round()
    folder.update(frame(100, 3, world=3))
    assert folder.round is None and "abandoned" in shown(folder.status.content)
    assert timers.pass_time() == 0 and folder.hint.content == ""


def test_a_round_begins_on_its_own_world_not_on_one_an_earlier_reset_built():
    """CI failed once here (compare mode, a challenge started while the pairing's reset was still in
    flight): the round began on the pairing's world, published between the round's start and its
    reset's answer, and was abandoned at the round world's first frame: no score, ever."""
    lamps = []

    def reset(seed, on_done, on_error):
        folder.runner.latest = frame(0, 1, world=2, program=PAPER_PROGRAM)  # the earlier reset's world, meanwhile
        on_done(3)  # the round's world: 3

    folder = challenge_folder(reset, lambda playing: None, InlineEvents(), lamps)
    folder.start("Ada", None)
    assert lamps == [] and folder.round.world is None  # not on world 2
    folder.update(frame(0, 4, world=3, program=PAPER_PROGRAM))
    assert len(lamps) == 1 and folder.round.world == 3 and folder.round.started == 4
    folder.update(frame(50, 4, world=3))
    assert folder.round is not None and "step 50" in shown(folder.status.content)


# ------------------------------------------------- the reference run's pool: the event thread's (issue 55)
class Pools:
    """multiprocessing's context as the challenge uses it, with pools that say on which thread each was
    set going, closed or terminated. ``Pool()`` waits until :attr:`release` is set (starting a pool blocks)."""

    def __init__(self):
        self.asked, self.release = threading.Event(), threading.Event()
        self.made = []

    def context(self):
        return SimpleNamespace(Pool=self.pool)

    def pool(self, processes):
        self.asked.set()
        self.release.wait(10)
        self.made.append(FakePool())
        return self.made[-1]


class FakePool:
    """A pool that records what is done to it, and on which thread; its answer is the test's to give."""

    def __init__(self):
        self.calls, self.answer = [], None

    def _heard(self, what):
        self.calls.append((what, threading.current_thread().name))

    def apply_async(self, fn, args, callback, error_callback):
        self._heard("apply")
        self.answer = callback

    def close(self):
        self._heard("close")

    def terminate(self):
        self._heard("terminate")


@pytest.fixture
def reference(monkeypatch):
    """A finished round's folder on a real event queue (served), its pools the test's."""
    from sandbox.app.panel import challenge as module
    from sandbox.app.panel.challenge import Round
    from sandbox.app.web.events import EventQueue

    pools = Pools()
    monkeypatch.setattr(module, "simulation_context", pools.context)
    events = EventQueue(name="the-event-thread").open()
    folder = ChallengeFolder(None, None, None, None, on_change=lambda what: None, events=events)
    folder.status, folder.hint, folder.scores = Markdown(), Markdown(), Markdown()
    r = Round("Ada", 100, world=1, started=2, most=5, score=Gain(2, 5, 10), at_step=100)
    yield folder, r, pools, events
    pools.release.set()
    events.stop()


def test_the_reference_pool_is_handed_to_the_event_thread_which_hears_its_answer_and_ends_it(reference):
    folder, r, pools, events = reference
    pools.release.set()
    events.call(folder._score_the_paper, r, (Config(), 0, None))
    wait_until(lambda: pools.made and pools.made[0].answer is not None, timeout=10, what="the run set going")
    pool = pools.made[0]
    pool.answer(Gain(2, 4, 10))  # the pool's answer, on the pool's own thread
    events.call(lambda: None)
    assert pool.calls == [("apply", "the-event-thread"), ("close", "the-event-thread")]
    assert "You beat it!" in folder.status.content and folder.best == {"Ada": 0.375}
    assert events.call(lambda: folder._pools) == {}


def test_a_stop_ends_a_running_reference_on_the_event_thread_and_the_round_counts(reference):
    """The pool was set on the worker and read by stop() on another thread (issue 55): now only the event
    thread holds it, and stop (an event) terminates it there, once."""
    folder, r, pools, events = reference
    pools.release.set()
    events.call(folder._score_the_paper, r, (Config(), 0, None))
    wait_until(lambda: pools.made and pools.made[0].answer is not None, timeout=10, what="the run set going")
    for starter in events.call(folder.stop):  # its worker only started the pool: it is done, or nearly
        starter.join(10)
    assert pools.made[0].calls == [("apply", "the-event-thread"), ("terminate", "the-event-thread")]
    assert "no reference: the app stopped" in shown(folder.status.content) and folder.best == {"Ada": 0.375}


def test_a_pool_started_after_the_stop_is_ended_when_handed_over_and_never_runs(reference):
    folder, r, pools, events = reference
    events.call(folder._score_the_paper, r, (Config(), 0, None))
    assert pools.asked.wait(10)  # the worker is starting its pool
    starters = events.call(folder.stop)
    assert [thread.name for thread in starters] == ["challenge-reference"]  # for the app to wait for
    pools.release.set()
    starters[0].join(10)
    assert pools.made[0].calls == [("terminate", "the-event-thread")]
    assert "no reference: the app stopped" in shown(folder.status.content)


def test_a_pool_started_after_the_queue_stopped_is_ended_by_its_worker(reference):
    folder, r, pools, events = reference
    events.call(folder._score_the_paper, r, (Config(), 0, None))
    assert pools.asked.wait(10)
    starters = [thread for thread in threading.enumerate() if thread.name == "challenge-reference"]
    events.stop()  # nobody will take the pool: the worker that started it ends it
    pools.release.set()
    for thread in starters:
        thread.join(10)
    assert pools.made[0].calls == [("terminate", "challenge-reference")]


def test_a_round_lasts_about_a_minute_at_the_default_pace_as_the_page_says():
    """Issue 56, item 13: a round of 20,000 steps lasted 27-29 s where the docs said about a minute. The
    round is the minute: its steps at `serve`'s default pace (steps a frame times frames a second)."""
    import inspect
    from pathlib import Path

    from sandbox.commands.serve import App
    from sandbox.model.challenge import ROUND_STEPS

    defaults = inspect.signature(App).parameters
    per_second = defaults["steps_per_frame"].default * defaults["fps"].default
    assert 55 <= ROUND_STEPS / per_second <= 65, ROUND_STEPS / per_second
    docs = " ".join((Path(__file__).resolve().parents[3] / "docs" / "browser.md").read_text(encoding="utf-8").split())
    assert f"{ROUND_STEPS:,} steps" in docs and "about a minute" in docs
