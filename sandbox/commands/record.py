"""``phototaxis record``: a run, captured headless, as a file to share.

- ``.html``: one standalone page that replays the run in any browser, with no
  server (viser's scene serializer; the same scene as the live sandbox).
- ``.viser``: the raw viser recording.
- ``.gif`` / ``.mp4``: an animation for slides, frames drawn top-down with
  Pillow in the page's colours (MP4 needs the ``imageio-ffmpeg`` package).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import time
from pathlib import Path
from typing import Any, Callable

from tqdm import tqdm

from sandbox.app.view.frames import render
from sandbox.app.world.runner import Runner
from sandbox.app.view.scene import SceneView, add_floor_legend, configure_scene
from sandbox.commands.serve import free_port
from sandbox.app.world.snapshot import caption
from sandbox.cli import UserError, add_config_arguments, config_from_args
from sandbox.model.config import Config
from sandbox.model.controller import first_cycle_steps
from sandbox.shapes import shape_vertices

FORMATS = (".html", ".viser", ".gif", ".mp4")


def add_parser(sub: Any) -> argparse.ArgumentParser:

    p = sub.add_parser("record", help="record a run headless as a replayable HTML page, a GIF or an MP4",
                       description="Run the simulation headless and write it to FILE: .html (standalone page "
                       "that replays in any browser), .viser, .gif or .mp4 (for slides).")
    p.add_argument("--out", required=True, metavar="FILE", help="output file: .html, .viser, .gif or .mp4")
    p.add_argument("--every", type=int, default=50, metavar="N",
                   help="world steps between two recorded frames (default 50)")
    p.add_argument("--fps", type=float, default=15.0, help="playback frames per second (default 15)")
    p.add_argument("--size", type=int, default=512, metavar="PX", help="GIF / MP4 frame size in pixels (default 512)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_config_arguments(p)
    p.set_defaults(func=record_command)
    p.epilog = "Without --steps, the recording covers the first full contract-hold-dilate cycle."
    return p


def record_command(args: argparse.Namespace) -> int:

    config = config_from_args(args)
    if args.steps is None:  # one full cycle: what a viewer needs to see the method work
        config = config.replace(steps=first_cycle_steps(config, shape_vertices(config.shape)))
    out = Path(args.out)
    suffix = out.suffix.lower()
    if suffix not in FORMATS:
        raise UserError(f"--out must end in one of {', '.join(FORMATS)} (got {args.out!r})")
    if args.every < 1:
        raise UserError("--every must be at least 1")
    if not 0.1 <= args.fps <= 120:
        raise UserError("--fps must be between 0.1 and 120")
    if not 64 <= args.size <= 4096:
        raise UserError("--size must be between 64 and 4096 pixels")
    if suffix == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise UserError("writing .mp4 needs the imageio-ffmpeg package: pip install -e '.[mp4]'") from None
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create {out.parent}: {exc.strerror or exc}") from None
    started = time.perf_counter()
    with tqdm(total=config.steps, unit="step", desc="recording", file=sys.stderr, disable=args.no_progress,
              dynamic_ncols=True) as bar:
        data = record(config, suffix, every=args.every, fps=args.fps, size=args.size,
                      progress=lambda step: bar.update(step - bar.n))
    try:
        out.write_bytes(data)
    except OSError as exc:
        raise UserError(f"cannot write {out}: {exc.strerror or exc}") from None
    print(f"wrote {out} ({len(data) / 1e6:.1f} MB, {config.steps} steps, "
          f"{time.perf_counter() - started:.0f} s)")
    return 0


def frames(config: Config, every: int, shape: Any = "from-config", progress: Callable[[int], None] | None = None):
    """Snapshots of a headless run: the start, then every ``every`` steps to ``config.steps``."""
    runner = Runner(config, shape=shape, playing=False)
    yield runner.latest
    while runner.sim.steps_done < config.steps:
        n = min(every, config.steps - runner.sim.steps_done)
        snap = runner.advance(n)
        if progress:
            progress(snap.step)
        yield snap


def record(config: Config, kind: str = ".html", *, every: int = 50, fps: float = 15.0, size: int = 512,
           shape: Any = "from-config", progress: Callable[[int], None] | None = None) -> bytes:
    """Run ``config.steps`` steps and return the recording as bytes of the given kind."""
    if kind in (".html", ".viser"):
        return _record_viser(config, kind, every, fps, shape, progress)
    return _record_animation(config, kind, every, fps, size, shape, progress)


def _record_animation(config: Config, kind: str, every: int, fps: float, size: int, shape: Any,
                      progress: Callable[[int], None] | None) -> bytes:
    import imageio.v3 as iio
    import numpy as np

    pictures = [np.asarray(render(snap, size, label=caption(snap)))
                for snap in frames(config, every, shape, progress)]
    if kind == ".gif":
        buffer = io.BytesIO()
        iio.imwrite(buffer, pictures, extension=".gif", duration=1000.0 / fps, loop=0)
        return buffer.getvalue()
    return _mp4(pictures, fps)


def _mp4(pictures: list, fps: float) -> bytes:
    """H.264 through imageio-ffmpeg (its own ffmpeg binary), via a temporary file."""
    import tempfile

    import imageio.v2 as imageio

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "run.mp4"
        writer = imageio.get_writer(path, format="FFMPEG", fps=fps, codec="libx264", quality=7,
                                    macro_block_size=16, pixelformat="yuv420p")
        try:
            for picture in pictures:
                writer.append_data(picture)
        finally:
            writer.close()
        return path.read_bytes()


def _record_viser(config: Config, kind: str, every: int, fps: float, shape: Any,
                  progress: Callable[[int], None] | None) -> bytes:
    import viser

    with contextlib.redirect_stdout(io.StringIO()):  # viser prints a banner
        server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        configure_scene(server, config)
        add_floor_legend(server.scene, config)
        serializer = server.get_scene_serializer()
        view = None
        for snap in frames(config, every, shape, progress):
            if view is None:
                view = SceneView(server.scene, snap)  # draws the caption too
            else:
                view.update(snap)
            serializer.insert_sleep(1.0 / fps)
        if kind == ".viser":
            return serializer.serialize()
        return serializer.as_html(dark_mode=True).encode("utf-8")
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
