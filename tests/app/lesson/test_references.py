"""The class challenge's reference runs, shared (issue 58): one run a world for the whole class, in one
pool, not a process pool a student. Without processes: the pool is a stand-in that answers at once, and
the gathering's timer fires when the test says."""

from __future__ import annotations

from concurrent.futures import Future
from types import SimpleNamespace

import numpy as np

from sandbox.app.lesson import references
from sandbox.model.challenge import Gain, paper_gain, paper_gains
from sandbox.model.config import Config
from tests.waiting import wait_until


class Events:
    """The app's event queue, run at once on the calling thread; timers wait for ``fire()``."""

    def __init__(self):
        self.timers = []

    def post(self, fn, *args):
        fn(*args)

    def submit(self, fn, *args):
        done: Future = Future()
        done.set_result(fn(*args))
        return done

    def after(self, seconds, fn, *args):
        self.timers.append((fn, args))

    def fire(self):
        timers, self.timers = self.timers, []
        for fn, args in timers:
            fn(*args)


class Pool:
    """A process pool whose run scores each step asked: the step's tenth brought in, of 20 boxes."""

    made: list["Pool"] = []

    def __init__(self, processes):
        self.processes, self.runs, self.closed = processes, [], False
        Pool.made.append(self)

    def apply_async(self, fn, args, callback, error_callback):
        assert fn is paper_gains
        self.runs.append(args[2])
        callback({step: Gain(2, 2 + step // 10, 20) for step in args[2]})

    def close(self):
        self.closed = True


def class_references(monkeypatch, processes: int = 2) -> tuple[references.References, Events]:
    Pool.made = []
    monkeypatch.setattr(references, "simulation_context", lambda: SimpleNamespace(Pool=Pool))
    events = Events()
    return references.References(events, processes=processes), events


def test_rounds_in_one_world_share_one_run_at_each_ones_step(monkeypatch):
    refs, events = class_references(monkeypatch)
    square, star = (Config(), 1, "square"), (Config(), 1, "star")
    heard = []
    for student, (spec, step) in enumerate([(square, 450), (square, 450), (square, 459), (star, 450)]):
        refs.ask(spec, step, lambda gain, s=student: heard.append((s, gain.brought)), heard.append)
    assert heard == [] and len(events.timers) == 2  # gathering: one timer a world
    events.fire()
    wait_until(lambda: len(heard) == 4, what="the runs (their pool started in a worker)")
    assert sorted(heard) == [(0, 45), (1, 45), (2, 45), (3, 45)]  # 459 // 10 == 45 too
    assert refs.runs == 2 and sorted(run for pool in Pool.made for run in pool.runs) == [[450], [450, 459]]
    assert all(pool.closed for pool in Pool.made) and refs._pool is None  # nothing waits: its processes end
    refs.ask(square, 459, lambda gain: heard.append(("later", gain.brought)), heard.append)  # known: at once
    assert heard[-1] == ("later", 45) and refs.runs == 2 and not events.timers


def test_a_class_that_stopped_answers_why_and_starts_nothing(monkeypatch):
    refs, events = class_references(monkeypatch)
    refs.stop()
    why = []
    refs.ask((Config(), 1, "square"), 450, lambda gain: why.append(gain), why.append)
    assert why == ["the app stopped"] and not events.timers and not Pool.made


def test_one_run_gives_the_paper_gain_at_every_step_asked():
    config = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
    shape = np.array([[60.0, 60.0], [68.0, 60.0], [68.0, 68.0], [60.0, 68.0]])
    gains = paper_gains(config, 3, [40, 25, 40], shape)
    assert gains == {25: paper_gain(config, 3, 25, shape), 40: paper_gain(config, 3, 40, shape)}
