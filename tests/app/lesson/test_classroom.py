"""The class's worlds over time (issue 58, item 3): a world nobody watches is freed after a while and its
student comes back to a new one; the teacher's world pauses while no teacher's page is open; the
projector shows a student's world named in its caption."""

from __future__ import annotations

import time

import pytest

from sandbox.app.lesson import classroom
from tests.app.lesson.classing import class_app, new_student, student
from tests.app.web.test_security import notification
from tests.waiting import wait_until


def held(pool, key: str) -> bool:
    """Whether a host of the pool still holds the world ``key``."""
    return any(key in host.kept for host in pool.hosts)


@pytest.mark.slow  # (5 s: the host's housekeeping frees it within a second, the world is built twice)
def test_a_world_left_alone_is_freed_and_its_student_comes_back_to_a_new_one(monkeypatch):
    monkeypatch.setattr(classroom, "FREE_AWAY_SECONDS", 0.3)
    app = class_app()
    try:
        lesson = app.lesson
        identity, page, _ = new_student(app)
        world = lesson.worlds[identity]
        key = world.runner.key
        assert held(lesson.pool, key)
        page.close()
        wait_until(lambda: identity not in lesson.worlds, what="the world left alone to be freed")
        wait_until(lambda: not held(lesson.pool, key), what="its host to free it")
        assert identity in lesson.freed and lesson.seats.get(identity) is not None  # the seat stays

        again, _ = student(app, identity)  # the student comes back to the seat's link
        try:
            assert lesson.worlds[identity] is not world and lesson.worlds[identity].runner.key != key
            assert notification(again, "Welcome back")["body"] == classroom.FREED_NOTICE
            assert identity not in lesson.freed
        finally:
            again.close()
    finally:
        app.stop()


def test_only_a_world_whose_page_has_been_gone_long_enough_is_freed(monkeypatch):
    """Pinned by hand, without a server: a seat with its page open is never freed; one gone 299 s of 300
    is kept; one gone 300 s is freed, and the projector that showed it shows the teacher's world again."""
    from types import SimpleNamespace

    monkeypatch.setattr(classroom, "FREE_AWAY_SECONDS", 300.0)
    lesson = classroom.Classroom(make_runner=lambda *a, **k: None)
    stopped = []
    runner = lambda name: SimpleNamespace(free=lambda: stopped.append(name))  # noqa: E731
    lesson.worlds = {name: SimpleNamespace(runner=runner(name)) for name in ("here", "soon", "gone")}
    lesson.page_of = {"here": object()}
    lesson.away_since = {"here": 0.0, "soon": 701.0, "gone": 700.0}
    lesson.projected, projected = "gone", []
    lesson.project = projected.append
    assert lesson.free_left_alone(now=1000.0) == ["gone"]
    assert set(lesson.worlds) == {"here", "soon"} and lesson.freed == {"gone"}
    assert projected == [None]
    wait_until(lambda: stopped == ["gone"], what="the freed world's runner to end")


def test_the_teachers_world_is_shown_at_most_a_few_frames_a_second_while_students_have_worlds():
    from types import SimpleNamespace

    from sandbox.app.lesson.classroom import TEACHERS_FPS_IN_CLASS

    lesson = classroom.Classroom(make_runner=lambda *a, **k: None)
    assert lesson.teachers_most_fps() is None  # no class yet: the teacher's world as its pages draw
    lesson.worlds = {"a": SimpleNamespace()}
    assert lesson.teachers_most_fps() == TEACHERS_FPS_IN_CLASS == 5.0


def test_the_teachers_world_pauses_while_no_teachers_page_is_open_and_goes_on_as_left():
    from tests.app.lesson.classing import TOKEN, own_page
    from tests.viser_wire import RawClient

    def teachers_page() -> RawClient:
        page = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
        page.say_hello()
        wait_until(lambda: len(app.pages.get_clients()) == 1, what="the teacher's page")
        return page

    app = class_app(idle_pause_seconds=0.5)
    try:
        runner = app.runner
        teacher = teachers_page()
        wait_until(lambda: runner.playing, what="the teacher's world playing")
        identity, page, _ = new_student(app)
        teacher.close()  # only a student watches now, their own world
        wait_until(lambda: app.auto_paused and not runner.playing, what="the teacher's world paused")
        assert app.lesson.worlds[identity].runner.playing

        teacher = teachers_page()
        wait_until(lambda: runner.playing and not app.auto_paused, what="the teacher's page to play it on")
        app.events.call(app.lockstep.set_playing, False)  # the teacher pauses it, and leaves
        teacher.close()
        wait_until(lambda: not app.pages.get_clients(), what="the teacher's page gone")
        app.events.call(app._check_viewers)
        teacher = teachers_page()
        app.events.call(app._check_viewers)
        assert not runner.playing and not app.auto_paused  # paused, as the teacher left it
        teacher.close()
        page.close()
    finally:
        app.stop()


