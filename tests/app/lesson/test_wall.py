"""The teacher's wall, without a server: the order the teacher picks, the ranking, the pictures."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

import pytest

from sandbox.app.lesson.seats import Seat
from sandbox.app.lesson.wall import THUMBNAIL, floor_picture, ranking_text, sort_seats
from sandbox.app.world.runner import Runner
from sandbox.model.challenge import Gain
from sandbox.model.config import Config


def snap(share: float, step: int) -> SimpleNamespace:
    return SimpleNamespace(sample=SimpleNamespace(fraction_in_goal=share), step=step)


SEATS = [Seat("a", "g", 1, "Student 1"), Seat("b", "g", 2, "ada"), Seat("c", "g", 3, "Zoe")]
SNAPS = {"a": snap(0.10, 500), "b": snap(0.40, 300), "c": snap(0.40, 900)}


def test_the_wall_is_sorted_as_the_teacher_chooses():
    def order(how: str) -> list[str]:
        return [seat.identity for seat in sort_seats(SEATS[::-1], SNAPS, how)]

    assert order("arrival") == ["a", "b", "c"]
    assert order("name") == ["b", "a", "c"]  # ada, Student 1, Zoe: without regard to case
    assert order("share in the goal") == ["b", "c", "a"]  # 40 % (the earlier first), 40 %, 10 %
    assert order("step") == ["c", "a", "b"]


def test_the_ranking_puts_the_most_boxes_first_and_those_still_playing_last():
    rows = [("Student 1", Gain(2, 9, 20), "done"), ("Student 3", Gain(0, 1, 20), "done"),
            ("Student 2", None, "playing, step 40 of 120")]
    assert ranking_text(rows).split("\n") == [
        "**Class challenge**",
        "1. **Student 1**: 7 boxes brought in (39 %)",  # 7 of the 18 outside at the start
        "2. **Student 3**: 1 box brought in (5 %)",
        "- Student 2: playing\\, step 40 of 120",  # (our words through plain: a comma escaped, shown as one)
    ]


@pytest.mark.slow  # (a world built: numba and pymunk loaded, 3 s)
def test_a_students_picture_is_their_construction_area_at_the_wall_size():
    runner = Runner(Config(robots=12, boxes=20), steps_per_frame=1)
    picture = floor_picture(runner.latest)
    assert picture.size == (THUMBNAIL, THUMBNAIL)
    assert len(picture.getcolors(THUMBNAIL * THUMBNAIL)) > 4  # the floor, its lights, the wall, the goal, the bodies


def test_the_walls_captions_are_written_as_imagedraw_writes_them_each_line_rendered_once():
    from PIL import Image, ImageDraw, ImageFont

    from sandbox.app.lesson.wall import Captions
    from sandbox.app.view import palette as pal

    lines = ["Student 12 (away)", "ada", "42 % in goal, step 12,345", "Zoë ü — ñ", " "]
    font = ImageFont.load_default(size=12)
    drawn, written = (Image.new("RGB", (300, 20 * len(lines)), pal.BACKGROUND) for _ in range(2))
    for picture in (drawn, written):
        picture.paste((200, 30, 30), (0, 0, 40, 60))  # a thumbnail under some of the text: blended over it
    captions = Captions()
    for again in range(2):
        for i, line in enumerate(lines):
            xy, fill = (2 + 50 * again, 20 * i + 3), (235, 235, 240) if i % 2 else (170, 175, 185)
            ImageDraw.Draw(drawn).text(xy, line, fill=fill, font=font)
            captions.write(written, xy, line, fill)
    assert drawn.tobytes() == written.tobytes()
    assert captions.rendered == len(lines)  # the second time round, every line was kept


def test_the_walls_captions_keep_the_lines_written_last():
    from PIL import Image

    from sandbox.app.lesson.wall import Captions

    captions, picture = Captions(), Image.new("RGB", (200, 20))
    captions.KEPT = 2
    for line in ("a", "b", "a", "c", "a", "b"):  # "b" is the least recent when "c" comes
        captions.write(picture, (0, 0), line, (255, 255, 255))
    assert captions.rendered == 4  # a, b, c, then b again


def test_a_students_picture_shows_each_light_in_its_colour():
    from sandbox.app.view import palette as pal

    # a 4 x 4 grid of 1-m lights, the construction area its middle 2 m, seen 1.4 times as wide (2.8 m)
    cfg = SimpleNamespace(arena_size=4.0, construction_size=2.0, centre=2.0, lights_per_side=4,
                          light_intensity=2.0, box_circumradius=0.01, robot_radius=0.01, capacity=1.0)
    intensities = np.zeros((4, 4))
    intensities[1, 2] = 2.0  # the light at x 1-2 m, y 2-3 m: fully on
    intensities[2, 1] = 1.0  # x 2-3 m, y 1-2 m: half
    empty = np.zeros((0, 2))
    snap = SimpleNamespace(world_config=cfg, intensities=intensities, box_in_goal=np.zeros(0, bool),
                           box_positions=empty, robot_positions=empty, robot_charges=np.zeros(0),
                           outline=empty, goal_outline=empty)
    picture = np.asarray(floor_picture(snap, size=28))  # 10 pixels a metre, from (0.6, 0.6) to (3.4, 3.4)
    assert tuple(picture[10, 8]) == pal.LIGHT_ON  # x 1.45 m, y 2.35 m (row 10 from the top at 3.4 m)
    assert tuple(picture[17, 17]) == (156, 136, 54)  # x 2.35, y 1.65: half way, 58 + 0.5 x 197 ...
    assert tuple(picture[20, 5]) == pal.LIGHT_OFF  # x 1.15, y 1.35: off
