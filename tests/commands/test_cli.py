"""The command line as a user runs it: exit codes, one-line errors, JSON and traces.

The commands run in this process (``sandbox.commands.main``, as ``python -m sandbox``
calls it), so that each one does not pay a fresh interpreter's second of imports;
the last test runs the real ``python -m sandbox`` and ``phototaxis`` in processes
of their own.
"""

import contextlib
import csv
import io
import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

SMALL = ["--robots", "10", "--boxes", "20", "--steps", "300", "--metrics-every", "100", "--no-progress"]


@dataclass
class Finished:
    """What a command left: as subprocess.CompletedProcess has it."""
    returncode: int
    stdout: str
    stderr: str


def phototaxis(*args: str) -> Finished:
    """``phototaxis ARGS`` in this process: its exit code and what it printed."""
    from sandbox.commands import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(args))
        except SystemExit as exc:  # argparse's usage errors, as the interpreter would end
            code = exc.code if isinstance(exc.code, int) else 1
    return Finished(code, out.getvalue(), err.getvalue())


def test_run_json_has_the_promised_keys(tmp_path):
    trace = tmp_path / "t.csv"
    out = phototaxis("run", "--case", "star-switch", *SMALL, "--json", "--trace", str(trace))
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    for key in ("case", "seed", "steps", "robots", "boxes", "fraction_in_goal", "mean_outside_distance",
                "boxes_escaped", "cycles", "wall_seconds", "steps_per_second", "config"):
        assert key in result
    assert result["case"] == "star-switch" and result["steps"] == 300 and result["boxes_escaped"] == 0
    assert result["config"]["switch"] == 0.25 and result["config"]["robots"] == 10
    rows = list(csv.DictReader(trace.open()))
    assert [int(r["step"]) for r in rows] == [0, 100, 200, 300]
    assert float(rows[-1]["fraction_in_goal"]) == pytest.approx(result["fraction_in_goal"])


