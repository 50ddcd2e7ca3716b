"""The baton (sandbox.app.world.baton): a build and the host's scheduler take turns, never run together,
and a build gives the turn back at its first turning point after its slice."""

from __future__ import annotations

import threading
import time

from sandbox.app.world.baton import Baton


def test_a_build_runs_only_in_the_slices_it_is_given():
    baton = Baton()
    running: list[str] = []  # who ran, in order; each appends only while it holds the turn
    steps = []

    def build() -> None:
        for step in range(6):
            running.append("build")
            steps.append(step)
            baton.turning_point()

    baton.begin(build)
    assert baton.building and not steps  # it waits for its first slice
    slices = 0
    while not baton.give(until=0.0):  # a slice already over: one step, then the turn comes back
        slices += 1
        running.append("scheduler")
    assert steps == list(range(6)) and slices == 6 and not baton.building  # (back after its last step too)
    assert running == ["build", "scheduler"] * 6


def test_a_slice_lasts_until_its_end_and_the_scheduler_passes_its_turning_points():
    baton = Baton()
    baton.turning_point()  # the scheduler's own frames pass the same points: nothing happens
    steps = []

    def build() -> None:
        for step in range(300):
            steps.append(step)
            time.sleep(0.0005)
            baton.turning_point()

    baton.begin(build)
    baton.give(until=time.perf_counter() + 0.05)
    assert 0 < len(steps) < 300  # some steps, then back at its next point after the slice
    while not baton.give(until=time.perf_counter() + 1.0):
        pass
    assert len(steps) == 300 and threading.active_count() >= 1 and baton.given > 0.05
