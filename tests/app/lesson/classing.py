"""What the class-mode tests share: a small class server, a student's seat and page over the network."""

from __future__ import annotations

import http.client

from sandbox.app.lesson.classroom import Classroom
from sandbox.app.web.access import Access
from tests.app.world.test_host import SMALL
from tests.viser_wire import RawClient
from tests.waiting import wait_until

TOKEN = "classroom-secret-42"


def class_app(*, seats=None, round_steps: int | None = None, trust_proxy: bool = False, fps: float = 30,
              steps_per_frame: int = 2, **kwargs):
    """A class server on loopback (the token needed for the teacher's page, as ``serve --class`` makes
    one), its worlds in world hosts, small; started."""
    from sandbox.commands.serve import App, free_port

    lesson = Classroom(seats, round_steps=round_steps, pace=(fps, steps_per_frame))  # the students' as the teacher's
    access = Access.for_server("127.0.0.1", token=TOKEN, trust_proxy=trust_proxy)
    access.seats = lesson.seats
    return App(SMALL, port=free_port(), fps=fps, steps_per_frame=steps_per_frame, process=False, access=access, lesson=lesson,
               **kwargs).start()


def join(port: int, headers: dict | None = None, path: str = "/join") -> tuple[int, str]:
    """Ask the students' link: the status, and the seat's address it sends the page on to."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    connection.request("GET", path, headers=headers or {})
    response = connection.getresponse()
    response.read()
    return response.status, response.getheader("Location") or ""


def seat_of(location: str) -> str:
    return location.rsplit("/", 1)[1]


def own_page(app) -> dict[str, str]:
    return {"Origin": f"http://127.0.0.1:{app.port}"}


def student(app, identity: str, headers: dict | None = None) -> tuple[RawClient, int]:
    """A student's page on its seat, connected, with its desk built: the page and its client id."""
    page = RawClient(app.port, {**own_page(app), **(headers or {})}, path=f"/seat/{identity}")
    before = set(app.server.get_clients())
    page.say_hello()
    new = wait_until(lambda: set(app.server.get_clients()) - before, what="the student's page to connect")
    wait_until(lambda: identity in app.lesson.desks, what="the student's desk")
    return page, next(iter(new))


def new_student(app, headers: dict | None = None) -> tuple[str, RawClient, int]:
    status, location = join(app.port, headers)
    assert status == 302, status
    identity = seat_of(location)
    page, client_id = student(app, identity, headers)
    return identity, page, client_id


def refusals(app, client_id: int) -> int:
    return app.gate.inbox._refusals.get(client_id, 0)


def uuid_of(handle) -> str:
    return handle._impl.uuid
