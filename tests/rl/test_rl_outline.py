"""sandbox.rl without Gymnasium: the outline action lights what the paper's controller lights,
the observation's histograms, and nothing outside sandbox.rl needs Gymnasium."""

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import sandbox
import sandbox.rl
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.family import make_goal
from sandbox.rl.features import DISTANCE_EDGES, distance_histogram, feature_names
from sandbox.rl.outline import FLARE_HIGH, NO_CORNERS_HIGH, Knobs, OutlinePainter
from sandbox.shapes import shape_vertices

CASES = [("circle", {}, "authors-code"), ("square", {}, "authors-code"),
         ("star", {"flare": 1.75, "no_corners": 0.5}, "authors-code"),
         ("star", {"flare": 1.75, "no_corners": 0.5}, "paper-text"), ("t-shape", {"no_corners": 0.3}, "paper-text")]


@pytest.mark.parametrize("shape,strategies,profile", CASES)
def test_outline_action_lights_the_controllers_band(shape, strategies, profile):
    config = Config(profile=profile, shape=shape, **strategies)
    goal = make_goal(config, shape_vertices(shape))
    controller = Controller(config, goal)  # it lights its largest outline first
    painter = OutlinePainter(config, goal)
    knobs = Knobs(size=1.0, flare=config.flare, no_corners=config.no_corners)
    np.testing.assert_array_equal(painter.pattern(knobs), controller.intensities)
    sizes = painter.sizes(config.flare)
    assert (sizes.smallest, sizes.largest) == pytest.approx((controller.min_scale, controller.max_scale))
    if not goal.is_circle:  # (the controller lights a circle by its radius, as the painter does)
        sizing = controller.sizing
        expected = sizing.lit(painter.centres, sizing.smallest, config.band).reshape(controller.intensities.shape)
        np.testing.assert_array_equal(painter.pattern(Knobs(size=0.0, flare=config.flare)), expected)


def test_knobs_from_an_action_are_clipped_into_the_strategies_ranges():
    assert Knobs.from_action([0.5, 1.0, 0.49, 1.0]) == Knobs(0.5, FLARE_HIGH, False, NO_CORNERS_HIGH)
    assert Knobs.from_action([-3.0, 2.0, 0.5, -1.0]) == Knobs(0.0, FLARE_HIGH, True, 0.0)


def test_circle_knob_lights_a_ring_around_a_polygon_goal():
    config = Config(shape="star")
    painter = OutlinePainter(config, make_goal(config, shape_vertices("star")))
    ring = painter.pattern(Knobs(size=0.5, circle=True))
    lit = painter.centres[ring.reshape(-1) > 0]
    sizes = painter.sizes(0.0)
    radius = sizes.circle_radius(sizes.smallest + 0.5 * (sizes.largest - sizes.smallest))
    assert np.abs(np.hypot(*(lit - painter.goal.centre).T) - radius).max() <= config.band + 1e-9


def test_distance_histogram_counts_inside_and_each_band():
    config = Config()
    goal = make_goal(config, None)
    edge = goal.centre + [goal.radius, 0.0]
    points = np.array([goal.centre, edge + [0.25, 0], edge + [3.0, 0], edge + [100.0, 0]])
    hist = distance_histogram(points, goal)
    assert len(hist) == len(DISTANCE_EDGES) + 2 and hist.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(hist[[0, 1, 4, -1]], 0.25)
    assert distance_histogram(np.empty((0, 2)), goal).sum() == 0
    assert len(feature_names(("size",))) == 2 * len(hist) + 3


def test_only_sandbox_rl_env_imports_gymnasium():
    """Headless runs and the app never import Gymnasium: it is an optional extra."""
    root = Path(sandbox.__file__).parent
    statement = re.compile(r"^\s*(import|from)\s+gymnasium\b", re.MULTILINE)
    importers = {path.relative_to(root).as_posix() for path in root.rglob("*.py")
                 if statement.search(path.read_text(encoding="utf-8"))}
    # rl/__init__.py imports it inside register(), guarded.
    assert importers == {"rl/env.py", "rl/__init__.py"}


def test_registering_without_gymnasium_does_nothing(monkeypatch):
    monkeypatch.setitem(sys.modules, "gymnasium", None)  # import gymnasium now raises ModuleNotFoundError
    assert sandbox.rl.register() is False
