"""Luminosity (SPEC §3) against hand-computed values, and the sampled field
against direct evaluation of the formula."""

import math

import numpy as np
import pytest

from sandbox.model import lights
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.family import make_goal
from sandbox.model.lights import LightField, brightness_kernel, light_centres, luminosity_direct
from sandbox.shapes import shape_vertices


def one_light(config: Config, ix: int, iy: int) -> np.ndarray:
    pattern = np.zeros((config.lights_per_side,) * 2)
    pattern[ix, iy] = 1.0
    return pattern


def test_light_centres_sit_mid_cell():
    c = light_centres(Config())
    assert c.shape == (64, 64, 2)
    assert c[0, 0].tolist() == [0.5, 0.5]
    assert c[10, 3].tolist() == [10.5, 3.5]


PAPER = Config(profile="paper-text")


@pytest.mark.parametrize("k, expected_diag", [(1.0, 0.5), (2.0, 2 ** -1.5)])
def test_single_light_by_hand(k, expected_diag):
    cfg = PAPER.replace(light_falloff=k)
    pattern = one_light(cfg, 20, 30)
    # Straight below: d = h = 1, sin = 1 -> 1.
    # One metre to the side: d = sqrt(2), B = 1/d^k, sin = 1/sqrt(2) -> 2^-(k+1)/2.
    points = np.array([[20.5, 30.5], [21.5, 30.5], [20.5, 29.5]])
    lum = luminosity_direct(points, pattern, cfg)
    assert lum == pytest.approx([1.0, expected_diag, expected_diag])


def test_two_lights_add_and_height_matters():
    cfg = PAPER.replace(light_height=2.0)
    pattern = one_light(cfg, 10, 10) + one_light(cfg, 12, 10)
    # Midway between them: each at horizontal 1 m, d = sqrt(1 + 4) = sqrt(5).
    # B = 1/sqrt(5), sin = 2/sqrt(5) -> 2/5 each, 4/5 together.
    assert luminosity_direct(np.array([[11.5, 10.5]]), pattern, cfg)[0] == pytest.approx(0.8)


def test_lights_out_of_range_do_not_count():
    cfg = PAPER
    pattern = one_light(cfg, 0, 0)
    # 13 m away in x: beyond the 12.8 m range, so nothing at all.
    assert luminosity_direct(np.array([[13.5, 0.5]]), pattern, cfg)[0] == 0.0
    # 12.5 m away: in range, by the formula.
    expected = 1.0 / (1 + 12.5**2)
    assert luminosity_direct(np.array([[13.0, 0.5]]), pattern, cfg)[0] == pytest.approx(expected)


def test_intensity_scales_linearly():
    cfg = Config()
    pattern = one_light(cfg, 5, 5)
    p = np.array([[6.2, 4.9]])
    assert luminosity_direct(p, 0.3 * pattern, cfg)[0] == pytest.approx(0.3 * luminosity_direct(p, pattern, cfg)[0])


def test_kernel_formula():
    assert brightness_kernel(np.array(0.0), np.array(0.0), 1.0, 1.0) == pytest.approx(1.0)
    assert brightness_kernel(np.array(3.0), np.array(4.0), 1.0, 1.0) == pytest.approx(1.0 / 26.0)


# --- the authors' program (SPEC §9 rows 1-4) --------------------------------

def test_program_single_light_by_hand():
    """Height 2 m, B = I / d^2 and the angle factor sin(atan2(h, hypot(dx^2, dy^2)))."""
    cfg = Config()
    pattern = one_light(cfg, 20, 30)  # centre (20.5, 30.5)
    points = np.array([[20.5, 30.5], [21.5, 30.5], [22.5, 30.5], [22.5, 31.5]])
    expected = [
        1 / 4 * 1.0,                        # below: d^2 = 4, angle factor 1
        1 / 5 * 2 / math.sqrt(4 + 1),       # dx = 1
        1 / 8 * 2 / math.sqrt(4 + 16),      # dx = 2: the squared offset, 2 / sqrt(4 + 2^4)
        1 / 9 * 2 / math.sqrt(4 + 16 + 1),  # dx = 2, dy = 1
    ]
    assert luminosity_direct(points, pattern, cfg) == pytest.approx(expected)
    # The quirk: the paper's elevation angle would give sin = h / d = 2 / sqrt(8) at dx = 2.
    assert expected[2] < 1 / 8 * 2 / math.sqrt(8) * 0.7


