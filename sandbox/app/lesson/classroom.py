"""The class: a world for every student who opens the students' link, the projector, a scene sent to
everyone or to one student, and the class challenge (issue 58, items 1 and 2).
Runs on the app's event thread; a world is built in a worker thread of its own, which posts it back.

Each seat (:mod:`sandbox.app.lesson.seats`) gets a world of its own, started from the scene the teacher
set (the teacher's running world's settings and goal), by ``make_runner`` (any runner of the contract,
:mod:`sandbox.app.world.contract`: by default a :class:`~sandbox.app.world.hosted.HostedRunner`, a
world in one of the class's world hosts, many worlds a process). The student's page gets a
:class:`~sandbox.app.lesson.desk.Desk`: the panel and the floor, its own. A page that leaves pauses
its world; the page that comes back to the seat (a reload) finds it again within
:data:`FREE_AWAY_SECONDS`. After that the world is freed (its memory goes back), and a page that comes
back gets a new one, from the scene the teacher set (and is told so).
"""

from __future__ import annotations

import functools
import logging
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable

from sandbox.app.lesson.desk import Desk
from sandbox.app.lesson.references import References
from sandbox.app.lesson.seats import Seats
from sandbox.app.lesson.wall import Wall
from sandbox.app.panel.framing import PRESENTER
from sandbox.app.world.hosted import CLASS_FPS, CLASS_STEPS_PER_FRAME, HostedRunner
from sandbox.app.world.lockstep import Lockstep, partner_config
from sandbox.app.world.pool import HostPool
from sandbox.app.world.snapshot import Snapshot

log = logging.getLogger("sandbox.app.lesson")

#: How often (s) the teacher's wall shows every student's world afresh: under a second, so that with the
#: event queue's jitter every picture is still new at least once a second (issue 58; at 1.0 the longest
#: gap measured 1.28-1.3 s with 30 students and the teacher's browser). A refresh costs about 25 ms.
WALL_SECONDS = 0.75
#: A seat's world whose page has been gone this long (s) is freed: a reload or a lost connection comes
#: back well within it; a student who closed the page for the lesson gives the class its memory back.
FREE_AWAY_SECONDS = 300.0
#: How often (s) the worlds left alone are looked for (and freed after :data:`FREE_AWAY_SECONDS`).
FREE_CHECK_SECONDS = 1.0
#: The teacher's world pauses when no teacher's page has been open this long (s): students watch worlds
#: of their own, and a world at 25x real time for nobody took about 18 % of a core. A teacher's page that
#: opens again plays it on, if it was playing.
TEACHER_AWAY_SECONDS = 3.0
#: The teacher's world's snapshots a second at most while students have worlds: the teacher's page shows
#: the wall, "a few frames a second" (issue 58), and the floor beside it no more often. Measured with 30
#: students and the teacher's page in Chromium on the class server's 2 cores: the teacher's world sent 30
#: snapshots a second, of which the page, drawing in software, showed 4; each cost the world and the
#: server all the same (docs/performance.md).
TEACHERS_FPS_IN_CLASS = 5.0
#: What a student who comes back after their world was freed reads (one line).
FREED_NOTICE = "Your world was closed while you were away: a new one starts from your teacher's scene."
#: The scene the teacher's running world sets (the wall's first choice of a scene to send).
TEACHERS_WORLD = "the teacher's world"


@dataclass(frozen=True)
class Scene:
    """What a student's world starts from: settings, a goal (vertices, None for the circle, or
    "from-config") and its name."""

    config: Any
    shape: Any
    name: str


class World:
    """One student's world: its runner, the lockstep its panel plays through, and how compare mode
    makes its second world."""

    def __init__(self, identity: str, runner: Any, events: Any, make_partner: Callable[..., Any]):
        self.identity, self.runner = identity, runner
        self.lockstep = Lockstep(runner, events)
        self.make_runner = make_partner
        #: Paused because its page left (played again when a page comes back).
        self.paused_by_leaving = False


