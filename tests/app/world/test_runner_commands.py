"""Typed commands (sandbox.app.world.orders): each written once, with what it does; every future settled;
a cancel stops the build it names and no other.

Whoever submits a command gets a future that resolves or fails: a stopped runner fails what it had not
carried out, a crashed child fails what it owed, and a command sent while the child is swapped reaches
the new child or fails at once. Stopping a process runner in the middle of a restart leaves no process.
"""

from __future__ import annotations

import functools
import inspect
import os
import signal
import threading
import time
from concurrent.futures import wait

import pytest

from sandbox.app.world import orders as commands
from sandbox.app.world.orders import (Apply, Arrival, Build, BuildCancelled, CancelBuild, Command, Control, Reset,
                                      RunnerStopped, Setting, SetOutline, SkipAhead, StepOnce)
from sandbox.app.world.child import ProcessRunner, SimulationCrashed
from sandbox.app.world.hosted import HostedRunner
from sandbox.app.world.pool import HostPool
from sandbox.app.world.runner import Runner
from sandbox.model.config import Config
from tests.waiting import wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
COMMANDS = [kind for _, kind in inspect.getmembers(commands, inspect.isclass)
            if issubclass(kind, Command) and kind not in (Command, Control, Setting, Build)]


def where_am_i(sim) -> int:
    """A command: the id of the process it runs in."""
    return os.getpid()


def blocks_until(sim, path: str) -> None:
    """A command that keeps the simulation busy until ``path`` exists (a long command)."""
    while not os.path.exists(path):
        time.sleep(0.01)


@pytest.mark.parametrize("kind", COMMANDS, ids=lambda kind: kind.__name__)
def test_every_command_says_what_it_does(kind):
    assert kind.carry_out is not Command.carry_out, f"{kind.__name__} has no carry_out: nothing carries it out"
    if issubclass(kind, Setting) and kind is not Setting:
        assert kind.settle is not Setting.settle, f"{kind.__name__} sets no control"


def test_the_runner_offers_its_commands_all_that_they_may_use():
    runner = Runner(SMALL, shape=None)
    wanted = {name for name in (*commands.World.__annotations__, *vars(commands.World)) if not name.startswith("_")}
    assert wanted and not [name for name in sorted(wanted) if not hasattr(runner, name)]


def test_a_stopped_runner_fails_every_command_it_had_not_carried_out():
    runner = Runner(SMALL, shape=None)  # not started: the commands wait for the loop
    heard: list[BaseException] = []
    futures = [runner.ask(Reset(3), on_error=heard.append), runner.ask(SetOutline("offset"), on_error=heard.append),
               runner.ask(Apply(where_am_i), on_error=heard.append), runner.ask(StepOnce(2))]
    runner.stop()
    assert all(isinstance(f.exception(timeout=0), RunnerStopped) for f in futures)
    assert len(heard) == 3 and all(isinstance(e, RunnerStopped) for e in heard)
    late = runner.ask(Reset(4), on_error=heard.append)
    assert isinstance(late.exception(timeout=0), RunnerStopped) and len(heard) == 4
    assert not runner.errors  # stopping is no error of the commands'


def test_callbacks_go_through_deliver_when_given():
    handed: list = []
    runner = Runner(SMALL, shape=None, deliver=handed.append)
    built, progress = [], []
    runner.on_progress(progress.append)
    future = runner.ask(Reset(5), on_done=built.append)
    runner.advance(1)
    assert future.done() and not built and not progress  # handed over, not called on the runner's thread
    for thunk in handed:
        thunk()
    assert built == [runner.latest.world_key] and progress and progress[-1] is None


def test_a_command_that_raises_fails_its_future_and_the_loop_goes_on():
    runner = Runner(SMALL, shape=None, fps=60, steps_per_frame=2).start()
    try:
        refused = runner.submit(commands.UpdateConfig({"robots": -1}))
        assert "robots" in str(refused.exception(timeout=10))
        step = runner.latest.step
        wait_until(lambda: runner.latest.step > step, what="steps after the refusal")
    finally:
        runner.stop()


# ------------------------------------------------------------------ a cancel belongs to its build
# Issue 55: a cancel was one flag of the runner's. Set just after a run to the end ended, it stopped the
# next one at its first step; a Reset cleared it as it started, so a cancel that waited its turn behind
# the reset was lost. Now a cancel names its build. A runner that was not started carries out what
# waits at call(), in order, on this thread: both orders below are run as they are written.
def _nothing(sim) -> None:
    return None


def test_a_cancel_that_comes_after_its_run_to_the_end_leaves_the_next_one_alone():
    runner = Runner(SMALL, shape=None, playing=False)
    first = SkipAhead(300)
    assert runner.call(first) == Arrival(300, False, runner.world_key)
    runner.submit(CancelBuild(first.build))  # pressed as it ended: too late, and for that one only
    assert runner.call(SkipAhead(700)) == Arrival(700, False, runner.world_key)