def test_show_on_the_projector_switches_the_teachers_pages_to_the_presenter_layout_and_names_the_student():
    from sandbox.app.panel.framing import PRESENTER, WHOLE_ARENA
    from tests.app.lesson.classing import TOKEN, own_page
    from tests.viser_wire import RawClient

    app = class_app()
    try:
        identity, page, _ = new_student(app)
        teacher = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
        teacher.say_hello()
        wait_until(lambda: app.pages.get_clients(), what="the teacher's page")
        [teachers] = app.pages.get_clients()
        framing, caption = app.panel.framing, lambda: app.view.handles["caption"].text
        assert framing.of(teachers) == WHOLE_ARENA and not caption().startswith("Student")

        app.events.call(app.lesson.project, identity)
        assert framing.of(teachers) == PRESENTER
        assert caption().startswith("Student 1: ") and app.view.caption_over_construction  # where it frames
        wait_until(lambda: app.on_projector is not None and app.on_projector.step > 2, what="the world, live")
        assert caption().startswith("Student 1: ")  # every frame of it

        app.events.call(app.lesson.project, None)
        assert framing.of(teachers) == WHOLE_ARENA and not caption().startswith("Student")
        assert not app.view.caption_over_construction
        teacher.close()
        page.close()
    finally:
        app.stop()


def test_a_students_floor_is_framed_again_whenever_their_window_changes_shape():
    """Without a page: a desk's camera followed its window's shape for its first 30 s only; a page whose
    canvas narrowed later (its docked panel laid out late) kept the wide framing, the caption's end under
    the panel."""
    from types import SimpleNamespace

    from sandbox.app.lesson.desk import Desk

    framed = []
    desk = object.__new__(Desk)
    desk.client = SimpleNamespace(client_id=7, camera=SimpleNamespace(aspect=1.33))
    desk.panel = SimpleNamespace(framing=SimpleNamespace(apply=lambda client: framed.append(client.camera.aspect)),
                                 inspector=SimpleNamespace(followers=set()))
    desk._fitted = None
    desk._fit()  # the first report: the whole window's width
    desk._fit()  # the same shape again (a camera moved): left as the student set it
    desk.client.camera.aspect = 0.79  # much later, the panel docked: 604 x 768
    desk._fit()
    assert framed == [1.33, 0.79]
    desk.panel.inspector.followers.add(7)  # following a robot: the inspector moves its camera
    desk.client.camera.aspect = 1.0
    desk._fit()
    assert framed == [1.33, 0.79]


@pytest.mark.slow  # (5-7 s: a student's world built in a host)
def test_the_teachers_world_is_paced_by_the_teachers_page_not_by_the_students():
    """A student's page that keeps up drew every frame of the teacher's world out of it (it draws a world
    of its own); with students in, the teacher's world is shown 5 times a second at most."""
    import re

    from sandbox.app.web.pacing import CALM, PATH
    from tests.app.lesson.classing import TOKEN, own_page
    from tests.viser_wire import RawClient

    def token_of(page) -> str:
        script = page.first("RunJavascriptMessage", 30.0)
        return re.search(re.escape(PATH) + r"([A-Za-z0-9_-]+)", script["source"]).group(1)

    app = class_app()  # 30 frames a second
    try:
        teacher = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
        teacher.say_hello()
        wait_until(lambda: app.pages.get_clients(), what="the teacher's page")
        pacer, now = app.gate.pacer, time.monotonic()
        teachers = token_of(teacher)
        for k in range(8):  # the teacher's page draws 7 frames a second
            assert pacer.drawn(teachers, now=now - 1.0 + k / 7)
        app.events.call(app._pace_snapshots)
        assert app.lockstep.shown_every == 2  # 10.5 wanted: 15 a second
        identity, page, _ = new_student(app)
        assert pacer.drawn(token_of(page) + CALM)  # the student's page keeps up
        app.events.call(app._pace_snapshots)
        assert app.lockstep.shown_every == 6  # 5 a second
        wait_until(lambda: app.runner.controls.show_every == 6, what="the teacher's world told")
        teacher.close()
        page.close()
    finally:
        app.stop()
