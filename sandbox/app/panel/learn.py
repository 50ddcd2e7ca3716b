"""The Learn panel: a short illustrated explanation of the model.
Its text and pictures are built once; the folder runs on the app's event thread.

The illustrations are drawn from the engine itself (its controller and light
grid), so they always match what the simulation does. They are drawn once,
stored as PNG files beside this module (``pictures/``) and read by the web
server: drawing them took the server most of a second at every start, most
of it loading numba for the controller, which nothing else in the server
needs. ``tests/app/view/test_pictures.py`` draws them again and fails when the stored
ones differ; ``python -m sandbox.app.panel.learn`` stores them anew.
"""

from __future__ import annotations

import io
from importlib import resources
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from sandbox.app.view import palette as pal
from sandbox.model.chase import ChaseController
from sandbox.model.config import Config
from sandbox.model.family import make_goal
from sandbox.model.lights import LightField
from sandbox.model.phases import DILATING
from sandbox.model.robots import PHOTOCELLS
from sandbox.shapes import shape_vertices

INTRO = """\
**Phototaxis.** Each robot has four photocells at the corners of its body
(front-left, front-right, back-left, back-right). Every 50 steps it reads
them and sets its motors once: the brighter its front pair than its back
pair, the faster it drives; the brighter its front-left than its
front-right, the faster it turns left. It then coasts on that command until
the next reading (or until it bumps into something). So
it climbs toward brighter light, overshoots a little, and settles where the
light is brightest. It cannot see other robots, boxes or where it is.

**Powered by light.** The same light charges the robot's store; moving and
living spend it. Colour shows charge: **green** more than half full, **amber**
half or less, **red** empty. An empty robot stops until light reaches it again.

This is how the authors' program works (the profile called authors-code).
The paper's text describes photocells on the body's axes and a motor that
follows the command all the time: pick the profile paper-text under
Population and physics (its group *Model*) to see it.
"""

CYCLE = """\
**Contract, hold, dilate.** Overhead lights are switched on along an outline
of the goal shape (yellow cells; orange line). The outline shrinks toward the
centre, the robots ride the bright band inward and bulldoze the boxes (white)
into the goal (blue line; boxes inside turn **pink**). It holds at its
smallest size, then grows back to the edge to spread the robots out, and the
cycle repeats. The paper's controller never looks at robots or boxes: it is open loop.
The grey square is a wall that stops boxes but lets robots through.
"""

STRATEGIES = """\
**Strategies** (switch them in *Strategies*; they act at the next update).
Each *Show me* runs the paper's case without the strategy (left) beside
the case with it (right), from the same seed (see *Compare*):
"""

#: Each strategy's paragraph and the two worlds its *Show me* button compares (without it, with it):
#: paper case names, or compare mode's ``star + chase`` (sandbox.app.world.lockstep.COMPARE_CASES).
STRATEGY_LESSONS = (
    ("""\
- **Flare** pushes the outline's corners out, more for sharper corners, so
  robots reach into corners instead of rounding them off. As in the
  authors' program, every corner is pushed out, a star's inner corners too
  (the paper's text pushes only the outer, convex ones).""", ("square", "square-flare")),
    ("""\
- **Switch to circle** uses a circle for the outer part of the cycle, which
  spreads robots evenly instead of letting them bunch at far vertices.""", ("star", "star-switch")),
    ("""\
- **No corners** leaves the band lights nearest the corners dark, so robots
  do not pile up in sharp points (and light is saved).""", ("star-switch", "star-switch-nocorners")),
    ("""\
- **Chase stray boxes** closes the loop: it looks at the boxes (as an
  overhead camera would). The band runs the same distance from every part
  of the goal (the goal grown, not scaled), so robots reach a star's tips
  and its notches together. It grows back only until it is a couple of
  metres beyond the farthest box still outside the goal, not to the edge.
  Near the goal it presses in where boxes spill out and goes dark where
  the goal still lacks boxes, so the pile flows there; and it holds the
  smallest outline as long as boxes keep arriving. More boxes end in the
  goal, with less light.""", ("star", "star + chase")),
)

STRATEGIES_MORE = """\
- **A goal already built**: set *box start* to *packed* (under
  *Population and physics*) and reset. The boxes start tiled in the goal,
  and you see what a strategy keeps of a finished shape rather than how
  well it gathers one: chase keeps about 86 % of a star, but gathers only
  82 % from scattered boxes, which jam more loosely than a tiling.
- **Light program** (its own folder) hands the lights to a Python class of
  your own: each update it is told the step and the goal (and the boxes or
  robots, if it asks to sense them) and returns one intensity per light.

Below, each strategy (right) beside the same moment without it (left).
"""

