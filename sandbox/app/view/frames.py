"""Top-down pictures of a snapshot with Pillow, in the page's colours.

Used for GIF / MP4 output of ``phototaxis record`` and for the illustrations
of the Learn panel. No browser, no GPU.
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from sandbox.app.view import palette as pal
from sandbox.app.world.snapshot import Snapshot


def render(snap: Snapshot, size: int = 640, *, show_field: bool = False, robot: int | None = None,
           label: str | None = None) -> Image.Image:
    """One frame of ``snap`` as a square RGB image of ``size`` pixels."""
    cfg = snap.world_config
    s = cfg.arena_size
    k = size / s  # pixels per metre

    def xy(points: np.ndarray) -> list[tuple[float, float]]:
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        return [(float(x * k), float(size - y * k)) for x, y in p]

    if show_field and snap.field is not None:
        floor = Image.fromarray(pal.field_image(snap.field)).resize((size, size), Image.BILINEAR)
    else:
        cells = max(1, int(round(size / cfg.lights_per_side)))
        grid = pal.light_grid_image(snap.intensities, cell_pixels=cells, peak=max(cfg.light_intensity, 1e-9))
        floor = Image.fromarray(grid).resize((size, size), Image.NEAREST)
    img = floor.convert("RGB")
    draw = ImageDraw.Draw(img)
    line = max(1, round(size / 400))
    draw.polygon(xy(pal.square(cfg.centre, cfg.construction_size / 2.0)), outline=pal.BOX_WALL, width=line)
    # Boxes: hexagons.
    r = cfg.box_circumradius
    corners = np.arange(6) * np.pi / 3
    for (x, y), a, inside in zip(snap.box_positions, snap.box_angles, snap.box_in_goal):
        hexagon = np.stack([x + r * np.cos(corners + a), y + r * np.sin(corners + a)], axis=1)
        draw.polygon(xy(hexagon), fill=pal.BOX_IN if inside else pal.BOX_OUT)
    # Robots: discs coloured by charge, with a dark heading mark.
    rr = cfg.robot_radius * k
    colours = pal.robot_colours(snap.robot_charges, cfg.capacity)
    for (x, y), h, col in zip(snap.robot_positions, snap.robot_headings, colours):
        (px, py), = xy([[x, y]])
        draw.ellipse([px - rr, py - rr, px + rr, py + rr], fill=tuple(int(v) for v in col))
        draw.line([px, py, px + 0.95 * rr * np.cos(h), py - 0.95 * rr * np.sin(h)], fill=pal.HEADING_MARK,
                  width=max(1, round(rr / 3)))
    if len(snap.outline) >= 2:
        draw.polygon(xy(snap.outline), outline=pal.LIGHT_LINE, width=line)
    if len(snap.goal_outline) >= 2:
        draw.polygon(xy(snap.goal_outline), outline=pal.GOAL_LINE, width=line + 1)
    draw.rectangle([0, 0, size - 1, size - 1], outline=pal.ARENA_WALL, width=line + 1)
    if robot is not None and 0 <= robot < len(snap.robot_positions):
        (px, py), = xy(snap.robot_positions[robot:robot + 1])
        rad = 2.2 * rr + 3
        draw.ellipse([px - rad, py - rad, px + rad, py + rad], outline=pal.SELECTED, width=line + 1)
    if label:  # readable on a slide: about 1/32 of the frame, at least 11 px
        font = ImageFont.load_default(size=max(11, size // 34))
        while font.getlength(label) > size - 12 and font.size > 8:
            font = ImageFont.load_default(size=font.size - 1)
        band = font.size + 10
        draw.rectangle([0, 0, size, band], fill=pal.BACKGROUND)
        draw.text((6, band // 2), label, fill=(235, 235, 240), font=font, anchor="lm")
    return img
