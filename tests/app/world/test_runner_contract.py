"""The runners (a thread, a child process, a world in a shared host) follow one contract, written once
(sandbox.app.world.contract), and a chart never joins two worlds."""

from __future__ import annotations

import inspect

import pytest

from sandbox.app.world.contract import FramePublisher, SimulationRunner
from sandbox.app.world.child import ProcessRunner
from sandbox.app.world.hosted import HostedRunner
from sandbox.app.world.orders import Reset
from sandbox.app.world.runner import Runner
from sandbox.model.config import Config

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)
MEMBERS = [name for name, value in vars(SimulationRunner).items()
           if not name.startswith("_") and (callable(value) or isinstance(value, property))]
#: What each runner does its own way; everything else the contract writes once, over submit().
OWN = {"submit", "start", "stop", "latest", "series", "on_progress", "on_halt", "call"}
#: All the contract holds beside: asking with callbacks, and reading the controls back. No command has a
#: method of its own (sandbox.app.world.orders: a command is its dataclass, and says what it does).
RUNNERS = [Runner, ProcessRunner, HostedRunner]
WRITTEN_ONCE = {"ask", "playing", "steps_per_frame", "followed", "hold_at", "want_field", "steps_per_second"}


@pytest.mark.parametrize("kind", RUNNERS)
@pytest.mark.parametrize("name", MEMBERS)
def test_each_runner_has_the_contracts_methods_with_its_signatures(kind, name):
    promised, offered = getattr(SimulationRunner, name), getattr(kind, name, None)
    assert offered is not None, f"{kind.__name__} lacks {name}"
    if isinstance(promised, property):
        assert isinstance(offered, property)
        return
    want = [(p.name, p.kind, p.default) for p in inspect.signature(promised).parameters.values()]
    got = [(p.name, p.kind, p.default) for p in inspect.signature(offered).parameters.values()]
    assert got == want, f"{kind.__name__}.{name}{inspect.signature(offered)} differs from the contract"


@pytest.mark.parametrize("kind", RUNNERS)
def test_the_commands_are_written_once_for_both_runners(kind):
    """A new command is one dataclass: no runner repeats anything of the contract's."""
    again = sorted(name for name in MEMBERS if name not in OWN and name in written_by(kind))
    assert not again, f"{kind.__name__} writes {again} again"
    assert OWN - {"call"} <= written_by(kind)  # what it must do itself (call: the Runner runs inline unstarted)


def written_by(kind: type) -> set[str]:
    """What ``kind`` and the runners it is made from write (a hosted runner is a process runner)."""
    below = kind.__mro__[:kind.__mro__.index(SimulationRunner)]
    return set().union(*(vars(c) for c in below))


def test_the_contract_has_no_method_per_command():
    assert set(MEMBERS) == OWN | WRITTEN_ONCE


def test_both_runners_publish_through_the_same_publisher():
    assert all(issubclass(kind, FramePublisher) for kind in RUNNERS)
    runner = Runner(SMALL, shape=None)
    assert isinstance(runner, SimulationRunner)


def test_after_a_reset_the_series_holds_the_new_world_only():
    runner = Runner(SMALL, shape=None, chart_every=10)
    runner.advance(200)
    world, series = runner.series_of_world()
    assert series[-1].step == 200
    runner.submit(Reset())
    for _ in range(3):
        runner.advance(10)
    new_world, series = runner.series_of_world()
    assert new_world == world + 1 and runner.latest.world_key == new_world
    assert [s.step for s in series] == [0, 10, 20, 30]
