"""Design files bounded once unpacked (issue 54 D; sandbox/model/design.py, sandbox/model/bounded_npz.py).

A 1.1 MB .npz of 200,000 all-zero patterns took ``run --design`` to 1.71 GB and a 197 KB file with a
50 MB header to 620 MB: np.load unpacks an array whole before its shape is seen. Every file here is
written in the test, its arrays streamed into the archive (zero patterns compress to almost nothing),
and each bound is refused in one line that names it and its limit, from the archive's directory and
the arrays' headers, with next to nothing allocated (tracemalloc sees numpy's arrays)."""

from __future__ import annotations

import dataclasses
import json
import os
import struct
import subprocess
import sys
import time
import tracemalloc
import zipfile
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np
import pytest

from sandbox.model import bounded_npz
from sandbox.model.config import Config
from sandbox.model.design import (FORMAT, MAX_CONTROLLER_CHARS, MAX_FILE_BYTES, MAX_HEADER_CHARS, MAX_NAME_CHARS,
                                  MAX_PATTERN_BYTES, MAX_PATTERNS, VERSION, Design, DesignError, PatternRecorder,
                                  light_field, load, save)
from sandbox.shapes.validation import MAX_VERTICES
from tests.commands.test_cli import phototaxis

ROOT = Path(__file__).resolve().parents[2]
GRID = 64  # the default light grid: 64 x 64 lights
#: What refusing a file may allocate, at most (the arrays' headers, the zip's directory).
REFUSAL_BYTES = 2_000_000
SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]


# ------------------------------------------------------------ writing files
def header(config: Config = Config(), *, steps_run: int = 1000, **changes) -> dict:
    """A design's JSON header, written by hand (docs/design-files.md), with some keys changed."""
    made = {"format": FORMAT, "version": VERSION, "seed": config.seed, "steps_run": steps_run,
            "controller": "paper (open loop)", "light_field": light_field(config),
            "goal": {"name": config.shape, "given": None}, "result": {}, "config": config.to_dict()}
    made.update(changes)
    return made


def zeros(nbytes: int) -> Iterator[bytes]:
    """``nbytes`` zero bytes, a megabyte at a time (a test never holds a hostile array whole)."""
    block = bytes(1 << 20)
    while nbytes > 0:
        yield block[:nbytes]
        nbytes -= len(block)


def member(archive: zipfile.ZipFile, name: str, dtype, shape: tuple, data: Iterable[bytes],
           *, header_bytes: bytes | None = None) -> None:
    """An .npy member streamed into ``archive``: its header (numpy's, or ``header_bytes``), then ``data``."""
    with archive.open(f"{name}.npy", "w", force_zip64=True) as out:
        if header_bytes is None:
            np.lib.format.write_array_header_1_0(out, {"descr": np.lib.format.dtype_to_descr(np.dtype(dtype)),
                                                       "fortran_order": False, "shape": shape})
        else:
            out.write(header_bytes)
        for chunk in data:
            out.write(chunk)


def design_file(path: Path, *, head: dict | str | None = None, count: int = 1, n: int = GRID,
                dtype=np.uint8, extra: dict | None = None, compression: int = zipfile.ZIP_DEFLATED) -> Path:
    """A design file of ``count`` all-zero patterns on an ``n`` x ``n`` grid, steps 0, 1, 2, ... and
    ``head`` as its header (a dict, or the JSON text itself); ``extra``: more members, name: bytes."""
    if head is None:
        head = header(steps_run=max(count, 1000))
    text_array = np.array(head if isinstance(head, str) else json.dumps(head))
    level = 1 if compression == zipfile.ZIP_DEFLATED else None  # zeros compress as well at level 1, and faster
    with zipfile.ZipFile(path, "w", compression, compresslevel=level) as archive:
        member(archive, "header", text_array.dtype, (), [text_array.tobytes()])
        member(archive, "steps", np.int64, (count,), [np.arange(count, dtype=np.int64).tobytes()])
        member(archive, "patterns", dtype, (count, n, n), zeros(count * n * n * np.dtype(dtype).itemsize))
        for name, data in (extra or {}).items():
            archive.writestr(name, data)
    return path


