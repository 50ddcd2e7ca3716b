"""What a world may cost (issue 54, item 2; sandbox/model/budget.py, docs/security.md): settings and goals
whose world would exhaust the machine are refused before it is built, in one line that says what to change,
from the command line, a design file and the page alike; a goal of thousands of vertices is simplified to
what the outlines afford and says so, or is refused."""

from __future__ import annotations

import math
import os
import resource
import subprocess
import sys
import time

import numpy as np
import pytest
import shapely

from sandbox.model import budget
from sandbox.model.config import Config, ConfigError
from sandbox.model.family import make_goal
from sandbox.model.goal import fit_goal
from sandbox.model.lights import _AxisLayout
from sandbox.model.simulation import Simulation
from sandbox.shapes import ShapeError, shape_vertices
from tests.commands.test_cli import phototaxis
from tests.waiting import wait_until

#: The tests' budget, the default's at most: the same refusals on any machine.
BUDGET = "1G"


@pytest.fixture(autouse=True)
def one_gigabyte(monkeypatch):
    monkeypatch.setenv(budget.BUDGET_VARIABLE, BUDGET)


def spiky_c(n: int, spike: float, outer: float = 1.0, inner: float = 0.55, gap: float = 70.0) -> np.ndarray:
    """A C of ``n`` vertices whose outer and inner arcs are saw-toothed, each tooth ``spike`` (of the
    outer radius) tall: a tooth a vertex wide, so that no simplification within less than its height
    drops it (the attack's 9,990-vertex C had such teeth; at 0.12 they are 0.84 m tall once fitted)."""
    half = n // 2
    a0, a1 = math.radians(gap / 2), math.radians(360 - gap / 2)
    t, ti = np.linspace(a0, a1, half), np.linspace(a1, a0, n - half)
    ro = outer + spike * (np.arange(half) % 2)
    ri = inner - 0.5 * spike * (np.arange(n - half) % 2)
    return np.vstack([np.column_stack([ro * np.cos(t), ro * np.sin(t)]),
                      np.column_stack([ri * np.cos(ti), ri * np.sin(ti)])])


def polygon_file(tmp_path, vertices: np.ndarray, name: str = "spiky.txt"):
    path = tmp_path / name
    path.write_text("".join(f"{x:.7f} {y:.7f}\n" for x, y in vertices))
    return path


def unchecked(**values) -> Config:
    with budget.unchecked_budget():
        return Config(**values)


# ------------------------------------------------------------------ the estimate
def test_a_config_offers_all_the_budget_reads_of_it():
    """budget.py is below config (every Config checks itself against it) and names what it reads in
    budget.Settings instead of importing Config: a field renamed in Config must be renamed there."""
    config = Config()
    read = [*budget.Settings.__annotations__, *budget.KNOBS, "replace"]
    assert len(read) > 12 and not [name for name in read if not hasattr(config, name)]


def test_the_field_is_sized_as_the_light_layout_makes_it():
    """Worked out without the layout's arrays, and equal to what it builds, on a spread of settings."""
    for window in ("cells", "range"):
        for pitch, reach, samples in [(1.0, 12.8, 6), (0.5, 3.2, 7), (0.25, 1.7, 2), (2.0, 20.0, 64), (1.0, 0.3, 1),
                                      (0.64, 12.8, 13), (1.0, 1.0, 3)]:
            if window == "cells" and reach < pitch:
                with pytest.raises(ConfigError, match="light_range .0.3. must be at least light_pitch .1."):
                    Config(light_pitch=pitch, light_range=reach, light_window=window)  # no light would reach
                continue
            config = Config(light_pitch=pitch, light_range=reach, field_samples=samples, light_window=window)
            layout = _AxisLayout(config)
            assert budget.field_side(config) == (layout.length, len(layout.light_offsets) * layout.per_cell)


