"""``phototaxis bench --class K`` (sandbox.commands.class_bench): a class server with K students' pages
over websockets, each world's speed and frames, the bytes per student, the wall, the server's CPU and
memory."""

from __future__ import annotations

import msgspec
import pytest
import zstandard

from sandbox.cli import UserError
from sandbox.commands import build_parser, class_bench
from sandbox.model.config import Config

SMALL = Config(robots=12, boxes=20, update_every=10, hold_steps=3)


def test_the_flags_reach_the_benchmark():
    args = build_parser("bench").parse_args(["bench", "--class", "30", "--seconds", "5", "--teacher-browser"])
    assert (args.class_students, args.seconds, args.teacher_browser) == (30, 5.0, True)


def test_the_class_challenges_steps_reach_the_benchmark():
    args = build_parser("bench").parse_args(["bench", "--class", "10", "--class-challenge", "450"])
    assert (args.class_students, args.class_challenge) == (10, 450)


def test_a_class_without_students_is_refused_in_a_line():
    with pytest.raises(UserError, match="at least one student"):
        class_bench.run(SMALL, 0, 1.0)


def test_more_students_than_seats_are_refused_in_a_line():
    args = build_parser("bench").parse_args(["bench", "--class", "41"])
    with pytest.raises(UserError, match="1 to 40 students"):
        args.func(args)


def frame(messages: list[dict]) -> bytes:
    """A server frame as viser sends it: [inner size][compressed size][zstd msgpack]."""
    inner = msgspec.msgpack.encode({"messages": messages, "timestampSec": 0.0, "binaryBufferLengths": ()})
    compressed = zstandard.ZstdCompressor().compress(inner)
    return len(inner).to_bytes(8, "little") + len(compressed).to_bytes(8, "little") + compressed


def test_a_student_finds_where_its_page_reports_drawing():
    script = '(() => { window.__phototaxisDrawn = "/__drawn/Ab-9_x"; })();'
    assert class_bench.reporting_address(frame([{"type": "RunJavascriptMessage", "source": script}]),
                                         zstandard) == "/__drawn/Ab-9_x"
    assert class_bench.reporting_address(frame([{"type": "GuiUpdateMessage"}]), zstandard) is None


def test_the_wall_is_timed_by_the_pictures_it_sends():
    class Wall:
        _drawn_key = None

        def refresh(self):
            self._drawn_key = self.next

    wall = Wall()
    clock = class_bench.WallClock(wall)
    for key in ("a", "a", "b"):  # a refresh that finds nothing moved sends no picture
        wall.next = key
        wall.refresh()
    assert clock.refreshes == 3 and len(clock.sent) == 2
    assert class_bench.intervals([1.0, 2.0, 3.5]) == [1.0, 1.5]
    assert class_bench.summary([3.0, 1.0, 2.0], 1) == {"min": 1.0, "median": 2.0}


@pytest.mark.slow
def test_it_reports_each_student_and_the_server(monkeypatch):
    """A class server, two students' pages over websockets, two seconds of measurement: tens of seconds on a
    loaded machine (the fast tests above are its neighbours)."""
    monkeypatch.setattr(class_bench, "WARM_UP", 0.5)
    result = class_bench.run(SMALL, 2, 2.0, steps_per_frame=2, challenge_steps=27)
    assert result["students"] == 2 and result["page_errors"] == [] and result["pages_calm"] == 2
    assert result["steps_per_second"]["min"] > 0 and result["real_time_factor"]["min"] > 0
    assert result["frames_per_second"]["min"] > 0 and result["desk_frames_per_second"]["min"] > 0
    assert result["world_frames_per_second"]["min"] > 0
    assert result["kb_per_second_per_student"]["median"] > 0
    assert result["kb_per_second_per_student"]["max"] >= result["kb_per_second_per_student"]["median"]
    assert result["cpu_seconds"]["server"] > 0 and result["hosts"] >= 1
    assert result["rss_mb"]["server"] > 0 and result["rss_mb"]["hosts"] > 0
    assert result["rss_per_student_world_beyond_first_mb"] is not None
    assert result["wall_refresh_seconds"]["pictures"] >= 1
    challenge = result["class_challenge"]  # two rounds in the same world (the teacher's scene): one reference
    assert challenge["students"] == 2 and challenge["reference_runs"] == 1
    assert challenge["pss_mb_peak"] >= challenge["pss_mb_before"] > 0


def test_the_measurement_is_told_window_by_window(monkeypatch):
    # Two worlds, dt 1/30, 25 s in windows of 10 s. World a: 90 steps/s throughout (3x); world b: 90, then
    # 45 (1.5x), then 90. The last window (5 s) is half a window: told.
    clock = {"now": 0.0}
    rates = {"a": [90, 90, 90], "b": [90, 45, 90]}

    class FakeTime:
        @staticmethod
        def perf_counter():
            return clock["now"]

        @staticmethod
        def sleep(seconds):
            window = min(int(clock["now"] // 10), 2)
            for key in steps:
                steps[key] += rates[key][window] * seconds
            clock["now"] += seconds

    class App:
        config = Config()

    steps = {"a": 0.0, "b": 0.0}
    monkeypatch.setattr(class_bench, "time", FakeTime)
    monkeypatch.setattr(class_bench, "steps_now", lambda app, identities: dict(steps))
    windows = class_bench.by_window(App(), ["a", "b"], 25.0, 0.0)
    assert windows == [(3.0, 3.0), (1.5, 2.25), (3.0, 3.0)]
    # A last window under half of one (2 s of 10) is not told: too few frames to count steps by.
    clock["now"], steps["a"], steps["b"] = 0.0, 0.0, 0.0
    assert class_bench.by_window(App(), ["a", "b"], 22.0, 0.0) == [(3.0, 3.0), (1.5, 2.25)]


def test_a_spread_class_runs_student_i_of_k_to_step_steps_i_over_k():
    from concurrent.futures import Future

    from sandbox.app.world.orders import SkipAhead

    asked: dict[str, list] = {}

    class Runner:
        def __init__(self, name):
            self.name = name

        def submit(self, order):
            asked.setdefault(self.name, []).append(order)
            done = Future()
            done.set_result(None)
            return done

    class World:
        def __init__(self, name):
            self.runner = Runner(name)

    class Events:
        @staticmethod
        def call(fn):
            return fn()

    class App:
        events = Events()

    App.lesson = type("Lesson", (), {"worlds": {name: World(name) for name in "abc"}})()
    class_bench.spread_out(App(), ["a", "b", "c"], 20_000)  # 20,000 x 1/3, 2/3, 3/3
    assert {name: [(type(order), order.step) for order in orders] for name, orders in asked.items()} == {
        "a": [(SkipAhead, 6_666)], "b": [(SkipAhead, 13_333)], "c": [(SkipAhead, 20_000)]}


def test_a_skip_below_zero_or_without_worlds_to_spread_is_refused_in_a_line():
    for argv, said in ((["bench", "--class", "2", "--skip", "-5"], "0 or more, got -5"),
                       (["bench", "--skip", "100"], "goes with --hosted K or --class K")):
        args = build_parser("bench").parse_args(argv)
        with pytest.raises(UserError, match=said):
            args.func(args)