def test_a_reset_keeps_the_cancel_of_the_run_to_the_end_behind_it():
    runner = Runner(SMALL, shape=None, playing=False)
    world = runner.world_key
    skip = SkipAhead(500)
    built, arrived = runner.submit(Reset()), runner.submit(skip)  # Use and run to the end
    runner.submit(CancelBuild(skip.build))  # while both wait their turn
    runner.call(Apply(_nothing))
    assert built.result(0) == world + 1  # not the one cancelled: built
    assert arrived.result(0) == Arrival(0, True, world + 1)  # stopped before its first step


def test_a_cancel_of_a_reset_waiting_its_turn_stops_it_and_nothing_after_it():
    runner = Runner(SMALL, shape=None, playing=False)
    world, seed = runner.world_key, runner.sim.seed
    reset = Reset(seed + 1)
    built, arrived = runner.submit(reset), runner.submit(SkipAhead(400))
    runner.submit(CancelBuild(reset.build))
    runner.call(Apply(_nothing))
    with pytest.raises(BuildCancelled):
        built.result(0)
    assert runner.world_key == world and runner.sim.seed == seed  # the old world goes on
    assert arrived.result(0) == Arrival(400, False, world)


def test_a_cancel_during_a_build_stops_it_and_one_after_it_does_nothing():
    runner = Runner(SMALL, shape=None, playing=False)
    skip = SkipAhead(10_000)
    runner.on_progress(lambda fraction: fraction is not None and runner.submit(CancelBuild(skip.build)))
    arrival = runner.call(skip)
    assert arrival.cancelled and 0 < arrival.step < 10_000  # stopped after its first chunk, where it got to
    runner.submit(CancelBuild(skip.build))
    assert not runner._builds  # over: nothing of it is kept


# ------------------------------------------------------------------ one owner of play
def test_a_frame_that_fails_halts_the_world_and_leaves_play_to_its_owner(monkeypatch):
    """Issue 55: the loop wrote ``controls.playing`` as the settings do. Now it writes no control: a frame
    that fails halts the world (its frames say paused) and the on_halt listener, which owns play, decides;
    its SetPlaying lifts the halt."""
    runner = Runner(SMALL, shape=None, steps_per_frame=5)
    told: list[str] = []
    runner.on_halt(told.append)
    real_step = runner.sim.step
    monkeypatch.setattr(runner.sim, "step", lambda n=None: (_ for _ in ()).throw(RuntimeError("a bug")))
    runner._frame_on_schedule(time.perf_counter(), 1 / 30)
    assert runner.controls.playing and len(told) == 1 and "a bug" in told[0]  # nothing written: the owner is told
    assert isinstance(runner.errors[-1], RuntimeError)
    monkeypatch.setattr(runner.sim, "step", real_step)
    runner._frame_on_schedule(time.perf_counter(), 1 / 30)
    assert runner.sim.steps_done == 0 and not runner.latest.playing  # halted: no step, and it says paused
    runner.submit(commands.SetPlaying(False))  # the owner pauses, as the app does (App: on_halt)
    runner.submit(commands.SetPlaying(True))  # and later plays again
    runner._frame_on_schedule(time.perf_counter(), 1 / 30)
    assert runner.sim.steps_done == 5 and runner.latest.playing and len(told) == 1


# ------------------------------------------------------------------ process runner
@pytest.fixture
def only_process_runner():
    runner = ProcessRunner(SMALL, shape=None, fps=60, steps_per_frame=2)
    runner.start()
    yield runner
    runner.stop()


@pytest.fixture(params=["process", "hosted"])
def process_runner(request):
    """A runner whose world runs in another process: a child of its own, or a world host's (which the
    proxy sees as its child: the same tests hold for both)."""
    pool = HostPool(hosts=1)
    if request.param == "process":
        runner = ProcessRunner(SMALL, shape=None, fps=60, steps_per_frame=2)
    else:
        runner = HostedRunner(SMALL, pool=pool, shape=None, fps=60, steps_per_frame=2)
    runner.start()
    yield runner
    runner.stop()
    pool.stop()


def test_stopping_fails_every_call_the_process_owes(process_runner, tmp_path):
    runner = process_runner
    heard: list[BaseException] = []
    released = tmp_path / "released"  # after the stop (a host's other worlds wait behind a busy one)
    busy = runner.submit(Apply(functools.partial(blocks_until, path=str(released))))
    owed = [runner.ask(Reset(1), on_error=heard.append), runner.ask(Apply(where_am_i), on_error=heard.append), busy]
    runner.stop(timeout=1)
    done, pending = wait(owed, timeout=10)
    assert not pending and all(isinstance(f.exception(), RunnerStopped) for f in owed)
    wait_until(lambda: len(heard) == 2, timeout=10, what="both callers to hear")
    assert not runner.process.is_alive()
    released.touch()


