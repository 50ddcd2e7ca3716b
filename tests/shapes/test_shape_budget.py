"""Polygon files that ask for more work than a goal can use are refused before the work, within
a time and memory bound (issue 39, hole 2): the reader the page and ``run --shape`` share, the
count of an SVG's points and elements, the first self-crossing of a star, the child process an
upload is read in."""

from __future__ import annotations

import math
import time
import tracemalloc

import pytest
import svgelements

from sandbox.shapes import MAX_BYTES, ShapeError
from sandbox.shapes.formats import read_polygon_bytes
from sandbox.shapes.svg import CURVE_POINTS, _outline
from sandbox.shapes.svg_budget import path_points
from tests.commands.test_cli import SMALL, phototaxis

SVG = '<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink">{}</svg>'
#: What the measurement allows the reader, in CPU seconds and bytes: it took 9.5 s and 209 MB of peak
#: memory for 30,000 arcs before the count, 0.05 s and 3 MB after.
SECONDS, BYTES = 2.0, 50_000_000


def svg_of_arcs(count: int = 32_000) -> bytes:
    """A path of ``count`` small arcs around a circle: the issue's 780 KB file."""
    ends = (f"A5 5 0 0 1 {100 * math.cos(2 * math.pi * i / count):.3f} "
            f"{100 * math.sin(2 * math.pi * i / count):.3f}" for i in range(1, count))
    return SVG.format(f'<path d="M100 0 {" ".join(ends)} Z"/>').encode()


def svg_of_cubics(count: int = 19_000) -> bytes:
    """A path of ``count`` cubic curves around a circle: the issue's 840 KB file."""
    def point(i: int) -> str:
        return f"{100 * math.cos(2 * math.pi * i / count):.2f} {100 * math.sin(2 * math.pi * i / count):.2f}"
    curves = (f"C{point(i)} {point(i)} {point(i)}" for i in range(1, count))
    return SVG.format(f'<path d="M100 0 {" ".join(curves)} Z"/>').encode()


def refusal_cost(data: bytes, name: str) -> tuple[str, float, int]:
    """The reader's message, the CPU seconds it took (wall time on a loaded machine says more about
    the machine) and the peak of the memory Python allocated for it (in a second reading: tracing
    slows the first)."""
    start = time.thread_time()
    with pytest.raises(ShapeError) as refused:
        read_polygon_bytes(data, name)
    seconds = time.thread_time() - start
    tracemalloc.start()
    try:
        with pytest.raises(ShapeError):
            read_polygon_bytes(data, name)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return str(refused.value), seconds, peak


@pytest.mark.parametrize("name, make", [("arcs.svg", svg_of_arcs), ("cubics.svg", svg_of_cubics)])
def test_a_megabyte_of_curves_is_refused_before_it_is_flattened(name, make):
    data = make()
    assert 750_000 < len(data) <= MAX_BYTES
    message, seconds, peak = refusal_cost(data, name)
    assert message == (f"{name}: the <path> has more than 10,000 points once its curves are flattened; "
                       "at most 10,000 are supported (simplify the outline)")
    assert seconds < SECONDS and peak < BYTES, f"{seconds:.2f} s, {peak / 1e6:.0f} MB"


def test_copies_and_floods_of_elements_are_refused_before_they_are_made():
    # Seven levels of ten <use> each: ten million triangles from 2 KB. svgelements ran for minutes.
    levels = ['<path id="p0" d="M0 0 L1 0 L0 1 Z"/>'] + [
        f'<g id="p{k}">' + f'<use xlink:href="#p{k - 1}"/>' * 10 + "</g>" for k in range(1, 8)]
    bomb = SVG.format(f'<defs>{"".join(levels)}</defs><use xlink:href="#p7"/>').encode()
    circle = SVG.format('<g id="a"><use href="#b"/></g><g id="b"><use href="#a"/></g>').encode()
    flood = SVG.format('<rect x="0" y="0" width="1" height="1"/>' * 20_000).encode()
    deep = SVG.format("<g>" * 12_000 + '<path d="M0 0 L1 0 L0 1 Z"/>' + "</g>" * 12_000).encode()
    for name, data, words in [("bomb.svg", bomb, "more than 20,000 elements and points once its <use> copies"),
                              ("circle.svg", circle, "once its <use> copies are made"),
                              ("flood.svg", flood, "the SVG has 20,001 elements; at most 10,000 are read"),
                              ("deep.svg", deep, "the SVG has 12,002 elements")]:
        message, seconds, peak = refusal_cost(data, name)
        assert message.startswith(f"{name}: ") and words in message, message
        assert seconds < SECONDS and peak < BYTES, f"{name}: {seconds:.2f} s, {peak / 1e6:.0f} MB"


@pytest.mark.parametrize("d", ["M0 0 L10 0 L10 10 Z", "m 1 1 2 0 0 2 -2 0 Z", "M0 0 H10 V10 h-10 z",
                               "M0 0 C1 1 2 2 3 3 4 4 5 5 6 6", "M0 0 Q1 1 2 2 T4 4 6 6 S7 7 8 8",
                               "M0 0 A5 5 0 0 1 10 0 5 5 0 1 1 0 0", "M0 0L1.5.5-2e1-3E-1 4 4z"])
