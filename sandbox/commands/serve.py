"""``phototaxis serve``: the browser sandbox.

:class:`App` glues the pieces: a runner (the simulation, by default in a
process of its own: :class:`~sandbox.app.world.child.ProcessRunner`), a
:class:`~sandbox.app.view.scene.SceneView` (what is drawn) and a
:class:`~sandbox.app.panel.Panel` (the controls), on one viser server.
Every connected browser sees the same simulation and the same panel; with a
``lesson`` (``serve --class``: :class:`~sandbox.app.lesson.classroom.Classroom`),
a page that holds a seat gets a world of its own instead, and the teacher's
panel a wall of them.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import os
import re
import socket
import time
from pathlib import Path
from typing import Any

from sandbox.app.lesson.classroom import TEACHER_AWAY_SECONDS, Classroom
from sandbox.app.lesson.pages import TeacherPages
from sandbox.app.web.access import WATCH, Access, is_loopback_host, is_shared, new_token, well_formed_token
from sandbox.app.view.partner import Comparison
from sandbox.app.world.lockstep import Lockstep, side_config
from sandbox.app.web.events import EventQueue, QueueStopped
from sandbox.app.web.gate import start_server
from sandbox.app.web.icons import read_icons_once
from sandbox.app.web.memory import return_memory_after_pages_leave
from sandbox.app.web.pacing import frames_per_snapshot
from sandbox.app.panel import Panel
from sandbox.app.panel.framing import PRESENTER, WHOLE_ARENA
from sandbox.app.world.child import ProcessRunner, SimulationCrashed
from sandbox.app.world.orders import PlayDesign, SetProgram
from sandbox.app.world.runner import Runner
from sandbox.app.view.scene import PHONE_ASPECT, SceneView, configure_scene
from sandbox.app.world.snapshot import Snapshot
from sandbox.app.web.stopping import interruptible, starting, term_stops
from sandbox.app.web.viser_seam import ViserMismatch
from sandbox.app.web.viser_seam import check as check_viser
from sandbox.cli import (UserError, add_config_arguments, add_controller_argument, add_design_argument,
                         config_from_args, controller_from_args, design_from_args, program_time_limit)
from sandbox.model.config import Config, ConfigError
from sandbox.model.watchdog import DEFAULT_LIMIT
from sandbox.processes import start_fork_server, stop_fork_server
from sandbox.shapes import ShapeError, shape_vertices

TITLE = "Phototaxis sandbox"
#: With no browser connected for this long, the app stops stepping (unless --keep-running).
IDLE_PAUSE_SECONDS = 60.0
#: How often (s) the worlds' snapshot rate follows the pages' drawing (sandbox.app.web.pacing).
PACE_SNAPSHOTS_EVERY = 0.5
#: For this long after a page connects, each change of its window's shape fits its camera to the
#: arena again (s): the page lays itself out, slowly on a loaded machine.
FIT_SECONDS = 30.0
#: As the app stops, how long (s) it waits for the panel's workers (the advisor's trials, the challenge's
#: reference runs) to end: they were told to at once, and end within a fraction of it.
STOP_WORKERS_SECONDS = 5.0

log = logging.getLogger("sandbox.app")


class App:
    """A live simulation served to browsers. ``start()`` it, ``stop()`` it."""

    def __init__(self, config: Config, *, host: str = "127.0.0.1", port: int = 8080, shape: Any = "from-config",
                 fps: float = 30.0, steps_per_frame: int = 25, playing: bool = True, verbose: bool = False,
                 process: bool = True, keep_running: bool = False, idle_pause_seconds: float = IDLE_PAUSE_SECONDS,
                 controller: str | None = None, allow_programs: bool = False, access: Access | None = None,
                 program_time_limit: float = DEFAULT_LIMIT, whole_arena: bool = True,
                 compare: tuple[Config, str] | None = None, design: Any = None, lesson: Any = None):
        """``lesson``: class mode (a :class:`~sandbox.app.lesson.classroom.Classroom`, whose seats the access
        knows): the pages that hold a seat are the lesson's, the others this world's; ``compare``: start in compare mode against a world of this configuration (its goal from the
        configuration), named so in the Compare folder (``serve --compare``); ``design``: start on a design
        (sandbox.model.design.Design), lit by its recorded light program (``serve --design``)."""
        if isinstance(shape, str) and shape == "from-config":
            shape = shape_vertices(config.shape)  # raises ShapeError before any server starts
        self.config = config
        #: What a new page's camera frames: the whole arena, or (classroom) the construction area.
        self.whole_arena = whole_arena
        #: Who may connect and what each page may do (sandbox.app.web.access); shared beyond this machine,
        #: control needs the token in :attr:`url`.
        self.access = access or Access.for_server(host, allow_programs=allow_programs)
        #: The one queue every change of the app's state goes through (docs/code.md, "Threads"). It is
        #: served from the end of this constructor on: no callback runs before the app exists.
        self.events = EventQueue()
        kind = ProcessRunner if process else Runner
        # The simulation process starts (about a second) while the server and the panel are built.
        # Its answers (on_done, on_error), its build progress and its crash notices come on the event queue.
        self.runner = kind(config, shape=shape, fps=fps, steps_per_frame=steps_per_frame, playing=playing,
                           program_time_limit=program_time_limit, deliver=self.events.post,
                           **({"wait": False} if process else {}))
        self._compare_with = compare

        def make_runner(partner_config: Config, **kwargs: Any) -> Any:  # compare mode's second world
            return kind(partner_config, fps=fps, steps_per_frame=self.runner.steps_per_frame,
                        program_time_limit=program_time_limit, deliver=self.events.post, **kwargs)

        self.lockstep = Lockstep(self.runner, self.events)  # on the event queue
        try:
            self.server, self.gate = start_server(self.access, host=host, port=port, label=TITLE, verbose=verbose,
                                                  callbacks=self.events.submit)
        except BaseException:
            self.events.stop()
            self.runner.stop()  # do not leave the simulation process behind
            raise
        try:
            read_icons_once()
            self._configure_page()
            with interruptible():  # the first world may take long to build: a stop asked for meanwhile acts now
                first = self.runner.latest
            self.view = SceneView(self.server.scene, first, caption_over_construction=not whole_arena)
            self.comparison = Comparison(self.server, self.lockstep, make_runner,
                                         on_layout=self._reframe_all, on_crash=self._on_partner_crash,
                                         caption_over_construction=not whole_arena, events=self.events)
            # Loading a program runs a Python file on this machine: every page may where the server is for
            # this machine alone or --allow-programs, else only a page on this machine; the gate decides per page.
            offered = self.access.allow_programs or not is_shared(host)
            self.lesson = lesson
            #: The server as this world's panel sees it: in class mode, without the students' pages.
            self.pages = TeacherPages(self.server, lesson.seated) if lesson is not None else self.server
            #: The student's frame the floor shows last (the lesson's projector), or None: this world's.
            self.on_projector: Snapshot | None = None
            self.panel = Panel(self.pages, self.runner, self.view, self.comparison, events=self.events,
                               allow_programs=offered, may_load_programs=self.gate.may_load_programs,
                               default_view=WHOLE_ARENA if whole_arena else PRESENTER)
            if lesson is not None:
                lesson.attach(self)  # its wall goes in the panel
        except BaseException:
            self.events.stop()
            _stop_quietly(self.server)  # do not leave a half-built server listening
            self.runner.stop()
            raise
        self.frames_drawn = 0
        self.runner.subscribe(lambda snap: self.events.post_latest("frame", self._on_frame, snap))
        # A frame that failed halted the world: the event thread, which owns play, pauses it (both worlds).
        self.runner.on_halt(lambda why: self.lockstep.set_playing(False))
        if process:
            self.runner.on_crash(self._on_crash)  # delivered on the event queue
            self.runner.on_settings_back(self.panel.show_settings)  # the panel shows the settings that stand
        # With no viewer for a while, stop stepping (a forgotten demo should not heat the room).
        self.keep_running, self.idle_pause_seconds = keep_running, idle_pause_seconds
        self.auto_paused = False  # owned by the event thread, as everything below
        self._last_viewer = time.monotonic()
        #: Each page's camera is fitted to the arena as the page tells its shape, until this (monotonic) time.
        self._fitting: dict[int, tuple[float, float | None]] = {}
        # viser replays these for pages that came while the app was built: through the queue, once each.
        self.server.on_client_connect(self._on_connect)
        self.server.on_client_disconnect(self._on_disconnect)
        self.memory = return_memory_after_pages_leave(self.server, self.events.after)  # what pages leave goes back to the system
        self._controller = controller
        self._design = design
        self.events.open()

    # ------------------------------------------------------------ set-up
    def _configure_page(self) -> None:
        server = self.server
        server.gui.configure_theme(dark_mode=True, control_width="large", show_logo=False,
                                   show_share_button=False, brand_color=(255, 190, 40))
        # Dock the panel beside the canvas so the arena is never hidden behind it.
        server.gui.main_panel.dock_right()
        server.gui.main_panel.set_width(420)
        if not self.whole_arena:
            # Every page starts in the presenter layout, its panel folded (sandbox.app.panel.framing). Folded
            # in the state every page is first sent, before the panel's controls: the page then never builds
            # them before the title card (measured: about 0.4 s of the first visit's main thread), where
            # folding each page at its arrival builds them first, then folds them away.
            server.gui.main_panel.minimize()
        configure_scene(server, self.config, whole=self.whole_arena)

    # ------------------------------------------------- events (all on the event thread)
    def _on_frame(self, snap: Snapshot) -> None:
        # The scene and the panel's read-outs of one snapshot in one batch: the page applies a
        # batch at once, so what it shows comes from one step.
        with self.server.atomic():
            if self.on_projector is None:
                self.view.update(snap)
            self.comparison.draw()  # compare mode's second world, in the same picture
            self.panel.update(snap)
        self.panel.inspector.draw(snap)  # each viewer's own marks, in its own messages
        self.panel.on_frame_drawn()
        self.frames_drawn += 1

    def project(self, snap: Snapshot | None, label: str | None = None) -> None:
        """The floor shows ``snap`` (a student's world, class mode's projector; ``label``: whose, before its
        caption), or this world again (None)."""
        self.on_projector = snap
        shown = snap if snap is not None else self.runner.latest
        with self.server.atomic():
            self.view.set_label(label if snap is not None else None, shown)
            self.view.update(shown)

    def _on_disconnect(self, client: Any) -> None:
        self._last_viewer = time.monotonic()
        if self.lesson is not None:
            self.lesson.leave(client.client_id)
        self._fitting.pop(client.client_id, None)
        self.panel.farewell(client.client_id)

    def _on_connect(self, client: Any) -> None:
        self._last_viewer = time.monotonic()
        grant = self.gate.grant(client.client_id)
        if self.lesson is not None and grant is not None and grant.seat:
            self.lesson.arrive(client, grant)  # a student's page: a world of its own
            return
        failed = getattr(self.runner, "failed", None)
        if failed:
            client.add_notification("The simulation cannot start", failed[0].upper() + failed[1:] + ".",
                                    color="red", auto_close_seconds=None)
        # Its title card at step 0, or (if it may control the simulation) Start over mid-run.
        self.panel.welcome(client, controls=grant is not None and grant.controls)
        if self.auto_paused:  # after the page's own parts exist: the frames it then gets are for it
            self.auto_paused = False
            self.lockstep.set_playing(True)
        # Fit the arena to this viewer's window as it tells its shape: its camera reports come while the
        # page lays itself out, and on a loaded machine the last one many seconds later.
        self._fitting[client.client_id] = (time.monotonic() + FIT_SECONDS, None)
        client.camera.on_update(lambda camera, client=client: self._on_camera(client))
        self._fit(client)

    def _on_camera(self, client: Any) -> None:
        """A page's camera moved or its window changed shape (viser's camera report)."""
        self._fit(client)

    def _fit(self, client: Any) -> None:
        """While a page lays itself out, frame the arena for its window's shape, and in the presenter
        layout whenever its window changes shape (unless it follows a robot: then the inspector moves
        its camera)."""
        fitting = self._fitting.get(client.client_id)
        if fitting is None:
            return
        until, fitted = fitting
        aspect = client.camera.aspect
        if not aspect or aspect == fitted or client.client_id in self.panel.inspector.followers:
            return
        # Later, the window changed shape: the presenter layout, which promises the floor framed for the
        # room, is framed again (its panel opened or folded), and so is a phone (its drawer opened over the
        # floor: the page's canvas ends at the drawer, page/layout.js); another view keeps its camera.
        phone = min(aspect, fitted or aspect) < PHONE_ASPECT
        if time.monotonic() <= until or phone or self.panel.framing.of(client.client_id) == PRESENTER:
            self.panel.framing.apply(client, lamp_in_view=phone and fitted is not None)  # as its View says
        self._fitting[client.client_id] = (until, aspect)

    def _check_viewers(self) -> None:
        """Every second: with no viewer for a while, pause (unless --keep-running). In class mode the
        viewers are the teacher's pages (students watch worlds of their own), gone for a few seconds."""
        idle = self.idle_pause_seconds if self.lesson is None else min(self.idle_pause_seconds, TEACHER_AWAY_SECONDS)
        if self.pages.get_clients():
            self._last_viewer = time.monotonic()
        elif (not self.keep_running and self.runner.playing
              and time.monotonic() - self._last_viewer >= idle):
            self.auto_paused = True
            self.lockstep.set_playing(False)

    def _pace_snapshots(self) -> None:
        """Twice a second: the worlds take a snapshot only as often as the fastest page draws (with
        headroom; every frame while any page keeps up). In class mode, as the teacher's pages draw (the
        students' draw worlds of their own), and no more often than the class wants the teacher's world shown."""
        pages = None if self.lesson is None else list(self.pages.get_clients())
        most = None if self.lesson is None else self.lesson.teachers_most_fps()
        self.lockstep.show_every(frames_per_snapshot(self.runner.fps, self.gate.pacer.drawing_rates(pages=pages),
                                                     most=most))

    def _reframe_all(self, offset: tuple[float, float] | None) -> None:
        """Compare mode began or ended: every page frames both worlds, or the one."""
        self.panel.framing.offset = offset
        with self.server.atomic():  # beside a second world, the caption goes over the construction wall
            self.view.set_compared(offset, self.runner.latest)
        for client in list(self.pages.get_clients().values()):
            if client.client_id not in self.panel.inspector.followers:
                self.panel.framing.apply(client)

    def _on_partner_crash(self, why: str) -> None:
        what = re.split("; (?:restarting|back to)", why)[0]  # what comes next is compare mode's end
        for client in self.pages.get_clients().values():
            client.add_notification("The compared world stopped", what[0].upper() + what[1:]
                                    + ". Compare mode has ended; the running world goes on alone.", color="red",
                                    auto_close_seconds=20.0)

    def _on_crash(self, why: str) -> None:
        given_up = self.runner.failed is not None
        title = "The simulation cannot start" if given_up else "The simulation stopped"
        for client in self.pages.get_clients().values():
            client.add_notification(title, why[0].upper() + why[1:] + ".", color="red",
                                    auto_close_seconds=None if given_up else 20.0)

    # -------------------------------------------------------------- life
    @property
    def port(self) -> int:
        return self.server.get_port()

    @property
    def url(self) -> str:
        """The address to open, with the token when one is needed (as ``jupyter`` prints it)."""
        host = self.server.get_host()
        shown = "localhost" if is_loopback_host(host) else host
        if host in ("0.0.0.0", "::", ""):
            shown = socket.gethostname()
        return self.access.url(shown)

    def start(self) -> "App":
        self.runner.start()
        if self._controller:  # the light program given on the command line, before anyone looks
            try:
                self.runner.call(SetProgram(self._controller), 30.0)
            except Exception as exc:
                self.stop()
                raise UserError(str(exc)) from None
        if self._design is not None:  # its recorded light program, from its seed, before anyone looks
            try:
                self.runner.call(PlayDesign(self._design), 60.0)
            except Exception as exc:
                self.stop()
                raise UserError(f"the design cannot play: {exc}") from None
        if self._compare_with is not None:
            partner_config, label = self._compare_with
            try:
                self.comparison.begin(partner_config, "from-config", label)
            except Exception as exc:
                self.stop()
                raise UserError(f"the compared world cannot start: {exc}") from None
        self.events.every(1.0, self._check_viewers)
        self.events.every(PACE_SNAPSHOTS_EVERY, self._pace_snapshots)
        if self.lesson is not None:
            self.lesson.start()
        return self

    def stop(self) -> None:
        stop_workers(self.events, self.panel)
        self.events.stop()  # no event runs from here on: what follows owns the app's state alone
        lesson = getattr(self, "lesson", None)  # (an app stopped while it was built may have none yet)
        if lesson is not None:
            lesson.stop()
        self.comparison.end()
        self.runner.stop()
        _stop_quietly(self.server)


