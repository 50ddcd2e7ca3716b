"""A crash loop ends, and the teacher can always undo (issue 54, B).

Field samples 64 and light pitch 0.05, then *Reset*: the simulation process was killed for want of
memory, restarted "from the last settings" and killed again every 15-20 s, never reaching the five
crashes in a minute that gave up; setting the values back was refused ("not changed: the simulation
process stopped"). Here a world is made to kill its process deterministically, without exhausting
memory: the test-only fault ``PHOTOTAXIS_TEST_CRASH_BUILD`` (sandbox/app/world/faults.py, read from the
environment each time a simulation process starts; no page reaches it) kills the process that builds a
world whose light pitch is 0.5, as the out-of-memory killer does.
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import Future

import pytest

from sandbox.app.world.faults import CRASH_BUILD
from sandbox.app.world.child import ProcessRunner, SimulationCrashed
from sandbox.app.world.hosted import HostedRunner
from sandbox.app.world.pool import HostPool
from sandbox.app.world.orders import Reset, UpdateConfig
from sandbox.model.config import Config
from tests.viser_wire import RawClient
from tests.waiting import wait_until

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
KILLED = "the simulation process was killed, most likely out of memory (exit code -9)"
NEVER = 10**9  # steps or seconds: no world runs long enough to count as having run


@pytest.fixture(params=["process", "hosted"])
def runner(monkeypatch, request):
    """A process runner, or a world in a host (whose host dies as a process runner's child does)."""
    monkeypatch.setenv(CRASH_BUILD, "light_pitch=0.5")
    pool = HostPool(hosts=1)  # after the fault is set: a host reads it as it starts
    if request.param == "process":
        r = ProcessRunner(SMALL, shape=None, fps=60, steps_per_frame=2)
    else:
        r = HostedRunner(SMALL, pool=pool, shape=None, fps=60, steps_per_frame=2)
    r.restart_pause = 0.05
    r.heard, r.went_back = [], []
    r.on_crash(r.heard.append)
    r.on_settings_back(r.went_back.append)
    r.start()
    yield r
    r.stop()
    pool.stop()


def running_again(r: ProcessRunner, restarts: int) -> None:
    """Wait for the ``restarts``-th new process to step."""
    wait_until(lambda: r.restarts == restarts and r.process.is_alive(), what=f"restart {restarts}")
    step, world = r.latest.step, r.latest.world_key
    wait_until(lambda: r.latest.world_key != world or r.latest.step > step + 5, what="the new process to step")


def kill(r: ProcessRunner) -> None:
    os.kill(r.process.pid, signal.SIGKILL)  # as the kernel's out-of-memory killer ends it


def test_settings_that_kill_the_process_while_building_go_back_to_the_last_that_ran(runner):
    """Before: restarted with light pitch 0.5 and killed again, for ever."""
    runner.call(UpdateConfig({"light_pitch": 0.5, "field_samples": 16}), 10)
    refused = runner.ask(Reset())
    assert isinstance(refused.exception(timeout=30), SimulationCrashed)
    running_again(runner, 1)
    assert runner.heard == [f"{KILLED} with light pitch 0.5, field samples 16; back to the last settings that ran "
                            f"(light pitch 1, field samples 6)"]
    assert [c.light_pitch for c in runner.went_back] == [1.0]
    snap = runner.latest
    assert snap.world_config.light_pitch == snap.config.light_pitch == 1.0  # running, and nothing waits
    frame = snap.frame
    wait_until(lambda: runner.latest.frame > frame + 30, what="the world to go on")
    assert len(runner.heard) == 1 and runner.restarts == 1 and runner.failed is None


def test_a_setting_changed_while_the_process_is_down_waits_for_the_next_one(runner):
    """Before: "not changed: the simulation is restarting; try again"."""
    changes: list[Future] = []
    runner.restart_pause = 0.5
    # Heard on the thread that restarts the process, before it does: the process is down.
    runner.on_crash(lambda why: changes.append(runner.ask(UpdateConfig({"light_pitch": 2.0}))))
    kill(runner)
    wait_until(lambda: changes, what="the crash")
    pending, settings = changes[0].result(30)  # answered by the next process, not refused
    assert pending == ["light_pitch"] and settings.light_pitch == 2.0
    running_again(runner, 1)
    wait_until(lambda: runner.latest.config.light_pitch == 2.0, what="the change waiting for a reset")
    assert runner.latest.world_config.light_pitch == 1.0


def test_a_second_crash_with_the_settings_that_ran_goes_back_to_those_before(runner):
    runner.proven_steps = 20
    runner.call(UpdateConfig({"robots": 14}), 10)
    runner.call(Reset(), 30)
    wait_until(lambda: runner.standing.config.robots == 14, what="the new world to count as having run")
    runner.proven_steps = runner.proven_seconds = NEVER
    kill(runner)  # the settings that stand: restarted from them
    running_again(runner, 1)
    assert runner.heard[0].startswith(f"{KILLED}; restarting in") and runner.latest.world_config.robots == 14
    kill(runner)  # twice: back to those that ran before
    running_again(runner, 2)
    assert runner.heard[1] == (f"{KILLED} with robots 14; back to the last settings that ran (robots 12)")
    assert runner.latest.world_config.robots == 12 and runner.standing.config.robots == 12


def test_crashes_far_apart_with_no_world_running_between_give_up(runner):
    """Before: only five crashes within a minute gave up; a crash every 15-20 s went on for ever."""
    runner.proven_steps = runner.proven_seconds = NEVER
    runner.crashes_before_giving_up, runner.crash_window = 3, 0.0  # every crash "far apart"
    for restarts in (1, 2):
        kill(runner)
        running_again(runner, restarts)
    kill(runner)
    wait_until(lambda: runner.failed, what="the runner to give up")
    assert runner.failed == (f"the simulation cannot start: it stopped 3 times with no world running in between "
                             f"(last: {KILLED})")
    refused = runner.ask(UpdateConfig({"robots": 20}))  # no process will take it: refused at once, with why
    assert "cannot start" in str(refused.exception(timeout=0))


def test_crashes_with_a_world_running_between_do_not_give_up(runner):
    runner.proven_steps = 5
    runner.crashes_before_giving_up, runner.crash_window = 2, 0.0
    for restarts in (1, 2, 3):
        kill(runner)
        running_again(runner, restarts)
        wait_until(lambda: runner._standing.crashes == 0, what="the new world to count as having run")
    assert runner.failed is None


# ---------------------------------------------------------------- the page
def own_page(app) -> dict[str, str]:
    return {"Origin": f"http://127.0.0.1:{app.port}"}


def notification(client: RawClient, title: str, seconds: float = 60.0) -> dict:
    """The first notification titled ``title`` the server sends within ``seconds`` (every message read:
    one frame of the server's may hold several notifications)."""
    for message in client._messages(seconds):
        if message.get("type") == "NotificationShowMessage" and message["props"]["title"] == title:
            return message["props"]
    raise AssertionError(f"no {title!r} notification within {seconds:.0f} s")


@pytest.mark.slow
def test_the_page_says_what_failed_and_its_panel_shows_the_settings_that_stand(monkeypatch):
    """Over the network, as the teacher's page: light pitch 0.5 and field samples 16, then Reset."""
    from sandbox.commands.serve import App, free_port

    monkeypatch.setenv(CRASH_BUILD, "light_pitch=0.5")
    app = App(SMALL, port=free_port(), fps=30, steps_per_frame=2).start()
    client = RawClient(app.port, own_page(app))
    try:
        client.say_hello()
        wait_until(lambda: app.server.get_clients(), what="the page to connect")
        controls = app.panel.parameters.controls
        client.set_value(controls["light_pitch"]._impl.uuid, 0.5)
        client.set_value(controls["field_samples"]._impl.uuid, 16)
        wait_until(lambda: app.runner.latest.config.field_samples == 16, what="both changes to wait for a reset")
        client.click(app.panel.run.reset_same._impl.uuid)
        told = notification(client, "The simulation stopped")
        assert told["body"] == (f"{KILLED[0].upper()}{KILLED[1:]} with light pitch 0.5, field samples 16; back to "
                                f"the last settings that ran (light pitch 1, field samples 6).")
        wait_until(lambda: controls["light_pitch"].value == 1.0 and controls["field_samples"].value == 6,
                   what="the panel to show the settings that stand")
        assert app.panel.parameters.pending.content == ""
        wait_until(lambda: app.runner.restarts == 1 and app.runner.latest.world_config.light_pitch == 1.0,
                   what="the world from the settings that stand")
    finally:
        client.close()
        app.stop()
