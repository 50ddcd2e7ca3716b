"""A light program is the user's code: it runs under a time limit, and
nothing it does (a loop that never ends, SystemExit, a crash of its process)
takes the run or the app down. And the app survives its own faults: a
callback that raises, a child killed while it builds a world, crashes in a
row."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from sandbox.app.world.orders import Apply, Reset, SetProgram, UpdateConfig
from sandbox.commands import main
from sandbox.model import watchdog
from sandbox.model.config import Config
from sandbox.model.programs import ProgramError, load_program
from sandbox.model.simulation import Simulation
from tests.waiting import wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
PAPER = "the paper's controller"

PROGRAMS = textwrap.dedent('''
    import os, sys, time
    import numpy as np

    class Spin:
        def update(self, observation):
            while True:
                pass

    class SpinInReset:
        def reset(self, config, goal):
            while True:
                pass
        def update(self, observation):
            return None

    class Sleeps:
        def update(self, observation):
            time.sleep(1000)  # stuck in C: the exception cannot land

    class Swallows:
        def update(self, observation):
            while True:
                try:
                    while True:
                        pass
                except BaseException:
                    pass

    class Exits:
        def update(self, observation):
            sys.exit(0)

    class Often:
        every = "often"
        def update(self, observation):
            return None

    class Crashes:
        def update(self, observation):
            os._exit(3)

    class Dark:
        def update(self, observation):
            return np.zeros(observation.lights_shape)
''')


@pytest.fixture(scope="module")
def programs(tmp_path_factory):
    path = tmp_path_factory.mktemp("programs") / "bad.py"
    path.write_text(PROGRAMS)
    return path


# ----------------------------------------------------------------- watchdog
def test_a_limited_call_that_overruns_is_stopped_and_says_where():
    def spin():
        while True:
            pass

    started = time.monotonic()
    with pytest.raises(watchdog.ProgramTimeout, match=r"spin took longer than 0.2 s \(at test_program_limits.py line"):
        watchdog.limited(spin, limit=0.2, what="spin", source=__file__)
    assert time.monotonic() - started < 1.0
    assert watchdog.limited(lambda x: x + 1, 1, limit=0.2) == 2  # and the next call is not hit by a stray one


def test_a_call_that_races_its_deadline_is_never_hit_after_it_returned():
    """Either the call overruns (ProgramTimeout from the call itself) or it returns: nothing lands later."""
    outcomes = []
    for _ in range(20):
        try:
            watchdog.limited(time.sleep, 0.049, limit=0.05)
            outcomes.append("returned")
        except watchdog.ProgramTimeout:
            outcomes.append("overran")
    with watchdog._WATCHDOG._lock:  # the watchdog raises only into a call it still holds, under this lock
        assert not watchdog._WATCHDOG._calls  # none is left: nothing can land later
    for _ in range(20):
        sum(range(10_000))  # bytecode after the calls: where a stray exception would land
    assert len(outcomes) == 20


def test_a_stuck_call_goes_to_the_processs_hook(monkeypatch):
    heard = []
    monkeypatch.setattr(watchdog, "on_stuck", heard.append)
    import threading

    release = threading.Event()

    def waits() -> None:
        with pytest.raises(watchdog.ProgramTimeout):  # it lands once the wait returns
            watchdog.limited(release.wait, 30, limit=0.1, what="waits")

    thread = threading.Thread(target=waits)
    thread.start()
    wait_until(lambda: heard, timeout=5, what="the stuck hook")
    release.set()
    thread.join(5)
    assert "waits took longer than its time limit and did not stop" in heard[0]


# ------------------------------------------------------------ simulation
@pytest.mark.parametrize("name, message", [
    ("Spin", r"Spin.update took longer than 0.3 s \(at bad.py line \d+, in update\) at step 0"),
    ("SpinInReset", r"SpinInReset.reset took longer than 0.3 s \(at bad.py line \d+, in reset\)"),
    ("Exits", r"Exits.update failed at step 0: SystemExit: 0"),
    ("Often", r"Often.every must be a whole number of world steps"),
])
def test_a_program_that_misbehaves_is_a_one_line_program_error(programs, name, message):
    with pytest.raises(ProgramError, match=message):
        program = load_program(f"{programs}:{name}")
        Simulation(SMALL, program=program, program_time_limit=0.3).step(3)


def test_loading_a_module_that_loops_or_exits_is_refused(tmp_path):
    loops, exits = tmp_path / "loops.py", tmp_path / "exits.py"
    loops.write_text("while True:\n    pass\n")
    exits.write_text("raise SystemExit(0)\n")
    with pytest.raises(ProgramError, match=r"importing .*loops.py took longer than 0.3 s \(at loops.py line 1"):
        load_program(f"{loops}:X", time_limit=0.3)
    with pytest.raises(ProgramError, match="cannot load it: SystemExit"):
        load_program(f"{exits}:X")


# ------------------------------------------------------------------- CLI
def test_run_stops_an_overrunning_program_with_one_line(programs, capsys):
    code = main(["run", "--controller", f"{programs}:Spin", "--program-time-limit", "0.3", "--steps", "50",
                 "--robots", "12", "--boxes", "20", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Spin.update took longer than 0.3 s" in err


@pytest.mark.slow
def test_run_ends_a_program_stuck_where_python_cannot_stop_it(programs):
    """time.sleep(1000) never takes the exception: the process ends, with one line, exit code 2."""
    result = subprocess.run([sys.executable, "-m", "sandbox", "run", "--controller", f"{programs}:Sleeps",
                             "--program-time-limit", "0.5", "--steps", "50", "--robots", "12", "--boxes", "20",
                             "--no-progress"], capture_output=True, text=True, timeout=60)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    assert lines[0].startswith("phototaxis run: error: Sleeps.update took longer than its time limit and did not "
                               "stop (at bad.py line ")


# ------------------------------------------------------------------ live app
def test_the_app_hands_the_lights_back_when_a_program_overruns(programs):
    from sandbox.app.world.runner import Runner

    runner = Runner(SMALL, shape=None, fps=60, steps_per_frame=2, program_time_limit=0.3).start()
    try:
        runner.ask(SetProgram(f"{programs}:Spin"))
        wait_until(lambda: runner.latest.program_error, what="the program to be stopped")
        assert runner.latest.program == PAPER
        assert "Spin.update took longer than 0.3 s (at bad.py line" in runner.latest.program_error[1]
        step = runner.latest.step
        wait_until(lambda: runner.latest.step > step + 20, what="the paper's controller to go on")
    finally:
        runner.stop()


@pytest.mark.slow
def test_a_program_that_cannot_be_stopped_or_crashes_costs_its_process_not_the_app(programs):
    """Stuck in C, then a crash: each time a new simulation process starts with the paper's controller,
    and the crash listeners hear which program did what."""
    from sandbox.app.world.child import ProcessRunner

    runner = ProcessRunner(SMALL, shape=None, fps=30, steps_per_frame=2, program_time_limit=0.3)
    runner.restart_pause = 0.05
    heard: list[str] = []
    runner.on_crash(heard.append)
    runner.start()
    try:
        for name, restarts in (("Sleeps", 1), ("Crashes", 2)):
            runner.ask(SetProgram(f"{programs}:{name}"))
            wait_until(lambda: runner.restarts == restarts and runner.latest.program == PAPER,
                       what=f"a fresh simulation after {name}")
            frame = runner.latest.frame
            wait_until(lambda: runner.latest.frame > frame + 10, what="frames from the new process")
        assert "Sleeps.update took longer than its time limit and did not stop (at bad.py line" in heard[0]
        assert "exit code 3" in heard[1] and runner.restarts == 2 and runner.failed is None
    finally:
        runner.stop()


@pytest.mark.slow
def test_the_app_survives_a_raising_callback_a_kill_while_building_and_gives_up_after_crashes_in_a_row():
    from sandbox.app.world.child import ProcessRunner

    runner = ProcessRunner(SMALL, shape=None, fps=30, steps_per_frame=2)
    runner.restart_pause, runner.crashes_before_giving_up = 0.05, 2
    progress: list = []
    runner.on_progress(progress.append)
    heard: list[str] = []
    runner.on_crash(heard.append)
    runner.start()
    try:
        def boom(result):
            raise RuntimeError("a broken callback")

        runner.ask(Apply(_steps_done), on_done=boom)
        wait_until(lambda: any("a broken callback" in str(e) for e in runner.errors), what="the callback to fail")
        frame = runner.latest.frame
        wait_until(lambda: runner.latest.frame > frame + 5, what="frames after the broken callback")

        runner.ask(UpdateConfig({"robots": 3000, "boxes": 3000}))
        runner.ask(Reset())  # a big world takes a while to build: kill the process in the middle
        wait_until(lambda: any(p is not None for p in progress), what="building to start")
        os.kill(runner.process.pid, signal.SIGKILL)
        wait_until(lambda: runner.restarts == 1, what="the restart")
        assert progress[-1] is None  # the page's "Building the world" ends
        frame = runner.latest.frame
        wait_until(lambda: runner.latest.frame > frame + 5, what="frames from the new process")

        os.kill(runner.process.pid, signal.SIGKILL)  # the second crash within a minute: give up
        wait_until(lambda: runner.failed, what="the runner to give up")
        assert "the simulation cannot start: it stopped 2 times within a minute" in heard[-1]
        done: list = []
        runner.ask(Reset(), on_error=done.append)
        assert done and "cannot start" in str(done[0])
    finally:
        runner.stop()


def _steps_done(sim):
    return sim.steps_done


@pytest.mark.slow
def test_after_a_restart_the_next_program_failure_is_announced_again(programs):
    """The Light program folder tells every page when a program fails. A restarted simulation process
    counts failures from nothing: its first one is news too (the folder used to wait for a second)."""
    from types import SimpleNamespace

    from sandbox.app.panel.program import ProgramFolder
    from sandbox.app.world.child import ProcessRunner

    told: list[str] = []
    page = SimpleNamespace(add_notification=lambda title, body, **kw: told.append(f"{title}: {body}"))
    server = SimpleNamespace(get_clients=lambda: {1: page})
    runner = ProcessRunner(SMALL, shape=None, fps=30, steps_per_frame=2)
    runner.restart_pause = 0.05
    folder = ProgramFolder(None, runner, server, allowed=True, on_change=lambda what: None)
    folder.status = SimpleNamespace(content="")
    runner.subscribe(folder.update)
    runner.start()
    try:
        def fails_and_is_told(times: int) -> None:
            runner.ask(SetProgram(f"{programs}:Exits"))
            wait_until(lambda: sum("Light program stopped" in t for t in told) == times,
                       what=f"failure {times} on the page")

        fails_and_is_told(1)
        os.kill(runner.process.pid, signal.SIGKILL)
        wait_until(lambda: runner.restarts == 1 and runner.latest.program == PAPER, what="the new process")
        fails_and_is_told(2)
        assert "Exits.update" in told[-1]
    finally:
        runner.stop()