def test_a_paths_count_is_the_points_it_is_flattened_into(d):
    assert path_points(d, CURVE_POINTS) == len(_outline(svgelements.Path(d), "p.svg"))


def test_arcs_with_flags_written_together_are_counted_on_the_low_side():
    d = "M0 0 a5 5 0 0110 0 5 5 0 1110 0"  # "0110" is the flags 0 and 1, then 10
    assert path_points(d, CURVE_POINTS) <= len(_outline(svgelements.Path(d), "p.svg"))


def test_a_run_of_digits_before_a_stray_letter_is_refused_at_once():
    """The points check once tried every way to split the digits into numbers: 10 s for sixteen."""
    data = SVG.format(f'<polygon points="0,0 1,0 {"1" * 40}x"/>').encode()
    message, seconds, _ = refusal_cost(data, "digits.svg")
    assert message == "digits.svg: the <polygon> points attribute is not a list of numbers"
    assert seconds < SECONDS, f"{seconds:.2f} s"


def test_a_star_of_many_crossings_is_refused_at_its_first():
    """Every edge of a {2999/1499} star crosses nearly every other: 4.5 million pairs, which listing
    all at once took half a minute (a 999-point star took 5 s)."""
    n = 2999
    angles = [2 * math.pi * (i * (n // 2) % n) / n for i in range(n)]
    text = "\n".join(f"{math.cos(a):.9f} {math.sin(a):.9f}" for a in angles).encode()
    message, seconds, peak = refusal_cost(text, "star.txt")
    assert "crosses itself" in message and "lines 1-2, 3-4" in message, message
    assert seconds < SECONDS and peak < BYTES, f"{seconds:.2f} s, {peak / 1e6:.0f} MB"


def test_run_refuses_a_megabyte_of_arcs_in_one_line(tmp_path):
    path = tmp_path / "big.svg"
    path.write_bytes(svg_of_arcs())
    start = time.thread_time()  # the command runs in this thread; its CPU time is what the file costs
    out = phototaxis("run", "--shape", str(path), *SMALL)
    seconds = time.thread_time() - start
    assert out.returncode == 2 and out.stderr.count("\n") == 1, out.stderr
    assert "big.svg: the <path> has more than 10,000 points" in out.stderr and "Traceback" not in out.stderr
    assert seconds < SECONDS, f"{seconds:.1f} s"


@pytest.mark.slow  # the first child of a test worker starts the fork server: seconds on a loaded machine
def test_an_upload_is_read_in_a_child_within_its_time_and_memory():
    """The page's reader: a good file's vertices come back; a file too slow or too large for the
    child's limits is refused in one line, the child ended (0.01 s is less than a child takes to start,
    and no memory at all less than a polygon of 3,000 vertices needs)."""
    from sandbox.shapes.isolated import read_polygon_isolated

    triangle = read_polygon_isolated(b"0 0\n6 0\n3 5\n", "tri.txt")
    assert triangle.tolist() == [[0, 0], [6, 0], [3, 5]]
    star = "\n".join(f"{math.cos(4 * math.pi * i / 2999):.9f} {math.sin(4 * math.pi * i / 2999):.9f}"
                     for i in range(2999)).encode()
    with pytest.raises(ShapeError, match=r"^star.txt: took more than 0.01 s to read"):
        read_polygon_isolated(star, "star.txt", time_limit=0.01)
    with pytest.raises(ShapeError, match=r"^star.txt: needs more than 0 MB to read$"):  # not slow: any load
        read_polygon_isolated(star, "star.txt", memory_limit=0, time_limit=60.0)


class _Pipe:
    """A reader's end of the pipe to the server, whose send may run out of memory."""

    def __init__(self, fails: bool = False):
        self.fails, self.sent = fails, []

    def send(self, answer):
        if self.fails:
            raise MemoryError
        self.sent.append(answer)

    def close(self):
        pass


def test_a_reader_out_of_memory_says_so_even_with_no_memory_left_to_send_it(monkeypatch):
    """Out of memory, the reader sends the refusal it made before its limit; when even the send fails, it
    ends with OUT_OF_MEMORY, which the server reads as the same refusal (a traceback, exit code 1, would
    have said only that the reader stopped)."""
    from sandbox.shapes import isolated

    def out_of_memory(data, name):
        raise MemoryError

    monkeypatch.setattr(isolated, "_limit_memory", lambda limit: None)  # not this test process's memory
    monkeypatch.setattr(isolated, "read_polygon_bytes", out_of_memory)
    pipe = _Pipe()
    isolated._read_in_child(pipe, b"", "big.svg", 64 * 2**20)
    assert pipe.sent == [("refused", "big.svg: needs more than 64 MB to read")]

    exits = []
    monkeypatch.setattr(isolated.os, "_exit", exits.append)
    isolated._read_in_child(_Pipe(fails=True), b"", "big.svg", 64 * 2**20)
    assert exits == [isolated.OUT_OF_MEMORY]
    assert str(isolated._stopped("big.svg", isolated.OUT_OF_MEMORY, 64 * 2**20)) == \
        "big.svg: needs more than 64 MB to read"
    assert str(isolated._stopped("big.svg", -9, 64 * 2**20)) == \
        "big.svg: could not be read (the reader stopped with exit code -9)"