def stop_workers(events: EventQueue, panel: Panel, timeout: float = STOP_WORKERS_SECONDS) -> None:
    """The panel's workers (the advisor's trials, the challenge's reference runs) stop through the event
    queue, whose thread owns what they report to, and this thread waits for them, at most ``timeout``
    seconds in all: they post to the queue as they end, so it stops only after. Nothing to do once the
    queue has stopped (a second stop)."""
    deadline = time.monotonic() + timeout
    try:
        workers = events.call(panel.stop, timeout=timeout)
    except QueueStopped:
        return
    except TimeoutError:
        log.warning("the panel's workers were not stopped within %.0f s: the app stops without them", timeout)
        return
    for worker in workers:
        worker.join(max(0.0, deadline - time.monotonic()))
    if any(worker.is_alive() for worker in workers):
        log.warning("a worker of the panel was still running %.0f s after the app asked it to stop", timeout)


def _stop_quietly(server: Any) -> None:
    with contextlib.redirect_stdout(io.StringIO()):  # viser says goodbye on stdout
        server.stop()


def free_port(host: str = "127.0.0.1") -> int:
    with socket.socket() as s:
        s.bind((host, 0))
        return s.getsockname()[1]


# ------------------------------------------------------------------- CLI
def add_parser(sub: Any) -> argparse.ArgumentParser:

    p = sub.add_parser("serve", help="start the browser sandbox (the default command)",
                       description="Start a live simulation in the browser. Open the printed URL. "
                       "Every model parameter is a flag; --case picks one of the paper's seven cases.")
    p.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; "
                        "0.0.0.0 shares it on the network)")
    p.add_argument("--port", type=int, default=8080, help="port to listen on (default 8080; the next free one if taken)")
    p.add_argument("--paused", action="store_true", help="start paused")
    p.add_argument("--classroom", action="store_true",
                   help="for a class: wait at step 0 until someone presses Play, and frame each new page on the "
                        "construction area, where the boxes are built (the Run folder's View buttons switch to "
                        "the whole arena)")
    p.add_argument("--class", dest="class_mode", action="store_true",
                   help="a lab lesson: prints two links, the teacher's (with the token) and the students'; "
                        "each student who opens theirs gets a world of their own, started from the teacher's "
                        "scene, and the teacher's panel shows every world on its Class wall (docs/browser.md)")
    p.add_argument("--steps-per-frame", type=int, default=25, metavar="N",
                   help="speed: world steps between two frames (default 25: 750 steps/s, 25x real time; "
                        "100: as fast as the machine can)")
    p.add_argument("--fps", type=float, default=30.0, help="frame rate the page is updated at (default 30)")
    p.add_argument("--compare", nargs=2, metavar=("LEFT", "RIGHT"), default=None,
                   help="compare mode: two worlds side by side from the same seed, each a paper case's name "
                        "(e.g. star star-switch) or a TOML or JSON file of values over the other flags; play, "
                        "pause, step and reset act on both")
    add_controller_argument(p)
    add_design_argument(p, "open a design file's goal, settings and seed (docs/design-files.md)")
    p.add_argument("--allow-programs", action="store_true",
                   help="let any controlling page load light programs (Python files on this machine), not only "
                        "a page opened on this machine itself")
    sharing = p.add_argument_group("sharing (see docs/security.md)")
    sharing.add_argument("--token", metavar="SECRET", default=None,
                         help="the secret a page needs to control the sandbox (shown in the printed URL); "
                              "served beyond this machine a new one is made unless given (environment: "
                              "PHOTOTAXIS_TOKEN)")
    sharing.add_argument("--viewers", choices=("watch", "none"), default=WATCH,
                         help="what a page without the token may do on a shared server: watch (default) or "
                              "nothing (refused)")
    sharing.add_argument("--allow-host", metavar="NAME", action="append", default=[],
                         help="also answer requests for this host name (repeatable; '*' for any, behind a "
                              "reverse proxy); localhost and the listening address always work")
    sharing.add_argument("--allow-origin", metavar="URL", action="append", default=[],
                         help="also accept websockets from pages of this origin, e.g. https://example.org "
                              "(repeatable); the page's own origin always works")
    sharing.add_argument("--trust-proxy", action="store_true",
                         help="behind a reverse proxy on this machine that sets X-Forwarded-For: take a page's "
                              "address from that header's last entry (by default a request with proxy headers is "
                              "never this machine's page, and every page counts as the proxy's address)")
    p.add_argument("--keep-running", action="store_true",
                   help=f"keep simulating with no browser connected (by default it pauses after "
                        f"{IDLE_PAUSE_SECONDS:.0f} s without one and goes on when one connects)")
    add_config_arguments(p)
    p.set_defaults(func=serve_command)
    return p


