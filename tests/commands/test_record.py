"""``phototaxis record``: headless HTML replays, GIFs and the command line."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.commands.record import frames, record
from sandbox.commands import main
from sandbox.model.config import Config

TINY = Config(robots=6, boxes=10, steps=60)


def test_frames_cover_the_run():
    steps = [s.step for s in frames(TINY, 25)]
    assert steps == [0, 25, 50, 60]


def test_gif_frames_are_drawn():
    import imageio.v3 as iio

    data = record(TINY, ".gif", every=30, size=128)
    assert data[:6] == b"GIF89a"
    pictures = iio.imread(data, index=None)
    assert pictures.shape[0] == 3 and pictures.shape[1:3] == (128, 128)
    assert len(np.unique(pictures[-1].reshape(-1, pictures.shape[-1]), axis=0)) > 4  # not blank


def test_html_replay_is_standalone():
    html = record(TINY, ".html", every=30).decode("utf-8")
    assert html.lstrip().lower().startswith("<!doctype html")
    assert "__VISER_EMBED_DATA__" in html


def test_a_replay_carries_its_legend_on_the_floor():
    """Issue 24, item 9: a replay has no panel, so the legend is a picture in the scene, beside the arena."""
    assert b"/legend" in record(TINY, ".viser", every=30)


def test_command_line(tmp_path, capsys):
    out = tmp_path / "run.gif"
    code = main(["record", "--robots", "5", "--boxes", "8", "--steps", "40", "--every", "20", "--size", "96",
                 "--no-progress", "--out", str(out)])
    assert code == 0 and out.read_bytes()[:6] == b"GIF89a"
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("args,message", [
    (["--out", "x.txt"], "--out must end in"),
    (["--out", "x.gif", "--every", "0"], "--every"),
    (["--out", "x.gif", "--robots", "-3"], "robots"),
])
def test_command_line_errors(tmp_path, capsys, args, message):
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    assert main(["record", *args]) == 2
    assert message in capsys.readouterr().err


def test_mp4_for_slides(tmp_path):
    pytest.importorskip("imageio_ffmpeg", reason="MP4 needs imageio-ffmpeg (pip install -e '.[mp4]')")
    import imageio.v2 as imageio

    out = tmp_path / "run.mp4"
    out.write_bytes(record(TINY, ".mp4", every=20, size=128))
    reader = imageio.get_reader(out)
    try:
        assert reader.count_frames() == 4 and reader.get_meta_data()["size"] == (128, 128)
    finally:
        reader.close()


def test_command_line_default_covers_the_first_cycle(tmp_path):
    import math

    import imageio.v3 as iio

    from sandbox.model.controller import first_cycle_steps
    from sandbox.shapes import shape_vertices

    out = tmp_path / "cycle.gif"
    args = ["--robots", "5", "--boxes", "8", "--update-every", "2"]
    assert main(["record", *args, "--every", "100", "--size", "64", "--no-progress", "--out", str(out)]) == 0
    cycle = first_cycle_steps(Config(robots=5, boxes=8, update_every=2), shape_vertices("circle"))
    assert 100 < cycle < 1000
    assert iio.imread(out, index=None).shape[0] == math.ceil(cycle / 100) + 1