def refusal(path: Path) -> tuple[str, int, float]:
    """``load(path)``'s one-line refusal, the bytes it allocated at most and the seconds it took."""
    tracemalloc.start()
    started = time.process_time()
    try:
        with pytest.raises(DesignError) as refused:
            load(path)
        return str(refused.value), tracemalloc.get_traced_memory()[1], time.process_time() - started
    finally:
        tracemalloc.stop()


def refused_cheaply(path: Path) -> str:
    line, peak, seconds = refusal(path)
    assert "\n" not in line and peak < REFUSAL_BYTES and seconds < 1.0, (line, peak, seconds)
    return line


# ------------------------------------------------------------------ bounds
def test_the_bounds_are_the_models_numbers():
    """10,000 patterns: ten default runs' controller updates (100,000 steps, one every 100); 41 MB: that
    many on / off patterns of the default 64 x 64 grid; the goal's vertices, an upload's most."""
    default = Config()
    assert MAX_PATTERNS == 10 * default.steps // default.update_every == 10_000
    assert MAX_PATTERN_BYTES == 10_000 * 64 * 64 == 40_960_000 and default.lights_per_side == GRID
    assert MAX_VERTICES == 10_000 and MAX_NAME_CHARS == 80 and MAX_HEADER_CHARS == 1_500_000
    assert MAX_FILE_BYTES == 64_000_000 > MAX_PATTERN_BYTES + 4 * MAX_HEADER_CHARS


def test_a_design_at_every_bound_loads_in_little_memory_and_time(tmp_path):
    """The most patterns, the longest names, the most vertices as given and as fitted: read in well
    under 100 MB (41 MB of them the patterns themselves) and a second."""
    name = "n" * MAX_NAME_CHARS
    config = Config(shape=name)
    ring = np.c_[np.cos(np.linspace(0, 6.28, MAX_VERTICES, endpoint=False)),
                 np.sin(np.linspace(0, 6.28, MAX_VERTICES, endpoint=False))].tolist()
    head = header(config, steps_run=MAX_PATTERNS, controller="c" * MAX_CONTROLLER_CHARS,
                  goal={"name": name, "given": ring, "vertices": ring, "centre": [32.5, 32.5], "radius": 1.5})
    path = design_file(tmp_path / "largest.npz", head=head, count=MAX_PATTERNS)
    tracemalloc.start()
    started = time.process_time()
    design = load(path)
    seconds, peak = time.process_time() - started, tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert design.patterns.shape == (MAX_PATTERNS, GRID, GRID) and design.config.shape == name
    assert len(design.shape) == len(design.goal["vertices"]) == MAX_VERTICES
    assert peak < 60_000_000 and seconds < 1.0, (peak, seconds)


