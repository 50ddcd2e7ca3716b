"""Worlds that share a host (sandbox.app.world.host, through HostedRunner): each at its own pace; one
nobody watches pauses, is kept for a reopen, then freed; a long build in one world leaves the others
their pace and says each waiting build's place; one world's failure is its own; a host that dies
restarts its worlds."""

from __future__ import annotations

import os
import signal
import time

import pytest

from sandbox.app.world.child import SimulationCrashed
from sandbox.app.world.host import FREE_AFTER
from sandbox.app.world.hosted import CLASS_FPS, CLASS_STEPS_PER_FRAME, HostedRunner
from sandbox.app.world.orders import Apply, SetPlaying, SetSpeed, SkipAhead
from sandbox.app.world.pool import HostPool
from sandbox.model.config import Config
from tests.waiting import wait_until

#: A small world, quick to build and step: the hosts', the pool's and the class's tests share it.
SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)


@pytest.fixture
def pool():
    pool = HostPool(hosts=1)
    yield pool
    pool.stop()


def hosted(pool: HostPool, **kwargs) -> HostedRunner:
    kwargs.setdefault("fps", 30)
    kwargs.setdefault("steps_per_frame", 3)
    return HostedRunner(SMALL, pool=pool, shape=None, **kwargs).start()


def where_am_i(sim) -> int:
    """A command: the id of the process it runs in."""
    return os.getpid()


def breaks_stepping(sim) -> None:
    """A command: every later step of this world raises (a bug in one world)."""
    def broken(n: int = 1) -> None:
        raise RuntimeError("a bug in this world")
    sim.step = broken


def raises(sim) -> None:
    raise ValueError("this command fails")


def steps_per_second(runners: list[HostedRunner], seconds: float) -> list[float]:
    """Each runner's steps per second over about ``seconds`` (from its frames)."""
    first = [(r.latest.step, time.perf_counter()) for r in runners]
    time.sleep(seconds)  # a measuring window, not a wait for a condition
    return [(r.latest.step - step) / (time.perf_counter() - at) for r, (step, at) in zip(runners, first)]


def test_a_class_world_runs_at_three_times_real_time():
    assert CLASS_FPS * CLASS_STEPS_PER_FRAME * Config().dt == pytest.approx(3.0)
    assert FREE_AFTER == 600.0


def test_worlds_in_one_host_each_step_at_their_own_pace(pool):
    paces = [(30, 3), (20, 2), (10, 1)]  # 90, 40 and 10 steps a second
    runners = [hosted(pool, fps=fps, steps_per_frame=spf) for fps, spf in paces]
    try:
        assert len({r.call(Apply(where_am_i)) for r in runners}) == 1 and len(pool.hosts) == 1
        wait_until(lambda: all(r.latest.step > 0 for r in runners), what="every world to step")
        seen: list[list[float]] = []

        def each_at_its_pace() -> bool:
            seen.append(steps_per_second(runners, 0.6))
            return all(0.7 * fps * spf <= speed <= 1.3 * fps * spf for (fps, spf), speed in zip(paces, seen[-1]))

        # A window at a time: on a loaded machine a world falls behind, then makes up to 2 s of it at up to 4
        # frames' steps a frame (Runner: BEHIND_AT_MOST, CATCH_UP_PER_FRAME); a window of catching up is not
        # its pace. Worlds that all stepped alike (one pace for the host) would never show theirs.
        try:
            wait_until(each_at_its_pace, timeout=20, what="each world at its pace")
        except AssertionError:
            raise AssertionError(f"no window showed each world at its pace {paces}: {seen[-3:]}") from None
    finally:
        for r in runners:
            r.stop()


def test_a_world_nobody_watches_pauses_and_sends_no_frames(pool):
    runner, other = hosted(pool), hosted(pool)
    try:
        runner.watch(False)
        runner.call(Apply(where_am_i))  # answered after the host took the Watch, and after every frame sent before
        paused = (runner.latest.step, runner.frames_published)
        step = other.latest.step
        wait_until(lambda: other.latest.step > step + 20, what="the watched world to go on")
        assert (runner.latest.step, runner.frames_published) == paused
        runner.watch(True)
        wait_until(lambda: runner.latest.step > paused[0], what="the world to step again")
    finally:
        runner.stop()
        other.stop()


