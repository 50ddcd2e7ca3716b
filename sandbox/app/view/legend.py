"""The legend of the scene, and the colour bar of the sensed-light heat map,
drawn with Pillow in the palette's own colours (so they cannot drift apart).
Pictures made once with Pillow; any thread."""

from __future__ import annotations

import functools

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from sandbox.app.view import palette as pal

WIDTH = 380
ROW = 30
FONT_SIZE = 16


def _font(size: int = FONT_SIZE) -> ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


@functools.cache  # the same picture for the panel, every presenter page's floor and every replay
def legend_picture() -> np.ndarray:
    """Swatches for everything on the floor: lights, robots by charge, boxes,
    the outlines and the walls."""
    rows = [
        ("cell", pal.LIGHT_ON, "light on"),
        ("cell", pal.LIGHT_OFF, "light off"),
        *(("disc", colour, f"robot {name}: {words}") for name, colour, words in pal.CHARGE_CLASSES),
        ("ring", pal.SELECTED, "robot you follow (ring)"),
        ("box", pal.BOX_IN, "box in the goal"),
        ("box", pal.BOX_OUT, "box outside the goal"),
        ("line", pal.GOAL_LINE, "goal outline"),
        ("line", pal.LIGHT_LINE, "outline the lights follow"),
        ("line", pal.BOX_WALL, "wall that stops boxes, not robots"),
        ("line", pal.ARENA_WALL, "arena wall"),
    ]
    img = Image.new("RGB", (WIDTH, ROW * len(rows) + 8), pal.BACKGROUND)
    draw = ImageDraw.Draw(img)
    font = _font()
    for i, (kind, colour, text) in enumerate(rows):
        y = 4 + i * ROW + ROW // 2
        _swatch(draw, kind, colour, 22, y)
        draw.text((58, y), text, fill=(235, 235, 240), font=font, anchor="lm")
    return np.asarray(img)


def _swatch(draw: ImageDraw.ImageDraw, kind: str, colour, x: int, y: int) -> None:
    if kind == "cell":
        draw.rectangle([x - 10, y - 10, x + 10, y + 10], fill=colour, outline=pal.CELL_EDGE)
    elif kind == "disc":
        draw.ellipse([x - 9, y - 9, x + 9, y + 9], fill=colour)
    elif kind == "ring":
        draw.ellipse([x - 9, y - 9, x + 9, y + 9], outline=colour, width=3)
    elif kind == "box":  # a hexagon, as the floor shows a box
        a = np.arange(6) * np.pi / 3
        draw.polygon([(x + 10 * np.cos(t), y + 10 * np.sin(t)) for t in a], fill=colour)
    else:
        draw.line([x - 14, y, x + 14, y], fill=colour, width=4)


def colour_bar_picture(width: int = WIDTH, height: int = 64) -> np.ndarray:
    """The heat map's colours from no light to the brightest on the floor now."""
    img = Image.new("RGB", (width, height), pal.BACKGROUND)
    ramp = np.linspace(0.0, 1.0, width - 24)[None, :].repeat(18, axis=0)
    img.paste(Image.fromarray(pal.field_image(ramp.T, scale=1.0, top_first=False)), (12, 8))
    draw = ImageDraw.Draw(img)
    font = _font(14)
    draw.text((12, 34), "no light", fill=(235, 235, 240), font=font)
    draw.text((width - 12, 34), "brightest now", fill=(235, 235, 240), font=font, anchor="ra")
    return np.asarray(img)
