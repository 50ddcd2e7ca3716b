"""Safe with a class (issue 58, item 5), over the network: a student's identity is the server's to issue,
unguessable, held by one page at a time and only from the address it was given to; a student's page
reaches neither another student's world, the teacher's controls nor light programs; 200 connections from
one address are refused cleanly while the teacher and the students carry on; a student's flood of values
is applied within their page's budget, to their own world."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import pytest
import websockets.exceptions

from sandbox.app.lesson.seats import MOST_SEATS, UNCLAIMED_SECONDS, Seats
from sandbox.app.web.access import SEAT_PATTERN
from sandbox.app.web.rates import CONTROLS
from tests.app.lesson.classing import (TOKEN, class_app, join, new_student, own_page, refusals, seat_of, student,
                                       uuid_of)
from tests.app.web.test_security import notification
from tests.app.world.test_host import steps_per_second
from tests.viser_wire import RawClient
from tests.waiting import wait_until, wait_until_steady


@pytest.fixture
def app():
    a = class_app(keep_running=True)  # the teacher's world plays throughout, as with the teacher's page open
    yield a
    a.stop()


def refused_status(port: int, path: str, headers: dict | None = None) -> int:
    with pytest.raises(websockets.exceptions.InvalidStatus) as refused:
        RawClient(port, headers, path=path)
    return refused.value.response.status_code


def test_the_server_issues_each_page_an_unguessable_seat_of_its_own(app):
    statuses, locations = zip(*(join(app.port) for _ in range(3)))
    identities = [seat_of(location) for location in locations]
    assert statuses == (302, 302, 302) and all(loc.startswith("/seat/") for loc in locations)
    assert len(set(identities)) == 3 and all(SEAT_PATTERN.fullmatch(i) for i in identities)  # 192 random bits
    made_up = "A" * 32  # well formed, never issued
    assert refused_status(app.port, f"/seat/{made_up}") == 403
    assert refused_status(app.port, "/seat/../../etc") == 403
    assert refused_status(app.port, "/join") == 403  # a seat is issued to a page, never to a websocket
    assert refused_status(app.port, "/") == 403  # nor does a page without the token watch the teacher's
    assert join(app.port, path="/") == (302, "/join")  # the plain address is the students' link too
    page, _ = student(app, identities[0])  # an issued one is taken
    page.close()


def test_a_seat_is_held_by_one_page_and_a_reload_finds_its_world(app):
    identity, page, _ = new_student(app)
    world = app.lesson.worlds[identity]
    assert refused_status(app.port, f"/seat/{identity}", own_page(app)) == 503  # a second page of the same seat
    wait_until(lambda: world.runner.latest.step > 10, what="the world to run")
    page.close()
    wait_until(lambda: identity not in app.lesson.desks, what="the page to leave")
    step = world.runner.latest.step
    again, _ = student(app, identity)  # the reload: the same address, the page gone
    assert app.lesson.worlds[identity] is world and world.runner.latest.step >= step
    again.close()


def test_a_seat_is_refused_from_another_address():
    app = class_app(trust_proxy=True)  # the page's address from the proxy's header, as a school's proxy sends it
    try:
        status, location = join(app.port, {"X-Forwarded-For": "198.51.100.7"})
        assert status == 302
        assert refused_status(app.port, location, {"X-Forwarded-For": "198.51.100.8"}) == 403
        page, _ = student(app, seat_of(location), {"X-Forwarded-For": "198.51.100.7"})
        page.close()
    finally:
        app.stop()


def test_a_student_reaches_neither_another_students_world_nor_the_teachers_controls(app):
    first, first_page, fid = new_student(app)
    second, second_page, sid = new_student(app)
    theirs = app.lesson.desks[second].panel.run
    wait_until(lambda: app.lesson.worlds[second].runner.playing, what="the second world to play")
    first_page.click(uuid_of(theirs.play))  # the other student's Pause
    first_page.click(uuid_of(app.panel.run.play))  # the teacher's Pause
    first_page.click(uuid_of(app.lesson.wall.send_all))  # the teacher's wall
    wait_until(lambda: refusals(app, fid) >= 3, what="three refusals")
    assert app.lesson.worlds[second].runner.playing and app.runner.playing
    first_page.click(uuid_of(app.lesson.desks[first].panel.run.play))  # its own Pause acts, on its own world
    wait_until(lambda: not app.lesson.worlds[first].runner.playing, what="the student's own pause")
    assert app.lesson.worlds[second].runner.playing and app.runner.playing
    first_page.close()
    second_page.close()


def test_a_students_page_is_sent_none_of_the_teachers_page(app):
    identity, page, _ = new_student(app)
    wall = uuid_of(app.lesson.wall.folder)
    own = uuid_of(app.lesson.desks[identity].panel.run.play)
    seen = set()
    for message in page._messages(3.0):
        seen.add(message.get("uuid"))
        if own in seen:
            break
    marker = app.events.call(app.server.gui.add_markdown, "for the teacher's pages")
    late = {m.get("uuid") for m in page._messages(1.5)}
    assert own in seen and wall not in seen | late and uuid_of(marker) not in late
    page.close()


def test_a_student_cannot_load_light_programs(app, tmp_path):
    identity, page, client_id = new_student(app)
    desk = app.lesson.desks[identity]
    assert not app.gate.may_load_programs(app.server.get_clients()[client_id])
    program = tmp_path / "lights.py"
    program.write_text("class Lights:\n    def update(self, observation):\n        return None\n")
    page.set_value(uuid_of(desk.panel.program.path), f"{program}:Lights")
    wait_until(lambda: desk.panel.program.path.value.startswith(str(program)), what="the path typed")
    page.click(uuid_of(desk.panel.program.use))
    assert "only a page opened on the server's own machine" in notification(page, "Program not used")["body"]
    assert app.lesson.worlds[identity].runner.latest.program == app.runner.latest.program  # the paper's
    page.close()


@pytest.mark.slow
def test_two_hundred_connections_from_one_address_are_refused_while_the_class_carries_on(app):
    identity, page, _ = new_student(app)
    world = app.lesson.worlds[identity]
    joins = [join(app.port)[0] for _ in range(200)]
    assert joins.count(302) == MOST_SEATS - 1 and set(joins) == {302, 503}  # the class is full: said so

    def attempt(path: str) -> RawClient | int:
        try:
            return RawClient(app.port, own_page(app), path=path)
        except websockets.exceptions.InvalidStatus as refused:
            return refused.response.status_code

    paths = ["/"] * 150 + [f"/seat/{identity}"] * 50
    with ThreadPoolExecutor(max_workers=50) as pool:
        outcomes = list(pool.map(attempt, paths))
    let_in = [o for o in outcomes if isinstance(o, RawClient)]
    # no page watches the teacher's in a lesson (403); the seat's page is open already (503)
    assert not let_in and outcomes.count(403) == 150 and outcomes.count(503) == 50
    # the teacher connects and controls; the student's world goes on, its page open
    teacher = RawClient(app.port, {**own_page(app), "Authorization": f"token {TOKEN}"})
    teacher.say_hello()
    step = world.runner.latest.step
    wait_until(lambda: world.runner.latest.step > step + 20, what="the student's world to go on")
    teacher.click(uuid_of(app.panel.run.play))
    wait_until(lambda: not app.runner.playing, what="the teacher's Pause")
    assert page.ws.state.name == "OPEN" and identity in app.lesson.desks
    for client in let_in + [teacher, page]:
        client.close()


def test_a_students_flood_of_values_is_applied_within_their_budget_to_their_own_world(app):
    first, first_page, fid = new_student(app)
    second, second_page, _ = new_student(app)
    speed = app.lesson.desks[first].panel.run.speed
    applied = []
    speed.on_update(lambda event: applied.append(event))
    others = (app.lesson.worlds[second].runner.steps_per_frame, app.runner.steps_per_frame)
    started = time.monotonic()
    for i in range(200):
        first_page.set_value(uuid_of(speed), 2 + i % 50)
    sending = time.monotonic() - started
    wait_until(lambda: app.lesson.worlds[first].runner.steps_per_frame == 2 + 199 % 50, what="the last value")
    wait_until_steady(lambda: len(applied))
    allowed = CONTROLS.burst + CONTROLS.rate * sending + 5
    assert len(applied) <= allowed, f"{len(applied)} values applied, {allowed:.0f} allowed"
    assert (app.lesson.worlds[second].runner.steps_per_frame, app.runner.steps_per_frame) == others
    assert app.gate.flow(fid).counts["replaced"] >= 130
    first_page.close()
    second_page.close()


def test_the_seats_are_counted_per_class_and_per_address():
    seats = Seats(most=3, most_per_address=2)
    assert seats.issue("10.0.0.1") and seats.issue("10.0.0.1") and seats.issue("10.0.0.1") is None
    assert seats.issue("10.0.0.2") and seats.issue("10.0.0.3") is None
    first = seats.all()[0]
    assert seats.check(first.identity, "10.0.0.1") == "" and seats.check(first.identity, "10.0.0.2")
    assert seats.check("B" * 32, "10.0.0.1") == "no such seat"


def test_a_student_uploads_a_goal_to_their_own_world_and_not_to_the_teachers(app):
    identity, page, client_id = new_student(app)
    triangle = b"0 0\n6 0\n3 5\n"
    own = uuid_of(app.lesson.desks[identity].panel.shape.upload)
    transfer = page.start_upload(own, size=len(triangle), parts=1, name="tri.txt")
    page.upload_part(own, transfer, 0, triangle)
    wait_until(lambda: app.lesson.worlds[identity].runner.latest.shape_name == "tri.txt", what="the student's goal")
    teachers = uuid_of(app.panel.shape.upload)
    transfer = page.start_upload(teachers, size=len(triangle), parts=1, name="tri2.txt")
    page.upload_part(teachers, transfer, 0, triangle)
    wait_until(lambda: refusals(app, client_id) >= 2, what="the upload to the teacher's button refused")
    assert app.runner.latest.shape_name != "tri2.txt"
    page.close()


def steps_a_second(runner, seconds: float) -> float:
    return steps_per_second([runner], seconds)[0]


@pytest.mark.slow
def test_a_student_who_floods_for_seconds_slows_only_their_own_world(app):
    """A student's page sends values to its own speed slider as fast as its socket takes them, for 5 s,
    from a process of its own: another student's world and the teacher's step on at about their pace."""
    from tests.flooding import flood_result, start_flood

    flooder, flooder_page, _ = new_student(app)
    other, other_page, _ = new_student(app)
    worlds = (app.lesson.worlds[other].runner, app.runner)
    before = [steps_a_second(runner, 2.0) for runner in worlds]
    speed = uuid_of(app.lesson.desks[flooder].panel.run.speed)
    flooder_page.close()  # the flood's own connection takes the seat's page, as a reload would
    wait_until(lambda: flooder not in app.lesson.desks, what="the page to leave")
    flood = start_flood(app.port, "values", 1, 5.0, own_page(app), uuid=speed, path=f"/seat/{flooder}")
    wait_until(lambda: flooder in app.lesson.desks, what="the flooding page's desk")
    during = [steps_a_second(runner, 3.0) for runner in worlds]
    sent, closed = flood_result(flood)
    assert sent > 1000
    for was, now in zip(before, during):
        assert now >= 0.6 * was, f"{now:.0f} steps/s during the flood, {was:.0f} before"
    other_page.close()


def test_a_seat_never_used_goes_back_to_the_class_and_a_used_one_stays():
    seats = Seats(most=2)
    used, unused = seats.issue("10.0.0.1", now=0.0), seats.issue("10.0.0.1", now=0.0)
    seats.claim(used)
    assert seats.issue("10.0.0.1", now=UNCLAIMED_SECONDS - 1) is None  # the class is full
    newcomer = seats.issue("10.0.0.1", now=UNCLAIMED_SECONDS + 1)  # the unused seat was given back
    assert newcomer and seats.get(unused) is None and seats.get(used) is not None
