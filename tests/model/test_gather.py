"""The sides a notched goal's dilating band gathers the robots beside (sandbox/model/gather.py, issue 42),
on values computed by hand."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sandbox.model import gather, notches
from sandbox.model.config import Config
from sandbox.model.controller import Controller
from sandbox.model.family import make_goal
from sandbox.model.goal import Goal
from sandbox.model.offset import OffsetSizing
from sandbox.model.phases import CONTRACTING, DILATING
from sandbox.model.simulation import Simulation
from sandbox.shapes import shape_vertices

ROOT = Path(__file__).resolve().parents[2]
NOTCHED = ROOT / "static" / "shapes" / "notched"
#: A U: the square [0, 6]^2 less the notch [2, 4] x [2, 6], which opens upwards.
U_VERTICES = np.array([[0, 0], [6, 0], [6, 6], [4, 6], [4, 2], [2, 2], [2, 6], [0, 6]], dtype=float)
U_GOAL = Goal(np.array([3.0, 3.0]), 28.0, U_VERTICES)
#: An H: the U and the same U upside down, joined by a bar: [0, 6] x [0, 10] less the notches
#: [2, 4] x [6, 10] (opening up) and [2, 4] x [0, 4] (opening down).
H_VERTICES = np.array([[0, 0], [2, 0], [2, 4], [4, 4], [4, 0], [6, 0], [6, 10], [4, 10], [4, 6], [2, 6],
                       [2, 10], [0, 10]], dtype=float)
#: Lights one metre apart at the half metres, over [-8, 14]^2.
LIGHTS = np.stack(np.meshgrid(np.arange(-7.5, 14.0), np.arange(-7.5, 14.0), indexing="ij"), axis=-1).reshape(-1, 2)


def u_sizing(gathered: str) -> OffsetSizing:
    found = tuple(notches.notch_polygons(U_VERTICES))
    return OffsetSizing(U_GOAL, 0.5, 12.0, 8.0, math.sqrt(28.0 / math.pi), 24.0, found, notches.PACE,
                        notches.SLOW_WITHIN, gather=gathered)


def test_a_notchs_mouth_faces_where_it_opens():
    (up,) = gather.mouth_directions(U_VERTICES, tuple(notches.notch_polygons(U_VERTICES)))
    # The notch and its mouth (the closing's arc between (2, 6) and (4, 6)) are symmetric about x = 3:
    # the direction from one centroid to the other is straight up.
    assert up == pytest.approx([0.0, 1.0], abs=1e-9)
    directions = gather.mouth_directions(H_VERTICES, tuple(notches.notch_polygons(H_VERTICES)))
    assert gather.all_faced(directions) == "BT"


def test_a_mouth_faces_the_side_it_points_to_most():
    assert gather.faced_side(np.array([0.36, 0.93])) == "T"  # the letter K's upper notch: up, leaning right
    assert gather.faced_side(np.array([-0.38, -0.92])) == "B"  # the N's lower one leans the other way
    assert gather.faced_side(np.array([0.99, 0.11])) == "R"  # the letter E's
    assert gather.faced_side(np.array([-0.88, -0.47])) == "L"  # the letter Z's
    assert gather.all_faced([np.array([0.0, 1.0]), np.array([0.0, -1.0]), np.array([0.0, 1.0])]) == "BT"


#: Pockets' bounding boxes: two in line across x (one above the other), and two staggered.
ABOVE, BELOW, HIGH_LEFT, LOW_RIGHT = (2, 6, 4, 10), (2, 0, 4, 4), (0, 6, 3, 8), (3, 0, 6, 2)


@pytest.mark.parametrize("faced, bounds, starved", [
    ([(0, 1), (0, -1)], [ABOVE, BELOW], "LR"),            # H, X: up and down; the left and right starve
    ([(0.12, 0.99), (-0.12, 0.99), (0, -1)], [(0, 6, 6, 10)] * 2 + [(2, 0, 4, 4)], "LR"),  # W
    ([(-0.38, 0.92), (0.38, -0.92)], [ABOVE, BELOW], "LR"),  # N: the leans cancel
    ([(0.36, 0.93), (0.36, -0.93)], [ABOVE, BELOW], "L"),  # K: both lean 0.36 right; only the stem's side
    ([(-0.88, -0.47), (0.88, 0.47)], [(0, 0, 6, 10), (2, 0, 8, 10)], ""),  # Z: in line, leaning 0.47 up and down
    ([(-0.88, -0.4), (0.88, 0.4)], [(0, 0, 6, 10), (2, 0, 8, 10)], "BT"),  # ... were it to lean 0.4 only
    ([(1, 0), (-1, 0)], [(2, 6, 6, 8), (0, 0, 4, 2)], ""),  # S: left and right at different heights
    ([(0, 1), (0, -1)], [HIGH_LEFT, LOW_RIGHT], ""),       # up and down, side by side: not in line
    ([(0, 1), (0, -1), (1, 0)], [ABOVE, BELOW, (4, 4, 6, 6)], "L"),  # three sides faced: the fourth
    ([(0, 1), (0, -1), (1, 0), (-1, 0)], [ABOVE, BELOW, (4, 4, 6, 6), (0, 4, 2, 6)], ""),  # all faced
    ([(1, 0), (1, 0)], [ABOVE, BELOW], ""),                # E: one side only
    ([(0, 1)], [ABOVE], ""),                               # Y
    ([(1, 0), (0, 1)], [ABOVE, BELOW], ""),                # two sides, not opposite
    ([], [], ""),
])
def test_only_notches_in_line_facing_opposite_sides_starve_the_sides_between(faced, bounds, starved):
    assert gather.LEAN == 0.45
    assert gather.starved_sides([np.array(d, float) for d in faced], bounds) == starved


def test_the_mouths_lean_adds_each_ones_lean_towards_a_side():
    ks = [np.array([0.36, 0.93]), np.array([0.36, -0.93])]
    assert gather.lean(ks, "R") == pytest.approx(0.72) and gather.lean(ks, "L") == 0.0
    ns = [np.array([-0.38, 0.92]), np.array([0.38, -0.92])]
    assert gather.lean(ns, "L") == pytest.approx(0.38) and gather.lean(ns, "R") == pytest.approx(0.38)


def test_the_ns_notches_lie_at_opposite_ends_but_their_pockets_side_by_side():
    vertices = shape_vertices(str(NOTCHED / "own" / "N.txt")) * 1.0
    found = gather.mouths(vertices, tuple(notches.notch_polygons(vertices)))
    (up, above), (down, below) = sorted(found, key=lambda f: -f[0][1])
    assert up[1] > 0.9 and down[1] < -0.9 and up[0] < -0.3 and down[0] > 0.3  # leaning left and right
    # The pockets are the triangles beside the diagonal, each between x = 1.5 and 6.
    assert above[0] == pytest.approx(1.5) and above[2] == pytest.approx(6.0)
    assert below[0] == pytest.approx(1.5) and below[2] == pytest.approx(6.0)
    assert gather.in_line(above, below, "T")


def test_notches_are_in_line_when_they_overlap_across_their_axis():
    assert gather.in_line(ABOVE, BELOW, "T") and not gather.in_line(HIGH_LEFT, LOW_RIGHT, "T")
    assert gather.in_line((0, 0, 2, 2), (4, 1, 6, 3), "L") and not gather.in_line((0, 0, 2, 2), (4, 1, 6, 3), "T")
    assert not gather.in_line((0, 0, 2, 2), (2, 4, 4, 6), "B")  # touching at x = 2 is not overlapping


def test_points_beyond_a_bounding_boxs_sides():
    points = np.array([[-1, 3], [7, 3], [3, -1], [3, 7], [3, 3], [-1, -1]], dtype=float)
    assert gather.beyond_sides(points, (0, 0, 6, 6), "LR").tolist() == [True, True, False, False, False, True]
    assert gather.beyond_sides(points, (0, 0, 6, 6), "B").tolist() == [False, False, True, False, False, True]
    assert gather.said("LR") == "the left and right" and gather.said("B") == "the bottom"


def test_the_dilating_band_beyond_2_5_m_lights_only_the_gathered_sides():
    sizing, plain = u_sizing("LR"), u_sizing("")
    full = plain.lit(LIGHTS, 4.0, 0.5, dilating=True)
    gathered = sizing.lit(LIGHTS, 4.0, 0.5, dilating=True)
    beside = (LIGHTS[:, 0] < 0.0) | (LIGHTS[:, 0] > 6.0)
    assert (gathered == (full & beside)).all()
    lit = {tuple(p) for p in LIGHTS[gathered]}
    # (-3.5, 3.5) is 3.5 m left of the U, within the band at 4 +- 0.5: lit; (3.5, -3.5), as far below it,
    # is in the full band but not beside the left or right.
    assert (-3.5, 3.5) in lit and (9.5, 3.5) in lit and (3.5, -3.5) not in lit
    assert full[np.all(LIGHTS == (3.5, -3.5), axis=1)].all()
    # Contracting, or at 2.5 m and nearer, the whole band is lit.
    assert gather.BEYOND == 2.5
    assert (sizing.lit(LIGHTS, 4.0, 0.5) == plain.lit(LIGHTS, 4.0, 0.5)).all()
    assert (sizing.lit(LIGHTS, 2.5, 0.5, dilating=True) == plain.lit(LIGHTS, 2.5, 0.5, dilating=True)).all()
    assert not (sizing.lit(LIGHTS, 2.6, 0.5, dilating=True) == plain.lit(LIGHTS, 2.6, 0.5, dilating=True)).all()
    assert sizing.gathering_at(4.0, True) == "LR" and sizing.gathering_at(2.6, True) == "LR"
    assert sizing.gathering_at(4.0, False) == "" and sizing.gathering_at(2.5, True) == ""


@pytest.mark.parametrize("path, sides", [
    (NOTCHED / "shapes" / "letter-H.txt", "LR"), (NOTCHED / "own" / "K.txt", "L"), (NOTCHED / "own" / "X.txt", "LR"),
    (NOTCHED / "shapes" / "W.txt", "LR"), (ROOT / "static" / "shapes" / "templates" / "shapes" / "letter-S.txt", ""),
    (ROOT / "static" / "shapes" / "templates" / "shapes" / "letter-Z.txt", ""),
    (NOTCHED / "own" / "N.txt", "LR"), (NOTCHED / "own" / "M.txt", "LR"), (NOTCHED / "own" / "A.txt", ""),
    (NOTCHED / "shapes" / "letter-E.txt", ""), (NOTCHED / "shapes" / "comb.txt", ""), (NOTCHED / "own" / "Y.txt", ""),
    (NOTCHED / "shapes" / "letter-F.txt", ""),
])
def test_the_default_gathers_beside_the_starved_sides_and_says_so(path, sides):
    cfg = Config()
    goal = make_goal(cfg, shape_vertices(str(path)))
    assert OffsetSizing.of(cfg, goal).gather == sides
    assert ("robots gather there (gather = auto)" in goal.family_reason) == bool(sides)
    off = Config(gather="off")
    assert OffsetSizing.of(off, make_goal(off, shape_vertices(str(path)))).gather == ""
    chasing = Config(chase=2.0)
    assert OffsetSizing.of(chasing, make_goal(chasing, shape_vertices(str(path))), chase=2.0).gather == ""


def test_the_letter_hs_reason_names_the_sides():
    goal = make_goal(Config(), shape_vertices(str(NOTCHED / "shapes" / "letter-H.txt")))
    assert ("The notches' mouths face the bottom and top of the goal: the robots they let out go there, and none "
            "come back to the left and right. While the band dilates beyond 2.5 m only its lights beyond the "
            "left and right stay lit") in goal.family_reason


def test_the_controller_gathers_while_dilating_far_out_and_the_phase_says_so():
    cfg = Config()
    goal = make_goal(cfg, shape_vertices(str(NOTCHED / "shapes" / "letter-H.txt")))
    controller = Controller(cfg, goal)
    x0, y0, x1, y1 = goal.outline().min(axis=0).tolist() + goal.outline().max(axis=0).tolist()
    centres = controller._centres
    seen, turning = set(), 0
    for _ in range(40_000):
        controller.advance()
        lit = controller.intensities.ravel() > 0
        if controller.gathering:
            seen.add("gathering")
            # The program's schedule turns at the first size past the largest without lighting it, so the
            # last gathered band stays lit for the turning update.
            if controller.phase == CONTRACTING:
                turning += 1
            else:
                assert controller.phase == DILATING and controller.scale > gather.BEYOND
            assert controller.phase_said == f"{controller.phase}, gathering beside the left and right"
            assert lit.any() and ((centres[lit, 0] < x0) | (centres[lit, 0] > x1)).all()
        elif controller.phase == CONTRACTING and controller.scale > gather.BEYOND:
            seen.add("contracting")
            assert controller.phase_said == CONTRACTING
            assert ((centres[lit, 1] < y0) | (centres[lit, 1] > y1)).any()  # the band above and below too
        if controller.cycle >= 2:
            break
    assert seen == {"gathering", "contracting"}
    # The first turn's whole update, and the first step of the second's (the loop stops at it).
    assert turning == cfg.update_every + 1


def test_gather_off_and_the_papers_cases_light_the_whole_band():
    sim = Simulation(Config(shape=str(NOTCHED / "shapes" / "letter-H.txt"), gather="off"))
    assert sim.controller.sizing.gather == "" and sim.phase_said == sim.phase
    assert Simulation(Config(shape="star")).controller.sizing.gathering_at(10.0, True) == ""


def test_the_simulation_says_when_the_band_gathers():
    """What the page's phase line and a recording's caption read (the runner's snapshot takes phase_said)."""
    sim = Simulation(Config(shape=str(NOTCHED / "own" / "K.txt"), robots=20))
    said = set()
    while sim.steps_done < 20_000 and not any("gathering" in s for s in said):
        sim.step(100)
        said.add(sim.phase_said)
    assert "dilating, gathering beside the left" in said
    assert sim.phase == DILATING
    assert sim.gathering == "L"  # what the runner's snapshot carries for the caption