def test_the_largest_header_is_read_in_a_bounded_time_and_memory(tmp_path):
    """1.5 million characters of small JSON objects (the most per character): parsed, checked, and
    dropped before the arrays are read."""
    head = header(result={"junk": []})
    head["result"]["junk"] = [[]] * ((MAX_HEADER_CHARS - len(json.dumps(head))) // 4)
    path = design_file(tmp_path / "crowded.npz", head=head)
    tracemalloc.start()
    started = time.process_time()
    design = load(path)
    seconds, peak = time.process_time() - started, tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert design.result == {} and peak < 60_000_000 and seconds < 1.5, (peak, seconds)


def over_count(tmp_path: Path) -> Path:
    return design_file(tmp_path / "many.npz", count=MAX_PATTERNS + 1)


def over_grid(tmp_path: Path) -> Path:
    config = Config(arena_size=128.0)  # 128 x 128 lights: 2,501 on / off patterns unpack to 40,976,384 bytes
    return design_file(tmp_path / "wide.npz", head=header(config, steps_run=5000), count=2501, n=128)


def over_dimmed(tmp_path: Path) -> Path:
    return design_file(tmp_path / "dimmed.npz", count=1251, dtype=np.float64)


def long_header(tmp_path: Path) -> Path:
    head = header(controller="")
    head["controller"] = "x" * (MAX_HEADER_CHARS + 1 - len(json.dumps(head)))
    return design_file(tmp_path / "header.npz", head=head)


def named(tmp_path: Path, **goal) -> Path:
    return design_file(tmp_path / "named.npz", head=header(goal={"name": "circle", "given": None, **goal}))


@pytest.mark.parametrize("write, said", [
    (over_count, "many.npz is too large: it holds 10,001 light patterns; a design holds at most 10,000"),
    (over_grid, "wide.npz is too large: its 2,501 patterns of 128 x 128 lights unpack to 40,976,384 bytes; "
                "a design's patterns unpack to at most 40,960,000 (10,000 on / off patterns of 64 x 64 lights)"),
    (over_dimmed, "dimmed.npz is too large: its 1,251 patterns of 64 x 64 lights unpack to 40,992,768 bytes"),
    (long_header, "header.npz is too large: its header is 1,500,001 characters of JSON; at most 1,500,000"),
    (lambda tmp: design_file(tmp / "shape.npz", head=header(Config(shape="s" * 81))),
     "shape.npz is refused: its goal's name (the settings' shape) is 81 characters long; at most 80"),
    (lambda tmp: named(tmp, name="g" * 81), "named.npz is refused: its goal's name is 81 characters long; at most 80"),
    (lambda tmp: named(tmp, name="<b>\nbold"), "its goal's name holds a control character (a line break?)"),
    (lambda tmp: design_file(tmp / "ctl.npz", head=header(controller="c" * 1001)),
     "ctl.npz is refused: its controller's name is 1,001 characters long; at most 1,000"),
    (lambda tmp: named(tmp, given=SQUARE * 2501), "its goal as given has 10,004 vertices; a goal has at most 10,000"),
    (lambda tmp: named(tmp, vertices=SQUARE * 2501), "its goal as fitted has 10,004 vertices; a goal has at most"),
])
def test_each_bound_is_refused_in_one_line_before_anything_is_unpacked(tmp_path, write, said):
    assert said in refused_cheaply(write(tmp_path))


def test_a_file_over_the_size_limit_is_refused_before_it_is_opened(tmp_path):
    path = tmp_path / "huge.npz"
    with path.open("wb") as handle:  # sparse: no disk used
        handle.truncate(MAX_FILE_BYTES + 1)
    assert refused_cheaply(path).endswith("huge.npz is too large: 64.0 MB on disk; a design file is at most 64.0 MB")


def test_a_pipe_or_a_device_is_never_read(tmp_path):
    """/dev/zero never ends (read whole, it took 2.4 GB and a MemoryError); a pipe's open waits."""
    pipe = tmp_path / "pipe.npz"
    os.mkfifo(pipe)
    assert refused_cheaply(pipe).endswith("pipe.npz: it is a pipe, not a file")
    assert refused_cheaply(Path("/dev/zero")) == "cannot read design file /dev/zero: it is a device, not a file"
    assert refused_cheaply(tmp_path).endswith("it is a folder, not a file")


def test_an_archive_listing_many_members_is_refused_before_zipfile_lists_them(tmp_path):
    """600,000 empty members (54 MB) took zipfile 340 MB and 3 s to list; 17 are refused from the
    archive's end record."""
    path = design_file(tmp_path / "crowd.npz", extra={f"{i:02d}": b"" for i in range(14)})
    line = refused_cheaply(path)
    assert "crowd.npz is too large: its archive lists 17 members in a directory of" in line
    assert line.endswith(f"at most {bounded_npz.MAX_MEMBERS} members in {bounded_npz.MAX_DIRECTORY_BYTES:,} bytes")


@pytest.mark.filterwarnings("ignore:Duplicate name")  # zipfile warns as it writes 'steps.npy' twice
@pytest.mark.parametrize("extra, said", [
    ({"evil.pkl": b"x"}, "is not a design file: it holds 'evil.pkl' besides a design's arrays (header, steps, "
                         "patterns)"),
    ({"steps.npy": np.arange(1, dtype=np.int64).tobytes()}, "is damaged: it holds 'steps' twice"),
])
def test_anything_but_a_designs_three_arrays_is_refused(tmp_path, extra, said):
    assert said in refused_cheaply(design_file(tmp_path / "more.npz", extra=extra))


def test_only_what_numpy_writes_is_decompressed(tmp_path):
    """LZMA's dictionary size is the file's to choose: only stored and deflated members are read."""
    assert load(design_file(tmp_path / "stored.npz", compression=zipfile.ZIP_STORED)).patterns.shape == (1, 64, 64)
    line = refused_cheaply(design_file(tmp_path / "lzma.npz", compression=zipfile.ZIP_LZMA))
    assert "lzma.npz is damaged: 'header.npy' is compressed in a way numpy never writes (zip method 14" in line


def npy_member(tmp_path: Path, name: str, raw: bytes) -> Path:
    """A design whose ``name`` member is ``raw`` (an .npy header of our making, and what follows it)."""
    path = tmp_path / f"{name}.npz"
    text = np.array(json.dumps(header(steps_run=1000)))
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for each, (dtype, shape, payload) in {"header": (text.dtype, (), text.tobytes()),
                                               "steps": (np.int64, (1,), bytes(8)),
                                               "patterns": (np.uint8, (1, GRID, GRID), bytes(GRID * GRID))}.items():
            if each == name:
                member(archive, each, None, (), [], header_bytes=raw)
            else:
                member(archive, each, dtype, shape, [payload])
    return path


def npy_header(text: str, version: tuple[int, int] = (1, 0)) -> bytes:
    raw = text.encode("latin1")
    length = struct.pack("<H" if version == (1, 0) else "<I", len(raw))
    return b"\x93NUMPY" + bytes(version) + length + raw


@pytest.mark.parametrize("name, made, said", [
    ("patterns", lambda: npy_header("{'descr': '|O', 'fortran_order': False, 'shape': (1, 64, 64), }"),
     "is damaged: its 'patterns' array holds Python objects (a pickle), which this program never reads"),
    ("header", lambda: npy_header("{'descr': '|O', 'fortran_order': False, 'shape': (), }"),
     "its 'header' array holds Python objects (a pickle)"),
    ("steps", lambda: b"\x93NUMPY\x02\x00" + struct.pack("<I", 50_000_000),
     "is too large: its 'steps' array's .npy header is 50,000,000 bytes; at most 10,000"),
    ("steps", lambda: npy_header("{'descr': [('a', '<i8')], 'fortran_order': False, 'shape': (1,), }"),
     "its 'steps' array is not an array of plain numbers or text"),
    ("patterns", lambda: npy_header("{'descr': '|u1', 'fortran_order': False, 'shape': (1, 64, 64), }") + b"\0" * 99,
     "is damaged: its 'patterns' array is 173 bytes in the archive's directory and 4,170 by its own header"),
    ("patterns", lambda: b"PK\x03\x04 not an array", "is damaged: its 'patterns' member is not a NumPy array (.npy)"),
])
def test_an_arrays_header_is_judged_before_its_data_is_read(tmp_path, name, made, said):
    assert said in refused_cheaply(npy_member(tmp_path, name, made()))


def test_an_array_in_fortran_order_or_stored_is_read_as_numpy_would(tmp_path):
    """What np.savez writes for a transposed array, read right (the checks are on the header, not the writer)."""
    config = Config()
    ones = np.zeros((2, GRID, GRID), np.uint8)
    ones[1, 3, 5] = 1
    path = tmp_path / "fortran.npz"
    with path.open("wb") as handle:
        np.savez(handle, header=np.array(json.dumps(header(config))), steps=np.array([0, 10]),
                 patterns=np.asfortranarray(ones))
    assert np.array_equal(load(path).patterns, ones)


# ---------------------------------------------------- what this program writes
def base_design() -> Design:
    """A small design, made by the recorder from pattern changes alone (no world is built)."""
    recorder = PatternRecorder()
    recorder.start(0, np.zeros((GRID, GRID)))
    steps, patterns = recorder.patterns()
    config = Config()
    return Design(config=config, shape=None, steps_run=1000, steps=steps, patterns=patterns, controller="test",
                  goal={"vertices": None, "centre": [32.5, 32.5], "radius": 1.5}, result={"state_digest": "ab"})


def test_the_recorder_keeps_at_most_what_a_design_holds():
    """On / off: 10,000 patterns of the default grid; dimmed: 1,250 (float64); then it stops."""
    lit = np.zeros((GRID, GRID))
    recorder = PatternRecorder()
    recorder.start(0, lit)
    for step in range(1, MAX_PATTERNS + 5):
        lit[step % GRID, step // GRID % GRID] = 1.0 - lit[step % GRID, step // GRID % GRID]
        recorder.change(step, lit)
    assert len(recorder) == MAX_PATTERNS and recorder.full
    dimmed = PatternRecorder()
    dimmed.start(0, np.full((GRID, GRID), 0.5))
    for step in range(1, 1300):
        dimmed.change(step, np.full((GRID, GRID), step / 2000))
    steps, patterns = dimmed.patterns()
    assert len(dimmed) == MAX_PATTERN_BYTES // (GRID * GRID * 8) == 1250 and dimmed.full
    assert patterns.dtype == np.float64 and patterns.nbytes <= MAX_PATTERN_BYTES


def test_a_full_recorder_says_so_in_one_line():
    recorder = PatternRecorder(most=3)
    recorder.start(0, np.zeros((GRID, GRID)))
    for step in (1, 2, 3):
        recorder.change(step, np.full((GRID, GRID), float(step % 2)))
    with pytest.raises(DesignError, match=r"^this world's light program has more than 3 patterns of 64 x 64 "
                                          r"lights, more than a design holds: record a shorter run"):
        recorder.design(sim=None)


def test_what_this_program_writes_at_the_bound_it_reads_and_over_it_refuses(tmp_path):
    base = base_design()
    most = dataclasses.replace(base, steps=np.arange(MAX_PATTERNS), steps_run=MAX_PATTERNS,
                               patterns=np.zeros((MAX_PATTERNS, GRID, GRID), np.uint8))
    save(most, tmp_path / "most.npz")
    assert load(tmp_path / "most.npz").patterns.shape == (MAX_PATTERNS, GRID, GRID)
    over = dataclasses.replace(most, steps=np.arange(MAX_PATTERNS + 1),
                               patterns=np.zeros((MAX_PATTERNS + 1, GRID, GRID), np.uint8))
    with pytest.raises(DesignError, match="^this design is too large: it holds 10,001 light patterns"):
        save(over, tmp_path / "over.npz")
    long_name = dataclasses.replace(base, config=base.config.replace(shape="s" * 81))
    with pytest.raises(DesignError, match="^this design is refused: its goal's name .* is 81 characters long"):
        save(long_name, tmp_path / "named.npz")
    assert not (tmp_path / "over.npz").exists() and not (tmp_path / "named.npz").exists()


def test_a_designs_repr_is_one_short_line():
    """A command carrying a design quoted in an error (serve's "cannot be sent") printed every pattern."""
    text = repr(dataclasses.replace(base_design(), patterns=np.zeros((500, GRID, GRID), np.uint8)))
    assert text == "Design(shape='circle', seed=0, steps_run=1000, patterns=500 x 64 x 64)"


def test_save_design_refuses_a_goal_name_too_long_before_running(tmp_path):
    """A polygon file's path is the goal's name: one longer than a design keeps is refused before the run."""
    folder = tmp_path / ("d" * MAX_NAME_CHARS)
    folder.mkdir()
    (folder / "square.txt").write_text("0 0\n1 0\n1 1\n0 1\n", encoding="utf-8")
    started = time.process_time()
    out = phototaxis("run", "--shape", str(folder / "square.txt"), "--steps", "100", "--no-progress",
                     "--save-design", str(tmp_path / "d.npz"))
    assert out.returncode == 2 and time.process_time() - started < 1.0 and out.stdout == ""
    said = (f"a design of this run is refused: its goal's name (the settings' shape) is "
            f"{len(str(folder / 'square.txt'))} characters long; at most 80")
    assert out.stderr.count("\n") == 1 and said in out.stderr, out.stderr


# --------------------------------------------------------------- the CLI
def cli_refusal(*args: str) -> tuple[str, int, float]:
    """``phototaxis ARGS`` in this process: its one error line, what it allocated at most, its seconds."""
    tracemalloc.start()
    started = time.process_time()
    try:
        out = phototaxis(*args)
        seconds, peak = time.process_time() - started, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert out.returncode == 2 and out.stdout == "", out
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in out.stderr, out.stderr
    return lines[0], peak, seconds


@pytest.mark.parametrize("write, said", [
    (lambda tmp: design_file(tmp / "hostile.npz", count=3 * MAX_PATTERNS),
     "hostile.npz is too large: it holds 30,000 light patterns; a design holds at most 10,000"),
    (long_header, "header.npz is too large: its header is 1,500,001 characters of JSON; at most 1,500,000"),
])
def test_run_design_refuses_a_hostile_file_at_once_in_little_memory(tmp_path, write, said):
    line, peak, seconds = cli_refusal("run", "--design", str(write(tmp_path)), "--no-progress")
    assert line.startswith("phototaxis run: error: ") and line.endswith(said)
    assert peak < REFUSAL_BYTES and seconds < 1.0, (peak, seconds)


def test_serve_design_refuses_a_hostile_file_before_any_server_starts(tmp_path, monkeypatch):
    from sandbox.commands import serve as server

    def app(*args, **kwargs):  # the server is never built: it would start on the design
        raise AssertionError("serve built its App for a refused design")

    monkeypatch.setattr(server, "App", app)
    line, peak, seconds = cli_refusal("serve", "--design", str(design_file(tmp_path / "hostile.npz",
                                                                          count=3 * MAX_PATTERNS)), "--port", "0")
    assert line == (f"phototaxis serve: error: {tmp_path / 'hostile.npz'} is too large: it holds 30,000 light "
                    f"patterns; a design holds at most 10,000")
    assert peak < REFUSAL_BYTES and seconds < 1.0, (peak, seconds)


#: Runs ``python -m sandbox ARGS`` under a 3 GB address-space cap and prints its seconds and peak
#: resident kilobytes (this interpreter's only child: its RUSAGE_CHILDREN is that child's).
MEASURE = """
import resource, subprocess, sys, time
def cap():
    resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, 3_000_000_000))
started = time.perf_counter()
out = subprocess.run([sys.executable, "-m", "sandbox", *sys.argv[1:]], capture_output=True, text=True,
                     timeout=120, preexec_fn=cap)
print(time.perf_counter() - started, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
sys.stderr.write(out.stderr)
sys.exit(out.returncode)
"""


def capped(*args: str) -> tuple[subprocess.CompletedProcess, float, float]:
    """``phototaxis ARGS`` in a capped child: how it ended, its seconds and its peak resident MB."""
    out = subprocess.run([sys.executable, "-c", MEASURE, *args], capture_output=True, text=True, timeout=180,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, cwd=ROOT)
    seconds, kilobytes = out.stdout.split()
    return out, float(seconds), int(kilobytes) / 1024


@pytest.mark.slow
@pytest.mark.parametrize("command", ["run", "serve"])
def test_the_reported_files_are_refused_in_a_child_at_once_in_little_memory(tmp_path, command):
    """The issue's files: 200,000 zero patterns in 1.1 MB (run --design took 1.71 GB, serve --design
    passed 3 GB) and a 50 MB header in 197 KB (620 MB). Refused in a second, the child's peak that of
    a refusal that reads no file (its interpreter and imports)."""
    many = design_file(tmp_path / "many.npz", count=200_000)
    big = design_file(tmp_path / "big-header.npz", head=header(controller="x" * 50_000_000))
    assert many.stat().st_size < 4_000_000 and big.stat().st_size < 1_000_000
    flags = ["--port", "0"] if command == "serve" else ["--no-progress"]
    nothing, nothing_seconds, nothing_mb = capped(command, "--design", str(tmp_path / "missing.npz"), *flags)
    assert nothing.returncode == 2 and "No such file" in nothing.stderr
    for path, said in ((many, "it holds 200,000 light patterns; a design holds at most 10,000"),
                       (big, "its header is 50,001,905 characters of JSON; at most 1,500,000")):
        out, seconds, peak_mb = capped(command, "--design", str(path), *flags)
        assert out.returncode == 2 and out.stderr.count("\n") == 1 and said in out.stderr, out.stderr[-2000:]
        # in about the time of a refusal that reads no file (on a loaded machine both take longer)
        assert seconds < max(5.0, 2 * nothing_seconds) and peak_mb < nothing_mb + 10, \
            (path.name, seconds, nothing_seconds, peak_mb, nothing_mb)
