"""The Learn panel: a short illustrated explanation of the model.

The illustrations are drawn from the engine itself (its controller and light
grid), so they always match what the simulation does.
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from sandbox.app import palette as pal
from sandbox.model.config import Config
from sandbox.model.controller import Controller, make_goal
from sandbox.model.lights import LightField
from sandbox.model.robots import PHOTOCELLS
from sandbox.shapes import shape_vertices

INTRO = """\
**Phototaxis.** Each robot has four photocells at the corners of its body
(front-left, front-right, back-left, back-right). Every 50 steps it reads
them and sets its motors once: forward speed *k_drive x (front pair - back
pair)*, turn rate *k_turn x (front-left - front-right)*; it then coasts on
that command until the next reading (or until it bumps into something). So
it climbs toward brighter light, overshoots a little, and settles where the
light is brightest. It cannot see other robots, boxes or where it is.

**Powered by light.** The same light charges the robot's store; moving and
living spend it. Colour shows charge: **green** full, **red** empty. An empty
robot stops until light reaches it again.

*This is the authors' program (profile* authors-code*); the paper's text
describes photocells on the body's axes and a motor that follows the
command continuously: choose* paper-text *under Population and physics.*
"""

CYCLE = """\
**Contract, hold, dilate.** Overhead lights are switched on along an outline
of the goal shape (yellow cells; orange line). The outline shrinks toward the
centre, the robots ride the bright band inward and bulldoze the boxes (white)
into the goal (blue line; boxes inside turn **pink**). It holds at its
smallest size, then grows back to the edge to spread the robots out, and the
cycle repeats. The controller never looks at robots or boxes: it is open loop.
The grey square is a wall that stops boxes but lets robots through.
"""

STRATEGIES = """\
**Strategies** (switch them in *Strategies*; they act at the next update):

- **Flare** pushes each convex corner out, more for sharper corners, so
  robots reach into corners instead of rounding them off.
- **Switch to circle** uses a circle for the outer part of the cycle, which
  spreads robots evenly instead of letting them bunch at far vertices.
- **No corners** leaves the band lights nearest the corners dark, so robots
  do not pile up in sharp points (and light is saved).
"""

INSPECT = """\
**Inspector.** Click a robot on the floor to follow it (it gets a purple
ring; its photocells show as dots). Its readings, command and charge update
live below; *Camera follows* zooms in on it.
"""


def _pattern(config: Config, shape: str, steps: int = 0, **strategies: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    cfg = config.replace(**strategies)
    goal = make_goal(cfg, shape_vertices(shape))
    ctrl = Controller(cfg, goal)
    for _ in range(steps):
        ctrl.advance()
    return ctrl.intensities.copy(), ctrl.outline.copy(), goal.outline().copy()


def _tile(config: Config, intensities: np.ndarray, outline: np.ndarray, goal: np.ndarray, label: str,
          cell: int = 3) -> Image.Image:
    img = Image.fromarray(pal.light_grid_image(intensities, cell_pixels=cell)).convert("RGB")
    size = img.size[0]
    k = size / config.arena_size
    draw = ImageDraw.Draw(img)

    def xy(p: np.ndarray) -> list[tuple[float, float]]:
        return [(float(x * k), float(size - y * k)) for x, y in np.asarray(p)]

    draw.polygon(xy(outline), outline=pal.LIGHT_LINE, width=1)
    draw.polygon(xy(goal), outline=pal.GOAL_LINE, width=2)
    out = Image.new("RGB", (size, size + 18), pal.BACKGROUND)
    out.paste(img, (0, 18))
    ImageDraw.Draw(out).text((4, 3), label, fill=(235, 235, 240))
    return out


def _row(tiles: list[Image.Image], gap: int = 6) -> np.ndarray:
    w = sum(t.size[0] for t in tiles) + gap * (len(tiles) - 1)
    h = max(t.size[1] for t in tiles)
    out = Image.new("RGB", (w, h), pal.BACKGROUND)
    x = 0
    for t in tiles:
        out.paste(t, (x, 0))
        x += t.size[0] + gap
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
    short = ["".join(word[0].upper() for word in name.split("-")) for name in cells.names]
    for name, a in zip(short, cells.angles):
        sx, sy = rx + 0.7 * r * np.cos(heading + a), ry - 0.7 * r * np.sin(heading + a)
        draw.ellipse([sx - 4, sy - 4, sx + 4, sy + 4], fill=(255, 255, 255), outline=(0, 0, 0))
        draw.text((rx + 1.45 * r * np.cos(heading + a) - 5, ry - 1.45 * r * np.sin(heading + a) - 5), name,
                  fill=(255, 255, 255))
    ax, ay = rx + 3.2 * r * np.cos(heading), ry - 3.2 * r * np.sin(heading)
    draw.line([rx + 1.8 * r * np.cos(heading), ry - 1.8 * r * np.sin(heading), ax, ay], fill=(255, 255, 255), width=3)
    draw.text((6, 6), "lit band: brightest here", fill=(255, 255, 255))
    draw.text((6, size - 18), "robot turns and drives up the gradient", fill=(255, 255, 255))
    return np.asarray(img)


def cycle_picture(config: Config | None = None) -> np.ndarray:
    cfg = config or Config()
    goal = make_goal(cfg, None)
    ctrl = Controller(cfg, goal)
    tiles = [_tile(cfg, ctrl.intensities, ctrl.outline, goal.outline(), "start: largest")]
    for label, phase in (("contracting", None), ("holding: smallest", "holding")):
        for _ in range(3000 if phase is None else 10**6):
            ctrl.advance()
            if ctrl.phase == phase:
                break
        tiles.append(_tile(cfg, ctrl.intensities, ctrl.outline, goal.outline(), label))
    return _row(tiles)


def strategies_picture(config: Config | None = None) -> np.ndarray:
    cfg = config or Config()
    cases = (("square", "square", {}), ("+ flare", "square", dict(flare=1.75)),
             ("star + no corners", "star", dict(no_corners=0.5)))
    tiles = [_tile(cfg, *_pattern(cfg, shape, 2500, **s), label) for label, shape, s in cases]
    return _row(tiles)