def serve_command(args: argparse.Namespace) -> int:
    """Serve until stopped. A SIGTERM or Ctrl+C at any moment, start-up included, stops what has
    started so far (the app, its simulation process, the fork server) and exits with 0 within 2 s
    (:mod:`sandbox.app.web.stopping`)."""
    app, asked = None, False
    with term_stops():  # (the dispatcher has done so already: this is for other callers)
        try:
            app = _app_from_args(args)  # a stop asked for meanwhile: at its first world, or once it is built
            with interruptible():
                app.start()
                _print_address(app, args.host)
                while True:
                    time.sleep(3600)
        except KeyboardInterrupt:
            asked = True  # (an app stopped while it was built stopped what it had started)
        finally:
            if app is not None:
                app.stop()
            stop_fork_server()  # now: it may still be loading the model, and would only end after
            if app is not None or asked:
                print("stopped", flush=True)
    return 0


def _app_from_args(args: argparse.Namespace) -> App:
    """The app the flags ask for (built, not started); a UserError for flags that cannot be served."""
    try:
        check_viser()  # before anything starts: one line naming what this viser lacks
    except ViserMismatch as exc:
        raise UserError(str(exc)) from None
    design = design_from_args(args)  # its goal, settings and seed, lit by its recorded light program
    config = design.config if design else config_from_args(args)
    _check_goal(config, design.shape if design else shape_vertices(config.shape),
                f"{args.design}: its goal" if design else config.shape)
    compare = None
    if args.compare:
        if args.case:
            raise UserError("--compare names both sides' cases; leave out --case")
        try:
            config, right = (side_config(spec, config) for spec in args.compare)
        except (ConfigError, OSError) as exc:
            raise UserError(str(exc)) from None
        compare = (right, Path(args.compare[1]).stem)
    if not 0 <= args.port <= 65535:
        raise UserError(f"--port must be between 0 and 65535, got {args.port}")
    if not 1 <= args.steps_per_frame <= 100:
        raise UserError("--steps-per-frame must be between 1 and 100")
    if not 1 <= args.fps <= 240:
        raise UserError("--fps must be between 1 and 240")
    token = args.token if args.token is not None else os.environ.get("PHOTOTAXIS_TOKEN") or None
    class_mode = getattr(args, "class_mode", False)
    if class_mode and args.compare:
        raise UserError("--class starts every student from the teacher's world; leave out --compare")
    if token is not None and (len(token) < 8 or not well_formed_token(token)):
        raise UserError("--token must be at least 8 characters of printable ASCII, without spaces, quotes, "
                        "commas, semicolons or backslashes")
    if class_mode and token is None:
        token = new_token()  # in a lesson the teacher's page needs the token, even on this machine alone
    lesson = Classroom() if class_mode else None
    try:
        access = Access.for_server(args.host, token=token, viewers=args.viewers, allow_programs=args.allow_programs,
                                   allow_hosts=args.allow_host, allow_origins=args.allow_origin,
                                   trust_proxy=args.trust_proxy)
        access.seats = lesson.seats if lesson is not None else None
    except ValueError as exc:
        raise UserError(str(exc)) from None
    controller = controller_from_args(args)[0]
    starting()  # from here on there are processes and a server to stop: a stop is acted on where it waits
    with interruptible():  # the fork server loads the model (1-3 s): here, where a stop needs no more tidying
        start_fork_server()
    try:
        return App(config, host=args.host, port=args.port, fps=args.fps, steps_per_frame=args.steps_per_frame,
                   playing=not (args.paused or args.classroom), whole_arena=not args.classroom,
                   keep_running=args.keep_running, controller=controller, access=access,
                   program_time_limit=program_time_limit(args), compare=compare,
                   shape=design.shape if design else "from-config", design=design, lesson=lesson)
    except OSError as exc:
        raise UserError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}") from None
    except SimulationCrashed as exc:  # its first world could not be built (out of memory, say)
        raise UserError(f"the simulation cannot start: {exc}") from None


def _check_goal(config: Config, vertices: Any, name: str) -> None:
    """A goal the simulation would refuse (more vertices than the outlines afford, too large for the
    construction area, over the memory budget) is refused here, in one line, before the simulation
    process starts: it would fail to build its first world."""
    from sandbox.model.goal import fit_goal

    try:
        fit_goal(config, vertices)
    except ShapeError as exc:
        raise UserError(f"{name}: {exc}") from None


def _print_address(app: App, host: str) -> None:
    print(f"Phototaxis sandbox running at {app.url}  (Ctrl+C to stop)", flush=True)
    if app.lesson is not None:
        print(f"  the students' link: {app.lesson.students_link(app.url)}  (a world each; the link above is "
              f"the teacher's)", flush=True)
    if app.access.token and is_shared(host):
        watchers = "may watch" if app.access.viewers == WATCH else "are refused"
        print(f"  shared beyond this machine: pages without the token {watchers}; only pages with it control",
              flush=True)