class Classroom:
    """The seats' worlds and desks, and the teacher's wall. ``attach(app)`` it to the single world's app
    (its server, gate, event queue and the teacher's runner), then ``start()``; ``stop()`` after the
    event queue stopped."""

    def __init__(self, seats: Seats | None = None, *, make_runner: Callable[..., Any] | None = None,
                 round_steps: int | None = None, pace: tuple[float, int] | None = None):
        """``make_runner``: a student's world (any runner of the contract); by default a world in one of
        this class's world hosts (:mod:`sandbox.app.world.pool`: many worlds a process, a process a core).
        ``pace``: a student world's frames a second and steps a frame (None: a class's 3x real time for
        hosted worlds, the teacher's world's pace for others)."""
        self.seats = seats or Seats()
        self.pace = pace
        #: The class's world hosts, started with its first world (None: worlds come from ``make_runner``).
        self.pool: HostPool | None = None
        #: The class challenge's reference runs (made when the classroom is attached to its app).
        self.references: References | None = None
        if make_runner is None:
            self.pool = HostPool()
            make_runner = functools.partial(HostedRunner, pool=self.pool)
        self.make_runner = make_runner
        #: World steps of a class challenge's round (None: the Challenge folder's own).
        self.round_steps = round_steps
        self.worlds: dict[str, World] = {}
        self.desks: dict[str, Desk] = {}
        self.page_of: dict[str, Any] = {}  # seat -> its page (client), while one is open
        self.projected: str | None = None
        self.entrants: list[str] = []  # the seats in the class challenge
        #: Since when (time.monotonic()) each seat's world has had no page open.
        self.away_since: dict[str, float] = {}
        #: The scene the teacher last sent each seat (a freed world comes back on it).
        self.scene_of: dict[str, Scene] = {}
        #: The seats whose world was freed and whose page has not come back yet.
        self.freed: set[str] = set()
        #: The views the teacher's pages had before a student's world went on the projector.
        self._views_before: dict[int, str] = {}
        self._stopping = False

    # ------------------------------------------------------------ set-up
    def attach(self, app: Any) -> None:
        """Join the app (on the main thread, before its event queue opens): the wall goes in its panel."""
        self.app, self.events, self.gate, self.server = app, app.events, app.gate, app.server
        self.teacher = app.runner
        self.fps, self.steps_per_frame = self._students_pace(app.runner)
        self.wall = Wall(self.server.gui, self, scenes=(TEACHERS_WORLD, *partner_cases()))
        #: The class challenge's reference runs, one a world for the class (not a process pool a student).
        self.references = References(self.events)

    def _students_pace(self, teachers: Any) -> tuple[float, int]:
        """A new student world's frames a second and steps a frame: as given, else a class's 3x real time
        for hosted worlds (a student may speed theirs up), else the teacher's world's."""
        if self.pace is not None:
            return self.pace
        if self.pool is not None:
            return CLASS_FPS, CLASS_STEPS_PER_FRAME
        return teachers.fps, teachers.steps_per_frame

    def start(self) -> None:
        self.events.every(WALL_SECONDS, self.wall.refresh)
        self.events.every(FREE_CHECK_SECONDS, self.free_left_alone)

    def teachers_most_fps(self) -> float | None:
        """The most snapshots a second the teacher's world needs (:data:`TEACHERS_FPS_IN_CLASS` while any
        student has a world; None, as many as its pages draw, before the class arrives)."""
        return TEACHERS_FPS_IN_CLASS if self.worlds else None

    def stop(self) -> None:
        """After the event queue stopped: the desks' workers and the worlds end."""
        self._stopping = True
        for desk in list(self.desks.values()):
            desk.close()
        for world in list(self.worlds.values()):
            world.runner.stop()
        if self.pool is not None:
            self.pool.stop()
        if self.references is not None:
            self.references.stop()

    def seated(self, client_id: int) -> bool:
        """Whether the page ``client_id`` holds a seat (its world is its own, not the teacher's)."""
        grant = self.gate.grant(client_id)
        return grant is not None and bool(grant.seat)

    def students_link(self, teachers_link: str) -> str:
        """The students' link beside the teacher's (the same address, without the token)."""
        from sandbox.app.web.access import JOIN_PATH

        return teachers_link.split("?", 1)[0].rstrip("/") + JOIN_PATH

    # ------------------------------------------------------------ pages
    def arrive(self, client: Any, grant: Any) -> None:
        """A seat's page connected: its world (built from the teacher's scene the first time), its desk."""
        identity = grant.seat
        self.seats.claim(identity)
        self.page_of[identity] = client
        self.away_since.pop(identity, None)
        world = self.worlds.get(identity)
        if world is None:
            self._build(identity, self.scene_of.get(identity) or self.teachers_scene())
            return
        if world.paused_by_leaving:
            world.paused_by_leaving = False
            world.lockstep.set_playing(True)
        self._sit(identity)

    def leave(self, client_id: int) -> None:
        """A seat's page left: its desk goes, its world pauses (and waits for the page to come back)."""
        for identity, client in list(self.page_of.items()):
            if client.client_id != client_id:
                continue
            del self.page_of[identity]
            self.away_since[identity] = time.monotonic()
            desk = self.desks.pop(identity, None)
            if desk is not None:
                desk.close()
            world = self.worlds.get(identity)
            if world is not None and world.runner.playing:
                world.paused_by_leaving = True
                world.lockstep.set_playing(False)

    # ------------------------------------------------------------ worlds
    def teachers_scene(self) -> Scene:
        """The scene the teacher set: the teacher's world's settings and goal, as it runs now."""
        snap = self.teacher.latest
        return Scene(snap.config, snap.goal_vertices, snap.shape_name)

    def case_scene(self, case: str) -> Scene:
        """A paper case over the teacher's settings (its goal from the case)."""
        return Scene(partner_config(self.teacher.latest.config, case), "from-config", case)

    def scene_named(self, name: str) -> Scene:
        return self.teachers_scene() if name == TEACHERS_WORLD else self.case_scene(name)

    def send(self, scene: Scene, identities: list[str] | None = None) -> list[str]:
        """Every seat (or those named) starts again from ``scene``: a new world each, built in a worker,
        which replaces the old once built. Returns the seats it goes to."""
        targets = [seat.identity for seat in self.seats.all() if seat.identity in self.worlds] \
            if identities is None else [i for i in identities if i in self.worlds]
        for identity in targets:
            self.scene_of[identity] = scene
            self._build(identity, scene)
        return targets

    def free_left_alone(self, now: float | None = None) -> list[str]:
        """Free the worlds whose page has been gone :data:`FREE_AWAY_SECONDS` (every second); returns
        their seats. A world built while its page left counts from when it is first seen alone."""
        now = time.monotonic() if now is None else now
        freed = []
        for identity in list(self.worlds):
            if identity in self.page_of:
                continue
            since = self.away_since.setdefault(identity, now)
            if now - since >= FREE_AWAY_SECONDS:
                self._free(identity)
                freed.append(identity)
        return freed

    def _free(self, identity: str) -> None:
        """The seat's world goes (its host frees it at once); the seat stays, for the student to come back."""
        world = self.worlds.pop(identity)
        self.away_since.pop(identity, None)
        self.freed.add(identity)
        if self.projected == identity:
            self.project(None)
        end = getattr(world.runner, "free", None) or world.runner.stop  # a hosted world: freed, not kept
        threading.Thread(target=end, name="phototaxis-seat-free", daemon=True).start()

    def _build(self, identity: str, scene: Scene) -> None:
        """Build a world for the seat in a worker thread (it blocks for a while); it is adopted on the
        event thread."""
        def build() -> None:
            try:
                # Built here (it blocks), started once its desk is on the page: the page meets it at step 0,
                # playing, with nothing to offer ("Joining mid-run" is for a page that comes back).
                runner = self.make_runner(scene.config, shape=scene.shape, fps=self.fps,
                                          steps_per_frame=self.steps_per_frame, playing=True,
                                          deliver=self.events.post)
            except Exception as exc:  # noqa: BLE001 - said on the student's page, the class goes on
                log.warning("a student's world could not be built: %s", exc)
                self.events.post(self._not_built, identity, str(exc))
                return
            try:
                self.events.post(self._adopt, identity, runner, scene)
            except Exception:  # noqa: BLE001 - the app stopped meanwhile: the world goes with it
                runner.stop()

        threading.Thread(target=build, name="phototaxis-seat-world", daemon=True).start()

    def _make_partner(self, config: Any, **kwargs: Any) -> Any:
        """Compare mode's second world in a student's desk: a runner as the student's."""
        return self.make_runner(config, fps=self.fps, steps_per_frame=self.steps_per_frame,
                                deliver=self.events.post, **kwargs)

    def _adopt(self, identity: str, runner: Any, scene: Scene) -> None:
        if self._stopping:
            runner.stop()
            return
        old = self.worlds.get(identity)
        world = self.worlds[identity] = World(identity, runner, self.events, self._make_partner)
        runner.subscribe(lambda snap, world=world: self.events.post_latest(
            ("seat-frame", id(world)), self._on_frame, world, snap))
        runner.on_halt(lambda why, world=world: world.lockstep.set_playing(False))
        if old is not None:
            desk = self.desks.pop(identity, None)
            if desk is not None:
                desk.close()
                desk.clear()
            threading.Thread(target=old.runner.stop, name="phototaxis-seat-stop", daemon=True).start()
        try:
            self._sit(identity)
        finally:
            runner.start()
        if identity in self.freed and identity in self.page_of:
            self.freed.discard(identity)
            self.page_of[identity].add_notification("Welcome back", FREED_NOTICE, color="blue",
                                                    auto_close_seconds=10.0)
        elif scene is not None and old is not None and identity in self.page_of:
            self.page_of[identity].add_notification("A new scene from your teacher", f"Your world starts "
                                                    f"again: {scene.name}.", color="blue",
                                                    auto_close_seconds=8.0)

    def _not_built(self, identity: str, why: str) -> None:
        client = self.page_of.get(identity)
        if client is not None:
            client.add_notification("Your world cannot start", why[:1].upper() + why[1:] + ".", color="red",
                                    auto_close_seconds=None)

    def _sit(self, identity: str) -> None:
        """The seat's page (if one is open) gets a desk for the seat's world."""
        client, world, seat = self.page_of.get(identity), self.worlds.get(identity), self.seats.get(identity)
        if client is None or world is None or seat is None or identity in self.desks:
            return
        if client.client_id not in self.server.get_clients():
            self.page_of.pop(identity, None)  # it left while its world was built
            return
        try:
            self.desks[identity] = Desk(client, world, seat.label, events=self.events)
        except Exception:
            log.exception("a student's page could not be built")
            raise

    def _on_frame(self, world: World, snap: Snapshot) -> None:
        """A frame of a student's world: to their desk, and to the projector when it shows that world."""
        if self.worlds.get(world.identity) is not world:
            return  # a world replaced since
        desk = self.desks.get(world.identity)
        if desk is not None and desk.world is world and desk.client.client_id in self.server.get_clients():
            desk.draw(snap)  # (a page that left is forgotten at its own event, which may come after this)
        if self.projected == world.identity:
            self.app.project(snap, self.projected_label)

    # ------------------------------------------------------------ the projector
    @property
    def projected_label(self) -> str | None:
        seat = self.seats.get(self.projected) if self.projected else None
        return seat.label if seat is not None else None

    def project(self, identity: str | None) -> None:
        """The teacher's floor shows this student's world, named in its caption, and the teacher's pages
        switch to the presenter layout (the room sees it full size); None: the teacher's own world again,
        each page back in the view it had."""
        self.projected = identity if identity in self.worlds else None
        world = self.worlds.get(self.projected) if self.projected else None
        self.app.project(world.runner.latest if world is not None else None, self.projected_label)
        self._teachers_pages_present(world is not None)
        self.wall.refresh()

    def _teachers_pages_present(self, on: bool) -> None:
        """The teacher's pages in the presenter layout (``on``), or back in the views they had before."""
        framing = self.app.panel.framing
        for client in list(self.app.pages.get_clients().values()):
            if on:
                self._views_before.setdefault(client.client_id, framing.of(client.client_id))
                framing.choose(client, PRESENTER)
            elif client.client_id in self._views_before:
                framing.choose(client, self._views_before[client.client_id])
        if not on:
            self._views_before.clear()

    # ------------------------------------------------------------ the class challenge
    def start_challenge(self) -> list[str]:
        """The same round (the paper's seed, the same steps) starts on every student's desk; returns the
        seats in it."""
        self.entrants = []
        for identity, desk in self.desks.items():
            seat = self.seats.get(identity)
            challenge = desk.panel.challenge
            challenge.reference = self.references.ask  # one reference run a world, for the class
            if self.round_steps is not None:
                challenge.round_steps = int(self.round_steps)
            challenge.start(seat.label if seat else "student", desk.client)
            self.entrants.append(identity)
        return self.entrants

    def challenge_results(self) -> list[tuple[str, Any, str]]:
        """(label, score or None, what it is doing) of each seat in the class challenge, best first (a
        score is a :class:`~sandbox.model.challenge.Gain`: boxes brought in, their share)."""
        rows = []
        for identity in self.entrants:
            seat, desk = self.seats.get(identity), self.desks.get(identity)
            label = seat.label if seat else "?"
            r = desk.panel.challenge.round if desk is not None else None
            if r is None:
                rows.append((label, None, "left the round"))
            elif r.score is None:
                world = self.worlds.get(identity)
                step = world.runner.latest.step if world is not None else 0
                rows.append((label, None, f"playing, step {step:,} of {r.steps:,}"))
            else:
                rows.append((label, r.score, "done"))
        return sorted(rows, key=lambda row: (row[1] is None, -(row[1].brought if row[1] else 0),
                                              -(row[1].share if row[1] else 0.0), row[0]))


def partner_cases() -> tuple[str, ...]:
    """The paper's cases a scene may be (those compare mode offers)."""
    from sandbox.app.world.lockstep import COMPARE_CASES

    return tuple(COMPARE_CASES)