def test_flags_override_case_and_config_file(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("seed = 5\nflare = 1.0\n")
    out = phototaxis("run", "--config", str(cfg), "--case", "square-flare", "--flare", "2.5", *SMALL, "--json")
    assert out.returncode == 0, out.stderr
    config = json.loads(out.stdout)["config"]
    assert (config["seed"], config["shape"], config["flare"]) == (5, "square", 2.5)


def test_bare_strategy_flags_take_their_default_amount():
    out = phototaxis("run", "--shape", "square", "--flare", "--switch", "--no-corners", *SMALL, "--json")
    config = json.loads(out.stdout)["config"]
    assert (config["flare"], config["switch"], config["no_corners"]) == (1.75, 0.25, 0.5)


def test_same_seed_same_result_from_the_cli():
    a = json.loads(phototaxis("run", *SMALL, "--seed", "4", "--json").stdout)
    b = json.loads(phototaxis("run", *SMALL, "--seed", "4", "--json").stdout)
    assert a["fraction_in_goal"] == b["fraction_in_goal"]
    assert a["mean_outside_distance"] == b["mean_outside_distance"]


#: A short world whose cycle is 211 steps (update every step, hold one update: by hand, a contraction of 105
#: updates, a hold of 1 and a dilation of 105): 500 steps go through 2 whole cycles.
CYCLING = ["--robots", "10", "--boxes", "20", "--update-every", "1", "--hold-steps", "1", "--steps", "500",
           "--no-progress"]


def test_a_replay_prints_the_cycles_its_design_went_through_not_0(tmp_path):
    """Issue 56, item 6: a replay never advances the paper's controller, so it printed '0 cycles'. The
    design records the count; a design that does not (a light program lit it, or an older file) says what
    it holds instead, and JSON's cycles is null."""
    path = tmp_path / "circle.npz"
    made = json.loads(phototaxis("run", *CYCLING, "--json", "--save-design", str(path)).stdout)
    assert made["cycles"] == 2
    replay = phototaxis("run", "--design", str(path))
    assert replay.returncode == 0, replay.stderr
    assert "500 steps, 2 cycles (as recorded in the design)," in replay.stdout
    assert json.loads(phototaxis("run", "--design", str(path), "--json", "--no-progress").stdout)["cycles"] == 2

    from sandbox.model.design import load
    from tests.model.test_design import altered

    older = altered(path, tmp_path / "older.npz", edit=lambda header: header["result"].pop("cycles"))
    patterns = len(load(older).steps)  # the pattern changed at most once a step: fewer than 500
    said = phototaxis("run", "--design", str(older)).stdout
    assert f"500 steps, {patterns} light patterns (the design records no cycle count)," in said
    assert " 0 cycles" not in said
    assert json.loads(phototaxis("run", "--design", str(older), "--json", "--no-progress").stdout)["cycles"] is None


def test_a_light_program_of_your_own_has_no_cycle_count_said_or_recorded(tmp_path):
    ring = Path(__file__).resolve().parents[2] / "examples" / "shrinking_ring.py"
    path = tmp_path / "ring.npz"
    out = phototaxis("run", *CYCLING, "--controller", f"{ring}:ShrinkingRing", "--save-design", str(path))
    assert out.returncode == 0, out.stderr
    assert "500 steps, cycles not counted (a light program of your own)," in out.stdout
    from sandbox.model.design import load

    assert load(path).result["cycles"] is None and load(path).cycles is None


@pytest.mark.parametrize("args, words", [
    (["--robots", "many"], "whole number"),
    (["--robots", "-3"], "outside the allowed range"),
    (["--k-drive", "nan"], "finite"),
    (["--shape", "nosuchshape"], "built-in shapes are"),
    (["--case", "hexagon"], "invalid choice"),
    (["--config", "/no/such/file.toml"], "cannot read config file"),
    (["--trace", "/proc/nope/t.csv"], "cannot write trace file"),
    (["--box-size-is", "side"], "invalid choice"),
])
def test_bad_input_is_one_line_and_exit_2(args, words):
    out = phototaxis("run", *SMALL, *args)
    assert out.returncode == 2
    assert words in out.stderr
    assert "Traceback" not in out.stderr
    assert len(out.stderr.strip().splitlines()) <= 2  # argparse adds a usage line


def test_bad_shape_file(tmp_path):
    bad = tmp_path / "bow.txt"
    bad.write_text("0 0\n1 1\n1 0\n0 1\n")
    out = phototaxis("run", *SMALL, "--shape", str(bad))
    assert out.returncode == 2 and "bow.txt" in out.stderr and "Traceback" not in out.stderr


def test_bench_json():
    out = phototaxis("bench", "--steps", "200", "--robots", "20", "--boxes", "30", "--json", "--no-progress")
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    assert r["steps_per_second"] > 0 and 0 < r["physics_share"] < 1 and r["peak_rss_mb"] > 0


def test_bench_scale_grows_the_world():
    from sandbox.commands.bench import scaled
    from sandbox.model.config import Config

    c = scaled(Config(), 10)
    assert (c.robots, c.boxes, c.arena_size, c.construction_size) == (2000, 5000, 202.0, 51.0)


@pytest.mark.slow
def test_bench_live_without_a_browser_measures_what_its_websocket_viewer_receives():
    from sandbox.commands import live_bench
    from sandbox.model.config import Config

    r = live_bench.run(Config(robots=20, boxes=30), 1.0, warmup=0.5, viewers=1, browser=False)
    assert r["steps_per_second"] > 0 and r["kb_per_second_per_viewer"] > 0
    assert (r["viewers"], r["browser_frames_per_second"]) == (1, None)
    refused = phototaxis("bench", "--live", "--no-browser", "--viewers", "0")
    assert refused.returncode == 2 and "needs a websocket viewer" in refused.stderr


def test_help_lists_commands():
    out = phototaxis("--help")
    assert out.returncode == 0
    for command in ("run", "bench", "serve", "sweep", "report", "record"):
        assert command in out.stdout


@pytest.mark.slow
def test_the_installed_commands_run_in_their_own_processes():
    """``python -m sandbox`` and the ``phototaxis`` script: exit codes and streams as a shell sees them."""
    module = [sys.executable, "-m", "sandbox"]
    script = shutil.which("phototaxis", path=str(Path(sys.executable).parent) + os.pathsep + os.environ["PATH"])
    for command in filter(None, [module, script and [script]]):
        done = subprocess.run([*command, "run", *SMALL, "--json"], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        assert json.loads(done.stdout)["steps"] == 300
    bad = subprocess.run([*module, "run", *SMALL, "--robots", "many"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "whole number" in bad.stderr and "Traceback" not in bad.stderr


def test_the_web_server_imports_no_simulation_engine():
    """The server draws; its simulation runs in a process of its own. Importing numba (and the scipy
    it pulls in), pymunk or matplotlib took a third of its start (docs/code.md)."""
    heavy = ("numba", "scipy", "pymunk", "matplotlib")
    code = f"import sys, sandbox.commands.serve; print([m for m in {heavy!r} if m in sys.modules])"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize("name, text", [("deep.json", "[" * 100_000 + "]" * 100_000),
                                        ("huge.txt", "0 0\n1e308 0\n0 1e308\n"),
                                        ("sliver.txt", "-120 0\n120 0\n0 0.3\n")])  # 50 m long at 20 boxes
def test_pathological_shape_files_are_one_line_errors(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    out = phototaxis("run", "--shape", str(path), *SMALL)
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("\n") == 1 and name in out.stderr and "Traceback" not in out.stderr