def test_program_window_is_one_cell_longer_below_than_above():
    """The program sums light cells floor(x) - 12 .. floor(x) + 11, so a light
    reaches points up to 12.5 m away on one side but only 11.5 m on the other."""
    cfg = Config()
    pattern = one_light(cfg, 20, 30)  # cell 20, centre x = 20.5
    lum = luminosity_direct(np.array([[32.9, 30.5], [33.0, 30.5], [9.0, 30.5], [8.99, 30.5]]), pattern, cfg)
    dx = 12.4
    assert lum[0] == pytest.approx(1 / (dx**2 + 4) * 2 / math.sqrt(4 + dx**4))  # cell 32 = 20 + 12: reached
    assert lum[1] == 0.0  # cell 33: not reached, though only 12.5 m away (< 12.8 m)
    assert lum[2] > 0.0  # cell 9 = 20 - 11: reached, 11.5 m away
    assert lum[3] == 0.0  # cell 8 = 20 - 12 on that side: not reached, 11.51 m away
    # The paper's window is symmetric: both 12.5 m and 11.51 m are in range.
    paper = luminosity_direct(np.array([[33.0, 30.5], [8.99, 30.5]]), pattern, PAPER)
    assert (paper > 0).all()


def test_program_never_reads_the_last_row_or_column():
    cfg = Config()
    last = one_light(cfg, 63, 10)
    assert luminosity_direct(np.array([[63.5, 10.5], [60.0, 10.5]]), last, cfg).tolist() == [0.0, 0.0]
    field = LightField(cfg)
    field.set_intensities(last)
    assert field.display_grid().max() == 0.0
    assert luminosity_direct(np.array([[63.5, 10.5]]), one_light(cfg, 62, 10), cfg)[0] > 0.0


def band_pattern(cfg: Config, shape: str, scale_steps: int = 0) -> np.ndarray:
    controller = Controller(cfg, make_goal(cfg, shape_vertices(shape)))
    for _ in range(scale_steps):
        controller._update()
    return controller.intensities


@pytest.mark.parametrize("profile, k", [("paper-text", 1.0), ("paper-text", 2.0), ("authors-code", 2.0)])
@pytest.mark.parametrize("shape, updates", [("circle", 0), ("star", 30), ("square", 50)])
def test_sampled_field_matches_formula_within_one_percent(profile, k, shape, updates, rng):
    cfg = Config(profile=profile, light_falloff=k)
    pattern = band_pattern(cfg, shape, updates)
    field = LightField(cfg)
    field.set_intensities(pattern)
    points = rng.uniform(0.0, cfg.arena_size, size=(3000, 2))
    exact = luminosity_direct(points, pattern, cfg)
    sampled = field.sample(points)
    assert np.abs(sampled - exact).max() <= 0.01 * exact.max()


def test_incremental_updates_agree_with_a_fresh_field(rng):
    cfg = Config()
    controller = Controller(cfg, make_goal(cfg, shape_vertices("star")))
    field = LightField(cfg)
    patterns = []
    for _ in range(60):
        controller._update()
        patterns.append(controller.intensities)
        field.set_intensities(controller.intensities)
    # Jump back to an old pattern, a partial change, a far one.
    for pattern in (patterns[3], patterns[3] * 0.5, patterns[40]):
        field.set_intensities(pattern)
        fresh = LightField(cfg)
        fresh.set_intensities(pattern)
        patched, rebuilt = field.display_grid(), fresh.display_grid()
        assert np.abs(patched - rebuilt).max() < 1e-5 * max(rebuilt.max(), 1.0)


def test_points_outside_arena_are_clamped():
    cfg = PAPER
    field = LightField(cfg)
    field.set_intensities(one_light(cfg, 0, 0))
    inside = field.sample(np.array([[0.0, 0.5]]))
    outside = field.sample(np.array([[-5.0, 0.5]]))
    assert outside[0] == pytest.approx(inside[0])
    assert math.isfinite(outside[0])


def test_compiled_block_adds_equal_one_numpy_add_per_light_bit_for_bit():
    """Overlapping blocks, in an order that is not sorted, with weights 1, -1 and others (a dimmed
    light takes the float32 product first, as numpy's ``block += float32(w) * kernel`` does)."""
    rng = np.random.default_rng(7)
    kernel = rng.random((6, 6), dtype=np.float32)
    values = rng.random((20, 20), dtype=np.float32)
    x0, y0 = np.array([9, 2, 5, 2, 12]), np.array([3, 4, 5, 4, 0])
    weights = np.array([1.0, -1.0, 0.3, 1.0 / 3.0, -2.5])
    expected = values.copy()
    for x, y, w in zip(x0, y0, weights):
        block = expected[x:x + 6, y:y + 6]
        if w == 1.0:
            np.add(block, kernel, out=block)
        elif w == -1.0:
            np.subtract(block, kernel, out=block)
        else:
            block += np.float32(w) * kernel
    lights.compiled_add_blocks(values, kernel, x0, y0, weights)
    assert np.array_equal(values.view(np.uint32), expected.view(np.uint32))
    lights.add_blocks(values, kernel, x0[:0], y0[:0], weights[:0])  # no light: nothing to do
    assert np.array_equal(values.view(np.uint32), expected.view(np.uint32))
