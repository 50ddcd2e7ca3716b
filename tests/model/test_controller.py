"""The light-field controller (SPEC §5)."""

import math

import numpy as np
import pytest

from sandbox.model.config import Config
from sandbox.model.controller import CONTRACTING, DILATING, HOLDING, Controller
from sandbox.model.family import make_goal
from sandbox.shapes import geometry, shape_vertices


def controller(shape="circle", **changes) -> Controller:
    """A controller of the paper text's model (profile paper-text)."""
    cfg = Config(profile="paper-text", **changes)
    return Controller(cfg, make_goal(cfg, shape_vertices(shape)))


@pytest.mark.parametrize("profile, box_area, centre", [
    ("paper-text", 2 * math.sqrt(3) * 0.25**2, 32.0),       # hexagon of apothem 0.25
    ("authors-code", 1.5 * math.sqrt(3) * 0.25**2, 32.5),   # hexagon of circumradius 0.25, on a light
])
@pytest.mark.parametrize("shape", ["circle", "square", "star", "l-shape"])
def test_goal_area_equals_total_box_area(shape, profile, box_area, centre):
    cfg = Config(profile=profile)
    goal = make_goal(cfg, shape_vertices(shape))
    assert goal.area == pytest.approx(500 * box_area)
    assert goal.centre.tolist() == [centre, centre]
    if not goal.is_circle:
        assert abs(geometry.signed_area(goal.vertices)) == pytest.approx(500 * box_area)
        # the centroid on the centre, unless the goal was moved inside the wall that stops the boxes
        assert geometry.centroid(goal.vertices) == pytest.approx(np.add([centre, centre], goal.moved))


def test_box_size_as_circumradius():
    cfg = Config(box_size_is="circumradius")
    assert cfg.box_area == pytest.approx(0.16238, abs=1e-5)  # the program's 81.19 m^2 for 500 boxes
    assert cfg.box_apothem == pytest.approx(0.25 * math.cos(math.pi / 6))


def test_sizes_for_the_circle():
    c = controller()
    r = c.goal.radius
    assert c.min_scale * r == pytest.approx(r + 0.5)  # plus one robot diameter
    assert c.max_scale * r == pytest.approx(0.75 * 32)


def test_polygon_max_fits_inside_arena():
    c = controller("star")
    biggest = c.goal.centre + c.max_scale * (c.goal.vertices - c.goal.centre)
    assert biggest.min() >= 0 and biggest.max() <= 64


def run_updates(c: Controller, steps: int) -> list[tuple[str, float]]:
    seen = []
    for _ in range(steps):
        if c.advance():
            seen.append((c.phase, c.scale))
    return seen


def test_full_cycle_contract_hold_dilate_contract():
    c = controller(update_every=10, hold_steps=25)
    assert c.phase == CONTRACTING
    phases = [c.phase]
    held_for = 0
    for _ in range(5000):
        c.advance()
        if c.phase == HOLDING:
            held_for += 1
        if c.phase != phases[-1]:
            phases.append(c.phase)
        if c.cycle == 1 and c.phase == CONTRACTING:
            break
    assert phases == [CONTRACTING, HOLDING, DILATING, CONTRACTING]
    assert held_for == 25
    assert c.cycle == 1
    assert c.scale == pytest.approx(c.max_scale)


def test_scale_changes_by_rate_each_update():
    c = controller(update_every=7)
    start = c.scale
    for _ in range(7 * 3):
        c.advance()
    assert c.scale == pytest.approx(start * 0.975**3)


def test_band_lights_on_circle():
    c = controller()
    centres = (np.argwhere(c.intensities > 0) + 0.5)
    radius = c.goal.radius * c.scale
    d = np.abs(np.hypot(*(centres - 32).T) - radius)
    assert (d <= 0.5 + 1e-9).all() and len(centres) > 0
    # And every light within the band is on.
    all_centres = np.argwhere(np.ones((64, 64))) + 0.5
    should = np.abs(np.hypot(*(all_centres - 32).T) - radius) <= 0.5
    assert should.sum() == len(centres)


def test_switch_to_circle_at_fraction_of_the_way():
    c = controller("square", switch=0.25, update_every=1, hold_steps=1)
    switched_at = None
    while c.cycle == 0:
        c.advance()
        if c.phase == DILATING and c.is_circle and switched_at is None:
            switched_at = c.progress
    assert switched_at is not None and 0.25 <= switched_at < 0.25 + 0.05
    # Contracting: polygon again below the same point.
    while c.progress >= 0.25:
        assert c.is_circle
        c.advance()
    assert not c.is_circle


def test_no_corners_turns_off_the_requested_fraction_nearest_corners():
    plain = controller("square")
    dark = controller("square", no_corners=0.5)
    on_plain = plain.intensities > 0
    on_dark = dark.intensities > 0
    assert on_dark.sum() == on_plain.sum() - round(0.5 * on_plain.sum())
    assert not (on_dark & ~on_plain).any()
    # The lights switched off are nearer to corners than those left on.
    centres = np.argwhere(np.ones((64, 64))) + 0.5
    d = np.hypot(*(centres[:, None, :] - dark.corners[None]).transpose(2, 0, 1)).min(axis=1).reshape(64, 64)
    assert d[on_plain & ~on_dark].max() <= d[on_dark].min() + 1e-9


@pytest.mark.parametrize("profile", ["paper-text", "authors-code"])
@pytest.mark.parametrize("strategy", [dict(), dict(flare=1.75), dict(no_corners=0.5), dict(flare=1.75, no_corners=0.5)])
def test_clockwise_and_counter_clockwise_files_behave_the_same(strategy, profile):
    star = shape_vertices("star")
    cfg = Config(profile=profile, **strategy)
    ccw = Controller(cfg, make_goal(cfg, star))
    cw = Controller(cfg, make_goal(cfg, star[::-1].copy()))
    for _ in range(30):
        ccw._update()
        cw._update()
        assert (ccw.intensities == cw.intensities).all()


def test_flare_moves_corners_out():
    plain, flared = controller("square"), controller("square", flare=1.75)
    assert len(flared.outline) == 2 * len(plain.outline)
    assert np.abs(flared.corners - 32).max() == pytest.approx(1.75 * np.abs(plain.corners - 32).max())


def test_live_strategy_change_waits_for_the_next_update():
    c = controller("square", update_every=10)
    before = c.intensities.copy()
    c.set_strategies(no_corners=0.5)
    assert (c.intensities == before).all()
    for _ in range(10):
        c.advance()
    assert c.strategies["no_corners"] == 0.5
    assert c.intensities.sum() < before.sum()


def test_redraw_lights_the_size_a_caller_set():
    """The learn panel's pictures set the smallest size and ask for its lights through the public redraw."""
    c = controller("square")
    largest = c.outline.copy()
    c.scale = c.min_scale
    assert np.array_equal(c.outline, largest)  # setting the size lights nothing by itself
    c.redraw()
    assert np.allclose(c.outline, c.sizing.polygon(c.min_scale))
    assert abs(geometry.signed_area(c.outline)) < abs(geometry.signed_area(largest))
    assert c.intensities.any()