INSPECT = """\
**Inspector.** Click a robot on the floor to follow it (it gets a purple
ring; its photocells show as dots). Its readings, command and charge update
live below; your view zooms in on it (untick *Camera follows* to see the whole arena).
"""


def _pattern(config: Config, shape: str, steps: int = 0, **strategies: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    cfg = config.replace(**strategies)
    goal = make_goal(cfg, shape_vertices(shape))
    ctrl = ChaseController(cfg, goal)
    for _ in range(steps):
        ctrl.advance()
    return ctrl.intensities.copy(), ctrl.outline.copy(), goal.outline().copy()


def _smallest(config: Config, shape: str, **strategies: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pattern at the smallest size (for chase: with no boxes seen, the plain grown goal)."""
    cfg = config.replace(**strategies)
    goal = make_goal(cfg, shape_vertices(shape))
    ctrl = ChaseController(cfg, goal)
    ctrl.scale = ctrl.min_scale
    ctrl.redraw()
    return ctrl.intensities.copy(), ctrl.outline.copy(), goal.outline().copy()


#: Caption size in picture pixels: the panel shows a two-tile row at about
#: 0.9x, so 17 px reads as about 15 px on screen (the old default font was 7).
CAPTION = 17
TEXT = (235, 235, 240)


def _font(size: int = CAPTION) -> ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


def _tile(config: Config, intensities: np.ndarray, outline: np.ndarray, goal: np.ndarray, label: str,
          cell: int = 3, view: float | None = None) -> Image.Image:
    img = Image.fromarray(pal.light_grid_image(intensities, cell_pixels=cell)).convert("RGB")
    size = img.size[0]
    k = size / config.arena_size
    draw = ImageDraw.Draw(img)

    def xy(p: np.ndarray) -> list[tuple[float, float]]:
        return [(float(x * k), float(size - y * k)) for x, y in np.asarray(p)]

    draw.polygon(xy(outline), outline=pal.LIGHT_LINE, width=2)
    draw.polygon(xy(goal), outline=pal.GOAL_LINE, width=2)
    if view:  # only the middle ``view`` metres, enlarged (drawn first, so lines stay 2 px at full size)
        half = view / 2.0 * k
        mid = size / 2.0
        img = img.crop((round(mid - half), round(mid - half), round(mid + half), round(mid + half)))
        img = img.resize((size, size), Image.NEAREST)
    top = CAPTION + 8
    out = Image.new("RGB", (size, size + top), pal.BACKGROUND)
    out.paste(img, (0, top))
    ImageDraw.Draw(out).text((3, 3), label, fill=TEXT, font=_font())
    return out


def _grid(tiles: list[Image.Image], columns: int = 2, gap: int = 8) -> np.ndarray:
    """Tiles in rows of ``columns`` (two keep captions readable in the panel)."""
    w, h = tiles[0].size
    rows = -(-len(tiles) // columns)
    out = Image.new("RGB", (columns * w + (columns - 1) * gap, rows * h + (rows - 1) * gap), pal.BACKGROUND)
    for i, t in enumerate(tiles):
        out.paste(t, ((i % columns) * (w + gap), (i // columns) * (h + gap)))
    return np.asarray(out)


def phototaxis_picture(config: Config | None = None, size: int = 300) -> np.ndarray:
    """A robot near a lit band: the field it senses and its four photocells."""
    cfg = config or Config()
    lights = LightField(cfg)
    on = np.zeros((cfg.lights_per_side,) * 2)
    on[:, cfg.lights_per_side // 2] = 1.0  # a horizontal band of lights
    lights.set_intensities(on)
    span = 6.0  # metres shown
    c = cfg.arena_size / 2
    xs = np.linspace(c - span / 2, c + span / 2, size)
    gx, gy = np.meshgrid(xs, xs[::-1])
    lum = lights.sample(np.stack([gx, gy], axis=-1))
    img = Image.fromarray(pal.field_image(lum.T[:, ::-1], scale=float(lum.max()))).convert("RGB")
    draw = ImageDraw.Draw(img)
    k = size / span
    rx, ry = size * 0.42, size * 0.78
    heading = np.radians(60)
    r = 0.45 * k
    draw.ellipse([rx - r, ry - r, rx + r, ry + r], fill=(170, 200, 60), outline=(20, 20, 20))
    cells = PHOTOCELLS[cfg.photocells]
    small, big = _font(15), _font(CAPTION)
    short = ["".join(word[0].upper() for word in name.split("-")) for name in cells.names]
    for name, a in zip(short, cells.angles):
        sx, sy = rx + 0.7 * r * np.cos(heading + a), ry - 0.7 * r * np.sin(heading + a)
        draw.ellipse([sx - 4, sy - 4, sx + 4, sy + 4], fill=(255, 255, 255), outline=(0, 0, 0))
        draw.text((rx + 1.45 * r * np.cos(heading + a) - 5, ry - 1.45 * r * np.sin(heading + a) - 5), name,
                  fill=(255, 255, 255), font=small)
    ax, ay = rx + 3.2 * r * np.cos(heading), ry - 3.2 * r * np.sin(heading)
    draw.line([rx + 1.8 * r * np.cos(heading), ry - 1.8 * r * np.sin(heading), ax, ay], fill=(255, 255, 255), width=3)
    draw.text((6, 6), "lit band: brightest here", fill=(255, 255, 255), font=big)
    draw.text((6, size - 24), "robot turns and drives up the gradient", fill=(255, 255, 255), font=small)
    return np.asarray(img)


def cycle_picture(config: Config | None = None) -> np.ndarray:
    """The circle goal's cycle: largest, contracting, holding, dilating."""
    cfg = config or Config()
    goal = make_goal(cfg, None)
    ctrl = ChaseController(cfg, goal)
    tiles = [_tile(cfg, ctrl.intensities, ctrl.outline, goal.outline(), "1 start: largest")]
    for label, phase in (("2 contracting", None), ("3 holding: smallest", "holding"), ("4 dilating", DILATING)):
        for _ in range(3000 if phase is None else 10**6):
            ctrl.advance()
            if ctrl.phase == phase:
                break
        if phase == DILATING:
            for _ in range(3000):
                ctrl.advance()
        tiles.append(_tile(cfg, ctrl.intensities, ctrl.outline, goal.outline(), label))
    return _grid(tiles)


def _switch_step(config: Config, shape: str, switch: float) -> int:
    """Steps until a little after switch puts a circle in the polygon's place
    (while dilating): the moment that shows what switch does."""
    cfg = config.replace(switch=switch)
    ctrl = ChaseController(cfg, make_goal(cfg, shape_vertices(shape)))
    steps = 0
    while not (ctrl.phase == DILATING and ctrl.circle_radius is not None) and steps < 200_000:
        ctrl.advance()
        steps += 1
    return steps + 3 * cfg.update_every


def strategies_picture(config: Config | None = None) -> np.ndarray:
    """Each strategy beside the same moment without it."""
    from sandbox.model.config import CASES

    cfg = config or Config()
    switch = CASES["star-switch"]["switch"]
    flare = CASES["square-flare"]["flare"]
    no_corners = CASES["star-switch-nocorners"]["no_corners"]
    switched = _switch_step(cfg, "star", switch)
    tiles = [
        _tile(cfg, *_pattern(cfg, "square", 2500), "square"),
        _tile(cfg, *_pattern(cfg, "square", 2500, flare=flare), "+ flare"),
        _tile(cfg, *_pattern(cfg, "star", switched), "star, dilating"),
        _tile(cfg, *_pattern(cfg, "star", switched, switch=switch), "+ switch: a circle"),
        _tile(cfg, *_pattern(cfg, "star", 2500), "star"),
        _tile(cfg, *_pattern(cfg, "star", 2500, no_corners=no_corners), "+ no corners"),
        _tile(cfg, *_smallest(cfg, "star"), "star, smallest (zoomed)", view=20.0),
        _tile(cfg, *_smallest(cfg, "star", chase=2.0), "+ chase: goal grown", view=20.0),
    ]
    return _grid(tiles)


#: The stored pictures: file name -> how to draw it.
PICTURES = {"learn-phototaxis.png": phototaxis_picture, "learn-cycle.png": cycle_picture,
            "learn-strategies.png": strategies_picture}


def stored_picture(name: str) -> np.ndarray:
    """A picture as stored (one of :data:`PICTURES`), as RGB pixels."""
    data = resources.files("sandbox.app.panel").joinpath("pictures", name).read_bytes()
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


def store_pictures(folder: Path | None = None) -> list[Path]:
    """Draw every picture of :data:`PICTURES` and store it as PNG in ``folder`` (this module's)."""
    folder = folder or Path(__file__).with_name("pictures")
    folder.mkdir(exist_ok=True)
    written = []
    for name, draw in PICTURES.items():
        path = folder / name
        Image.fromarray(draw()).save(path, optimize=True)
        written.append(path)
    return written


if __name__ == "__main__":
    for path in store_pictures():
        print(path)