def test_a_world_left_is_found_again_by_its_key_until_it_is_freed():
    pool = HostPool(hosts=1, free_after=0.5)
    try:
        runner = hosted(pool, key="student-1")
        runner.call(SkipAhead(500))
        runner.submit(SetSpeed(5))
        runner.submit(SetPlaying(False))
        runner.stop()  # the page is gone: the world pauses, kept
        again = hosted(pool, key="student-1")  # made with playing=True and 3 steps a frame
        assert again.latest.step >= 500 and again.latest.world_key == runner.latest.world_key
        assert not again.controls.playing and again.controls.steps_per_frame == 5  # as the student left it
        wait_until(lambda: not again.latest.playing, what="its frames to say paused")
        again.stop()
        host = pool.hosts[0]
        wait_until(lambda: "student-1" not in host.kept, what="the world to be freed")
        fresh = hosted(pool, key="student-1")
        assert fresh.latest.step < 500  # a new world
        fresh.stop()
    finally:
        pool.stop()


def test_a_world_freed_is_not_kept(pool):
    runner = hosted(pool, key="student-2")
    runner.free()
    wait_until(lambda: pool.worlds() == 0, what="the host to free it")  # at its next housekeeping, within 1 s


def test_a_run_to_the_end_in_one_world_leaves_the_others_their_pace(pool):
    """Before slices, the run to the end held the host: the other world stood still until it was over."""
    busy, other = hosted(pool), hosted(pool)
    try:
        wait_until(lambda: other.latest.step > 30, what="the other world to step")
        step, started = other.latest.step, time.perf_counter()
        arrival = busy.call(SkipAhead(30_000), timeout=60)
        took = time.perf_counter() - started
        stepped = other.latest.step - step
        assert arrival.step == 30_000 and took > 0.3  # long enough to matter
        # Its pace, within a bound: at least half of it on a loaded machine (a host given half a core runs over its
        # slices), less a frame or two in flight; a build in the scheduler's turn left it none until the end.
        assert stepped >= 0.5 * 90 * took - 2 * 3, (stepped, took)
    finally:
        busy.stop()
        other.stop()


def test_each_waiting_build_hears_its_place_in_the_queue(pool):
    runners = [hosted(pool) for _ in range(3)]
    heard: list[list] = [[], [], []]
    try:
        for r, places in zip(runners, heard):
            r.on_queue(places.append)
        futures = [r.submit(SkipAhead(2_000)) for r in runners]
        assert [f.result(60).step for f in futures] == [2_000] * 3
        wait_until(lambda: heard[2][-1:] == [None], what="the last build's turn")
        assert heard == [[], [2, None], [3, 2, None]]
    finally:
        for r in runners:
            r.stop()


def test_one_worlds_failure_leaves_the_others_running(pool):
    broken, other = hosted(pool), hosted(pool)
    halted, other_halted = [], []
    broken.on_halt(halted.append)
    other.on_halt(other_halted.append)
    try:
        with pytest.raises(ValueError, match="this command fails"):
            broken.call(Apply(raises))
        broken.call(Apply(breaks_stepping))
        wait_until(lambda: halted, what="the broken world to halt")
        assert "a bug in this world" in halted[0]
        broken.submit(SetPlaying(False))  # its owner pauses it, as the app does
        step = other.latest.step
        wait_until(lambda: other.latest.step > step + 30, what="the other world to go on")
        assert not other_halted and not other.errors and other.restarts == broken.restarts == 0
    finally:
        broken.stop()
        other.stop()


def test_a_world_that_cannot_be_built_fails_alone(pool):
    """Its runner says why, as a process runner whose child could not build its first world; the host and
    its other worlds go on."""
    other = hosted(pool)
    try:
        with pytest.raises(SimulationCrashed, match="the world could not be built"):
            HostedRunner(SMALL, pool=pool, shape=[[0.0, 0.0], [1.0, 0.0]])  # a goal with no area
        step = other.latest.step
        wait_until(lambda: other.latest.step > step + 10, what="the host's other world to go on")
        assert other.restarts == 0 and pool.worlds() == 1
    finally:
        other.stop()


def test_a_host_that_dies_restarts_each_of_its_worlds(pool):
    runners = [hosted(pool) for _ in range(2)]
    crashes: list[str] = []
    try:
        for r in runners:
            r.restart_pause = 0.05
            r.on_crash(crashes.append)
        pid = runners[0].process.pid
        assert runners[1].process.pid == pid
        os.kill(pid, signal.SIGKILL)
        wait_until(lambda: all(r.restarts == 1 for r in runners), what="both worlds to restart")
        steps = [r.latest.step for r in runners]
        wait_until(lambda: all(r.latest.step > s + 10 for r, s in zip(runners, steps)), what="both to step again")
        assert len(crashes) == 2 and all("killed" in why for why in crashes)
        assert {r.process.pid for r in runners} != {pid}
    finally:
        for r in runners:
            r.stop()
