"""The teacher's wall, without a server: the order the teacher picks, the ranking, the pictures."""

from __future__ import annotations

from types import SimpleNamespace

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
    assert len(set(picture.getdata())) > 4  # the floor, its lights, the wall, the goal, the bodies
