"""The pictures that explain the scene: the legend, the heat map's colour bar
and the Learn figures. They are drawn from the palette and the controller, so
these tests check that they say what they claim, not how they look."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.app.panel import learn
from sandbox.app.view import legend
from sandbox.app.view import palette as pal
from sandbox.model.config import Config


def _text_rows(img: np.ndarray, top: int, bottom: int) -> int:
    """Rows of a caption band that hold light (text) pixels."""
    band = img[top:bottom].astype(int)
    return int((band.min(axis=2) > 180).any(axis=1).sum())


def test_legend_swatches_use_the_scene_colours():
    img = legend.legend_picture()
    colours = {tuple(c) for c in img.reshape(-1, 3)}
    for colour in (pal.LIGHT_ON, pal.BOX_IN, pal.GOAL_LINE, pal.LIGHT_LINE):
        assert tuple(int(v) for v in colour) in colours


def test_colour_bar_runs_from_no_light_to_the_brightest():
    img = legend.colour_bar_picture()
    dark, bright = pal.field_image(np.array([[0.0]]), scale=1.0)[0, 0], pal.field_image(np.array([[1.0]]), scale=1.0)[0, 0]
    row = img[15]
    assert np.abs(row[12].astype(int) - dark).sum() < 10
    assert np.abs(row[-13].astype(int) - bright).sum() < 30


def test_the_heat_maps_colours_are_matplotlibs_inferno():
    colormaps = pytest.importorskip("matplotlib").colormaps
    inferno = np.round(colormaps["inferno"](np.linspace(0, 1, 256))[:, :3] * 255).astype(np.uint8)
    assert np.array_equal(pal._heat_lut(), inferno)


def test_learn_captions_are_readable():
    img = learn.cycle_picture()
    assert _text_rows(img, 0, learn.CAPTION + 8) >= 10  # the old captions were 7 px tall


def test_switch_picture_shows_a_circle_where_the_star_was():
    cfg = Config()
    from sandbox.model.config import CASES

    switch = CASES["star-switch"]["switch"]
    steps = learn._switch_step(cfg, "star", switch)
    plain, outline_plain, _ = learn._pattern(cfg, "star", steps)
    switched, outline_switched, _ = learn._pattern(cfg, "star", steps, switch=switch)
    # The lit outline with switch is a circle: all its points at one distance from its centre.
    r = np.hypot(*(outline_switched - outline_switched.mean(axis=0)).T)
    assert r.std() < 0.02 * r.mean()
    r_star = np.hypot(*(outline_plain - outline_plain.mean(axis=0)).T)
    assert r_star.std() > 0.1 * r_star.mean()
    assert not np.array_equal(plain, switched)
    assert learn.strategies_picture().shape[0] > 3 * 200  # three rows of two


def test_box_mesh_colours_are_what_the_page_needs_to_show_the_box_colours():
    """The hexagons are lit meshes: their colours are the bounded least-squares solutions of
    shown_on_mesh(x) = box colour, solved here again (the app does not import scipy.optimize)."""
    from scipy.optimize import least_squares

    for shown, given in ((pal.BOX_IN, pal.BOX_IN_MESH), (pal.BOX_OUT, pal.BOX_OUT_MESH)):
        target = np.asarray(shown, dtype=float)
        fit = least_squares(lambda x: pal.shown_on_mesh(x) - target, np.clip(target, 1, 254), bounds=(0.0, 255.0))
        assert tuple(int(v) for v in np.round(fit.x)) == given
    # Measured in the page: the mesh colour (255, 92, 168) shows as (231, 181, 209).
    assert np.allclose(pal.shown_on_mesh((255, 92, 168)), (231, 181, 209), atol=1.5)
    assert pal.box_mesh_colours(np.array([True, False])).tolist() == [list(pal.BOX_IN_MESH), list(pal.BOX_OUT_MESH)]


@pytest.mark.parametrize("name", sorted(learn.PICTURES))
def test_the_stored_learn_pictures_are_what_the_engine_draws(name):
    """The server shows the stored pictures; the engine draws the same (text may differ by a few
    pixels where another Pillow renders its font). Run ``python -m sandbox.app.panel.learn`` when this fails."""
    drawn, stored = learn.PICTURES[name](), learn.stored_picture(name)
    assert drawn.shape == stored.shape, f"{name}: drawn {drawn.shape}, stored {stored.shape}"
    differ = (np.abs(drawn.astype(int) - stored.astype(int)).max(axis=-1) > 40).mean()
    assert differ < 0.01, f"{name}: {100 * differ:.1f} % of the pixels differ; python -m sandbox.app.panel.learn"
