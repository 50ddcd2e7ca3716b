"""Where the boxes outside the goal lie (sandbox/model/explain.py), on positions placed by hand."""

from __future__ import annotations

import numpy as np

from sandbox.model.explain import place_strays, strays_in_words

#: Construction area 16 m centred on (32, 32): walls at 24 and 40. Goal: the square 30..34. Boxes 0.5 m wide.
GOAL = np.array([[30.0, 30.0], [34.0, 30.0], [34.0, 34.0], [30.0, 34.0]])
CENTRE, SIDE, WIDTH = 32.0, 16.0, 0.5


def places(boxes, in_goal):
    return place_strays(np.array(boxes, float), np.array(in_goal), GOAL, CENTRE, SIDE, WIDTH)


def test_each_stray_is_counted_in_the_first_place_that_fits():
    heap = [(25.0 + 0.3 * k, 25.0) for k in range(6)]  # 7 m left of and below the middle: the lower-left corner
    boxes = [(32.0, 32.0),  # in the goal
             (35.0, 32.0),  # 1.0 m right of the goal's edge: within 3 widths (1.5 m)
             *heap,
             (39.6, 32.0),  # 0.4 m from the right wall: within 1.5 widths (0.75 m), not in a corner
             (36.0, 36.0)]  # 2.8 m from the goal, 4 m from each wall, alone in its corner square
    strays = places(boxes, [True] + [False] * 9)
    assert list(strays.indices) == list(range(1, 10))
    assert (strays.near_goal, strays.heaps, strays.against_wall, strays.elsewhere) == (1, (("lower-left", 6),), 1, 1)
    assert strays_in_words(strays, WIDTH) == (
        "Of the 9 boxes outside the goal: 1 near the goal (within 1.5 m of its edge), 6 heaped in the lower-left "
        "corner of the construction area, 1 against the construction area's wall, 1 scattered elsewhere in the "
        "construction area.")


def test_a_few_boxes_in_a_corner_are_no_heap_and_a_corner_box_by_the_wall_is_against_it():
    boxes = [(24.3, 24.3), (24.4, 39.6), (39.7, 24.2)]  # three corners, one box each, each by a wall
    strays = places(boxes, [False] * 3)
    assert strays.heaps == () and strays.against_wall == 3 and strays.near_goal == strays.elsewhere == 0
    assert strays_in_words(strays, WIDTH) == "Of the 3 boxes outside the goal: 3 against the construction area's wall."


def test_every_box_in_the_goal():
    strays = places([(31.0, 31.0), (33.0, 33.0)], [True, True])
    assert strays.count == 0 and strays_in_words(strays, WIDTH) == "Every box is in the goal."