def test_the_paper_world_costs_what_its_parts_add_up_to():
    """By hand. A pitch of 1 m is cut at 0.3 and 0.7 m (12.8 m of range from light centres at 0.5) and at
    the cell edge: strips of 0.3, 0.4 and 0.3 m at 6 samples a metre have 2, 3 and 2 intervals, so 10
    samples a cell. 24 light columns reach a cell (W = 12: -12 .. 11): a light's block is 240 samples a
    side. 65 layout cells cover the arena, with 12 cells of padding each side: 890 samples a side."""
    config = Config()
    assert budget.field_side(config) == (890, 240)
    cost = budget.settings_cost(config)
    assert cost.terms == {"light field": 4 * 890**2 + 4 * 240**2,  # 3,398,800: float32 field and block
                          "field block": 16 * 240**2,  # 921,600: its float64 build, for a moment
                          "lights": 120 * 64**2,  # 491,520
                          "bodies": 3_500 * 200 + 6_000 * 500,  # 3,700,000
                          "metrics": 240 * (100_000 // 1_000 + 2)}  # 24,480
    assert cost.total == 3_398_800 + 491_520 + 3_700_000 + 24_480 + 921_600  # 8,536,400: 8.5 MB
    # With a goal: its vertices grown (500 bytes a pair) and a notched goal's widths (48 bytes a point of a
    # 0.1 m grid over it), for a moment, in place of the block's build (the larger of the two).
    with_goal = budget.world_cost(config, 300, 9.0, 9.0)
    assert with_goal.terms["goal"] == 500 * 300**2 + 48 * 91 * 91
    assert with_goal.total == 3_398_800 + 491_520 + 3_700_000 + 24_480 + 45_397_488


def test_the_attacks_settings_cost_what_they_would_have_taken():
    """Pitch 0.05 with 64 samples: 66 samples a cell, 512 light columns, 1,281 + 2 x 256 cells: a field
    118,338 samples a side (56 GB of float32) and blocks 33,792 a side (4.6 GB, and 18 GB to compute)."""
    attack = unchecked(light_pitch=0.05, field_samples=64)
    assert budget.field_side(attack) == (118_338, 33_792)
    cost = budget.settings_cost(attack)
    assert cost.terms["light field"] == 4 * 118_338**2 + 4 * 33_792**2 == 60_583_126_032
    assert cost.terms["field block"] == 16 * 33_792**2
    assert round(cost.total / 1e9) == 79
    assert budget.settings_cost(unchecked(arena_size=2000.0, light_pitch=0.05)).terms["lights"] == 120 * 40_000**2


def test_the_budget_is_a_share_of_the_machine_at_most_one_gigabyte(monkeypatch):
    monkeypatch.delenv(budget.BUDGET_VARIABLE)
    monkeypatch.setattr(budget, "physical_memory", lambda: 16 * 10**9)
    assert budget.memory_budget() == 10**9
    monkeypatch.setattr(budget, "physical_memory", lambda: 2 * 10**9)  # a small machine: a quarter
    assert budget.memory_budget() == 500 * 10**6
    monkeypatch.setattr(budget, "physical_memory", lambda: None)
    assert budget.memory_budget() == 10**9
    monkeypatch.setattr(budget, "physical_memory", lambda: 16 * 10**9)
    assert [budget.parse_budget(t) for t in ("1.5G", "800M", "2GiB", "1000000000", "50%")] == [
        1_500_000_000, 800_000_000, 2 * 2**30, 10**9, 8 * 10**9]
    for bad, said in [("lots", "give a size such as 2G"), ("5", "at least 50M"), ("17G", "more than this machine's")]:
        with pytest.raises(ValueError, match=said):
            budget.parse_budget(bad)


# ------------------------------------------------------------------ the refusal
def test_settings_over_the_budget_are_refused_in_one_line_that_says_what_to_change():
    with pytest.raises(budget.OverBudget) as refused:
        Config(light_pitch=0.05, field_samples=64)
    line = str(refused.value)
    assert line == ("light pitch 0.05 with field samples 64 needs ~79 GB (light field 61 GB, field block 18 GB), "
                    "over the 1.0 GB budget: raise light pitch to at least 0.5 or lower field samples to at most 4")
    assert isinstance(refused.value, ConfigError)
    # What it says works, and is the nearest that does: 0.4 and 5 do not.
    assert Config(light_pitch=0.5, field_samples=64) and Config(light_pitch=0.05, field_samples=4)
    for too_far in (dict(light_pitch=0.4, field_samples=64), dict(light_pitch=0.05, field_samples=5)):
        with pytest.raises(budget.OverBudget):
            Config(**too_far)
    with pytest.raises(budget.OverBudget, match=r"^arena size 2,000 with light pitch 1 needs ~3.1 GB \(light field 1.6 GB, "
                                                r"bodies 950 MB, lights 480 MB\), over the 1.0 GB budget: raise light "
                                                r"pitch to at least 8$"):
        Config(arena_size=2000.0, robot_spawn_size=2000.0, construction_size=1000.0, robots=100_000, boxes=100_000)


def test_a_larger_budget_lets_the_same_settings_through(monkeypatch):
    with pytest.raises(budget.OverBudget):
        Config(light_pitch=0.05)
    monkeypatch.setenv(budget.BUDGET_VARIABLE, "2G")
    assert Config(light_pitch=0.05).light_pitch == 0.05


def test_a_world_is_checked_again_where_it_is_built():
    """A Config that came another way (unpickled, made under a larger budget) is refused by the simulation."""
    attack = unchecked(light_pitch=0.05, field_samples=64)
    with pytest.raises(budget.OverBudget, match="needs ~79 GB"):
        Simulation(attack)
    sim = Simulation(Config(robots=10, boxes=20))
    with pytest.raises(budget.OverBudget):
        sim.reset(config=attack)
    sim.step(5)  # the world that ran goes on
    assert sim.steps_done == 5 and sim.config.light_pitch == 1.0


# ------------------------------------------------------------------ the command line
def _refused_quickly(*args: str) -> str:
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    started = time.thread_time()  # its CPU, not the clock (a loaded machine stretches the clock, not the work)
    out = phototaxis(*args)
    took = time.thread_time() - started
    grew_mb = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    assert out.returncode == 2 and out.stdout == "", out
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert took < 1.0 and grew_mb < 50, (took, grew_mb)
    return lines[0]


@pytest.mark.parametrize("flags, said", [
    (["--field-samples", "64", "--light-pitch", "0.05"], "light pitch 0.05 with field samples 64 needs ~79 GB"),
    (["--arena-size", "2000", "--light-pitch", "0.05"], "light pitch 0.05 with arena size 2,000 needs ~613 GB"),
    (["--robots", "100000", "--boxes", "100000", "--arena-size", "2000", "--robot-spawn-size", "2000",
      "--construction-size", "1000"], "arena size 2,000 with light pitch 1 needs ~3.1 GB (light field 1.6 GB, "
                                       "bodies 950 MB"),
    (["--steps", "1000000000", "--metrics-every", "1"], "metrics every 1 with steps 1,000,000,000 needs ~240 GB"),
])
def test_the_command_line_refuses_each_attack_at_once(flags, said):
    """Before: the first reached 2.9 GB, the second 3 GB in 1.4 s, the third 3 GB (each under a 3 GB cap)."""
    line = _refused_quickly("run", *flags, "--steps" if "--steps" not in flags else "--seed", "1", "--no-progress")
    assert line.startswith(f"phototaxis run: error: {said}") and "budget: " in line


@pytest.mark.parametrize("command, out", [("sweep", True), ("advise", False), ("record", True), ("serve", False)])
def test_every_command_that_builds_worlds_refuses_them_the_same_way(command, out, tmp_path):
    where = ["--out", str(tmp_path / "out")] if out else []
    line = _refused_quickly(command, "--field-samples", "64", "--light-pitch", "0.05", *where)
    assert f"phototaxis {command}: error: light pitch 0.05 with field samples 64 needs ~79 GB" in line


def test_the_memory_budget_flag_raises_the_budget_for_the_command():
    out = phototaxis("run", "--light-pitch", "0.5", "--field-samples", "64", "--steps", "0", "--no-progress",
                     "--memory-budget", "60M", "--json")
    assert out.returncode == 2 and "over the 60 MB budget" in out.stderr
    assert "--memory-budget: memory budget 'lots'" in phototaxis("run", "--memory-budget", "lots").stderr


def test_a_malformed_budget_in_the_environment_is_one_line_from_a_fresh_process():
    """A module makes a Config as it loads (design.py's defaults), so PHOTOTAXIS_MEMORY_BUDGET=zz was a
    traceback from the import in a fresh process; the dispatcher reads the budget before any import."""
    env = {**os.environ, "PHOTOTAXIS_MEMORY_BUDGET": "zz"}
    out = subprocess.run([sys.executable, "-m", "sandbox", "run", "--steps", "1"], env=env, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 2 and out.stderr.strip().splitlines() == [
        "phototaxis: error: PHOTOTAXIS_MEMORY_BUDGET: memory budget 'zz': give a size such as 2G, 800M or 50% "
        "(of the machine's memory)"]


def test_a_needle_c_is_refused_at_once_from_the_command_line(tmp_path):
    """The attack's C: 9,990 vertices, teeth 0.84 m tall that no simplification within a quarter pitch drops.
    Before: 8.6 GB and still running at 300 s (2,000 vertices: 2.5 GB, killed at the 3 GB cap after 40 s)."""
    path = polygon_file(tmp_path, spiky_c(9_990, 0.12))
    started = time.thread_time()
    out = phototaxis("run", "--shape", str(path), "--outline", "offset", "--steps", "200", "--no-progress")
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1
    assert time.thread_time() - started < 2.0  # reading and validating 9,990 vertices takes most of it
    assert ("the goal has 9,990 vertices, and simplified within 0.25 m (a quarter of the light pitch) still "
            "7,688: the outlines afford at most 300") in out.stderr


# ------------------------------------------------------------------ design files
def _design_file(tmp_path, config: Config, shape=None):
    from sandbox.model.design import Design, save

    n = config.lights_per_side
    design = Design(config=config, shape=shape, steps_run=0, steps=np.zeros(1, np.int64),
                    patterns=np.zeros((1, n, n), np.uint8))
    path = tmp_path / "design.npz"
    save(design, path)
    return path


def test_a_design_file_over_the_budget_is_refused_in_one_line(tmp_path):
    path = _design_file(tmp_path, unchecked(light_pitch=0.05, field_samples=64, robots=10, boxes=20))
    for command in ("run", "serve"):
        line = _refused_quickly(command, "--design", str(path))
        assert line == (f"phototaxis {command}: error: {path}: its settings are refused: light pitch 0.05 with field "
                        f"samples 64 needs ~79 GB (light field 61 GB, field block 18 GB), over the 1.0 GB budget: "
                        f"raise light pitch to at least 0.5 or lower field samples to at most 4")


def test_a_design_files_needle_goal_is_refused_in_one_line(tmp_path):
    """Before, ``serve --design`` of it ended in a traceback: its simulation process could not build the first
    world. Now the server fits the goal before it starts one."""
    path = _design_file(tmp_path, Config(robots=10, outline="offset"), spiky_c(9_990, 0.12))
    for command in (["run", "--no-progress"], ["serve", "--port", "0"]):
        out = phototaxis(command[0], "--design", str(path), *command[1:])
        assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1, out.stderr
        assert "the goal has 9,990 vertices" in out.stderr and "afford at most 300" in out.stderr


def test_serve_refuses_a_needle_goal_before_it_starts(tmp_path):
    path = polygon_file(tmp_path, spiky_c(9_990, 0.12))
    started = time.thread_time()
    out = phototaxis("serve", "--shape", str(path), "--port", "0")
    assert time.thread_time() - started < 2.0  # reading and validating 9,990 vertices takes most of it
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1
    assert out.stderr.startswith(f"phototaxis serve: error: {path}: the goal has 9,990 vertices")


# ------------------------------------------------------------------ goals
def test_a_goal_of_ten_thousand_vertices_is_simplified_quickly_and_says_so():
    config = Config(outline="offset")
    spiky = spiky_c(10_000, 0.03)  # teeth 0.2 m tall once fitted
    started = time.thread_time()  # its CPU, not the clock: a loaded machine took 2.15 s of wall time
    goal = make_goal(config, spiky)
    assert time.thread_time() - started < 2.0
    assert len(goal.vertices) <= budget.MAX_GOAL_VERTICES
    tolerance = float(goal.simplified.split("within ")[1].split(" m")[0])
    assert goal.simplified == f"simplified from 10,000 to {len(goal.vertices):,} vertices within {tolerance:.2g} m"
    assert config.light_pitch / 20 < tolerance <= config.light_pitch / 4
    raw = shapely.Polygon(spiky * math.sqrt(goal.area / shapely.Polygon(spiky).area))
    raw = shapely.affinity.translate(raw, *(goal.centre - np.array(raw.centroid.coords[0])))
    simplified = shapely.Polygon(goal.vertices)
    assert abs(simplified.area - goal.area) < 1e-6 * goal.area  # refitted to the boxes' area
    assert raw.hausdorff_distance(simplified) < 1.2 * tolerance
    assert raw.symmetric_difference(simplified).area < 0.1 * goal.area
    sim = Simulation(Config(robots=10, boxes=500, outline="offset"), shape=spiky)
    assert sim.controller.notes[0].startswith("the goal was simplified from 10,000 to ")


def test_a_goal_within_the_bound_is_fitted_as_it_always_was():
    """The paper's shapes, the templates and a 300-vertex outline: simplified within a twentieth of a pitch
    and refitted, bit for bit as before the bound, and nothing said."""
    from sandbox.shapes import geometry
    from sandbox.shapes.templates import TEMPLATES

    t = np.linspace(0.0, 2 * math.pi, 300, endpoint=False)
    wobbly = np.c_[np.cos(t) * (1 + 0.3 * np.sin(9 * t)), np.sin(t) * (1 + 0.3 * np.sin(9 * t))]
    config = Config()
    shapes = [shape_vertices(name) for name in ("square", "star", "l-shape", "crescent", "arrow")]
    for vertices in [*shapes, *(make() for make in TEMPLATES.values()), wobbly]:
        fitted = geometry.fit_to_area(vertices, 500 * config.box_area, np.full(2, config.centre))
        simpler = geometry.simplify(fitted, config.light_pitch / 20.0)
        expected = geometry.fit_to_area(simpler, 500 * config.box_area, np.full(2, config.centre)) \
            if len(simpler) < len(fitted) else fitted
        goal = fit_goal(config, vertices)
        assert np.array_equal(goal.vertices, expected) and goal.simplified == ""


def test_a_needle_goal_is_refused_everywhere_it_can_come_from():
    """At the paper's 500 boxes the teeth are 0.84 m tall: more than a quarter pitch."""
    needles = spiky_c(2_000, 0.12)
    said = "the goal has 2,000 vertices, and simplified within 0.25 m"
    from sandbox.model.preview import preview_goal

    for build in (lambda: make_goal(Config(), needles), lambda: preview_goal(Config(), needles, 0.0),
                  lambda: Simulation(Config(robots=10), shape=needles)):
        started = time.thread_time()
        with pytest.raises(ShapeError, match=said):
            build()
        assert time.thread_time() - started < 1.0
    sim = Simulation(Config(robots=10))
    with pytest.raises(ShapeError, match=said):
        sim.set_shape(needles, "needles.txt")
    sim.step(3)
    assert sim.goal.is_circle and sim.steps_done == 3


def test_a_goal_that_would_take_the_world_over_the_budget_is_refused(monkeypatch):
    """Pitch 0.25: 83 MB of settings, and a 300-vertex goal adds 46 MB (in place of the field block's 17 MB)."""
    config = Config(light_pitch=0.25, robots=10)
    monkeypatch.setenv(budget.BUDGET_VARIABLE, "100M")
    assert fit_goal(config, shape_vertices("square")) is not None
    with pytest.raises(ShapeError, match=r"^the goal \(300 vertices, needing ~46 MB as its outline grows\) with "
                                         r"these settings needs ~112 MB \(.*\), over the 100 MB budget: .*use a goal "
                                         r"with fewer vertices$"):
        fit_goal(config, spiky_c(300, 0.12))


# ------------------------------------------------------------------ the page
@pytest.fixture(params=[False, pytest.param(True, marks=pytest.mark.slow)], ids=["in-process", "own-process"])
def app(request):
    """The app, its simulation in this process, and (slow) in its own process as ``serve`` runs it."""
    from sandbox.commands.serve import App, free_port

    a = App(Config(robots=12, boxes=20, update_every=10, hold_steps=3), port=free_port(), fps=30, steps_per_frame=2,
            process=request.param).start()
    yield a
    a.stop()


def test_the_page_is_refused_by_the_server_and_the_world_goes_on(app):
    """The attack: field samples 64, then light pitch 0.05, then Reset. Before: the simulation process passed
    2.9 GB, was killed and restarted into the same settings. Now the server refuses the pitch with a
    notification, the control goes back, the samples stand, and Reset builds the world that fits."""
    from sandbox.app.world.orders import UpdateConfig
    from tests.app.web.test_security import connected, notification, own_page, uuid_of
    from tests.viser_wire import RawClient

    controls, runner = app.panel.parameters.controls, app.panel.parameters.runner
    asked = []  # what the panel asked of the simulation
    ask = runner.ask

    def asking(command, *args, **kwargs):
        if isinstance(command, UpdateConfig):
            asked.append(dict(command.changes))
        return ask(command, *args, **kwargs)

    runner.ask = asking
    client = RawClient(app.port, own_page(app))
    connected(app, client)
    client.set_value(uuid_of(controls["field_samples"]), 64)
    wait_until(lambda: app.runner.latest.config.field_samples == 64, what="field samples 64 to wait for a reset")
    client.set_value(uuid_of(controls["light_pitch"]), 0.05)
    body = notification(client, "light_pitch not changed")["body"]
    assert body.startswith("light pitch 0.05 with field samples 64 needs ~79 GB") and "raise light pitch" in body
    wait_until(lambda: controls["light_pitch"].value == 1.0, what="the field to show the pitch that stands")
    assert app.runner.latest.config.light_pitch == 1.0
    assert {"light_pitch": 0.05} not in asked  # the server refused it: the simulation never heard of it
    world = app.runner.latest.world_key
    client.click(uuid_of(app.panel.run.reset_same))
    snap = wait_until(lambda: app.runner.latest.world_key != world and app.runner.latest, what="the new world")
    assert snap.world_config.field_samples == 64 and snap.world_config.light_pitch == 1.0
    step = app.runner.latest.step
    wait_until(lambda: app.runner.latest.step > step + 10, what="the world to keep stepping")
    client.close()


def test_an_upload_the_outlines_cannot_afford_is_refused_by_the_server(app, tmp_path):
    from tests.app.test_app_runner import FakeClient

    client = FakeClient()
    text = polygon_file(tmp_path, spiky_c(2_000, 0.5), "needles.txt").read_bytes()  # 20 boxes: a small C
    assert not app.panel.shape.use_shape_file("needles.txt", text, client)
    title, body, _ = client.notes[-1]
    assert title == "File received, shape not used" and body.startswith("needles.txt: the goal has 2,000 vertices")
    assert app.runner.latest.shape_name == "circle"