@pytest.mark.slow
def test_a_call_made_while_the_child_is_swapped_is_answered_or_refused(process_runner):
    runner = process_runner
    runner.restart_pause = 0.05
    old = runner.call(Apply(where_am_i))
    futures, stop = [], threading.Event()

    def keep_calling() -> None:
        while not stop.is_set():
            futures.append(runner.submit(Apply(where_am_i)))
            time.sleep(0.002)  # a steady stream of calls across the crash and the restart

    caller = threading.Thread(target=keep_calling)
    caller.start()
    try:
        os.kill(old, signal.SIGKILL)
        wait_until(lambda: runner.restarts == 1 and any(f.done() and not f.exception() and f.result() != old
                                                        for f in list(futures)),
                   what="a call answered by the new process")
    finally:
        stop.set()
        caller.join()
    done, pending = wait(futures, timeout=30)
    assert not pending, f"{len(pending)} of {len(futures)} calls never settled"
    outcomes = {f.result() if f.exception() is None else type(f.exception()) for f in futures}
    assert outcomes <= {old, runner.process.pid, SimulationCrashed}


@pytest.mark.slow
def test_stopping_during_the_pause_before_a_restart_starts_no_process(process_runner):
    runner = process_runner
    runner.restart_pause = 60.0
    crashes: list[str] = []
    runner.on_crash(crashes.append)
    os.kill(runner.process.pid, signal.SIGKILL)
    wait_until(lambda: crashes, what="the crash to be reported")
    refused = runner.submit(Reset())  # no process to take it: refused at once, not kept for ever
    assert "restarting" in str(refused.exception(timeout=0))
    started = time.monotonic()
    runner.stop()
    assert time.monotonic() - started < 10  # the pause does not hold the stop
    assert runner.restarts == 0 and not runner.process.is_alive()  # the dead one, not replaced


class StopsWhileSpawning:
    """The runner's process context, except that spawning a process first starts stopping the runner
    (on another thread) and waits until the stop has begun: a stop that races a restart."""

    def __init__(self, runner: ProcessRunner):
        self.runner, self.real, self.stopper = runner, runner._context, None
        self.spawned: list = []

    def __getattr__(self, name: str):
        return getattr(self.real, name)

    def Process(self, *args, **kwargs):  # noqa: N802 - multiprocessing's name
        stopper = threading.Thread(target=self.runner.stop)
        stopper.start()
        self.stopper = stopper  # seen by the test only once started: a thread not yet started cannot be joined
        wait_until(self.runner._stop.is_set, what="the stop to begin")
        process = self.real.Process(*args, **kwargs)
        self.spawned.append(process)
        return process


@pytest.mark.slow
def test_a_process_spawned_while_the_runner_stops_is_stopped_too(only_process_runner):
    runner = only_process_runner
    runner.restart_pause = 0.0
    spawning = runner._context = StopsWhileSpawning(runner)
    old = runner.process.pid
    os.kill(old, signal.SIGKILL)
    wait_until(lambda: spawning.stopper is not None, what="the restart to spawn")
    spawning.stopper.join(30)
    assert not spawning.stopper.is_alive()
    assert spawning.spawned and all(p.pid is None or not p.is_alive() for p in spawning.spawned)


def test_the_settings_follow_the_running_config_and_the_changes_waiting_for_a_reset():
    """Runner.settings is kept between frames (building a Config checks every value: a quarter of a class
    world's frame) and made again when either changes."""
    runner = Runner(SMALL, shape=None)
    assert runner.settings is runner.sim.config and runner.settings is runner.settings
    runner.call(commands.UpdateConfig({"robots": 14}))  # waits for a reset
    assert runner.settings.robots == 14 and runner.sim.config.robots == 12 and runner.latest.config.robots == 14
    runner.call(commands.UpdateConfig({"switch": 0.25}))  # live: a new running config
    assert runner.settings.switch == 0.25 and runner.settings.robots == 14
    runner.call(Reset())
    assert runner.settings is runner.sim.config and (runner.settings.robots, runner.settings.switch) == (14, 0.25)


def test_a_frame_leaves_out_the_intensities_its_parent_has():
    """The lights' intensities are 33 of the paper's world's 58 KB a frame, and change once per 100 steps."""
    from sandbox.app.world.child import FrameSamples

    runner, sender = Runner(SMALL, shape=None), FrameSamples()
    first = sender.frame(runner, runner.latest)
    runner.advance(1)
    same_lights = sender.frame(runner, runner.latest)
    runner.call(commands.SetLamp((0.0, 0.0), 2.0))  # new lights
    runner.advance(1)
    new_lights = sender.frame(runner, runner.latest)
    assert first.snap.intensities is not None and runner.latest.intensities is not None
    assert same_lights.snap.lights_key == first.snap.lights_key and same_lights.snap.intensities is None
    assert new_lights.snap.lights_key != first.snap.lights_key and new_lights.snap.intensities is not None


def test_every_frame_heard_has_the_lights_intensities(process_runner):
    """The parent puts them back from the frame before (same lights)."""
    seen = []
    process_runner.subscribe(seen.append)
    wait_until(lambda: len(seen) >= 12, what="a dozen frames")
    keys = [snap.lights_key for snap in seen]
    assert len(set(keys)) < len(keys)  # some frames came without them
    assert all(snap.intensities is not None and snap.intensities.shape == seen[0].intensities.shape for snap in seen)
