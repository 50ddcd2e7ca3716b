"""``phototaxis bench --class K``: a class server (``serve --class``) with K students' pages over
websockets, and optionally the teacher's page in a headless Chromium: each student world's speed and
frames to its page, the bytes each page receives, the wall's refresh, and the server's CPU and memory
(issue 58, item 4).

Each student does what a page does without a browser: asks the students' link (``GET /join``, sent on
to ``/seat/<identity>``), opens viser's websocket at its seat, says hello (the first camera message),
and receives. viser's client sends nothing back per frame; the app's pacing (sandbox.app.web.pacing)
hears a page through the script it sends at connect, which reports ``/__drawn/<token>``: a page that
keeps up says ``?calm`` once, after its first second, and is then sent every frame. The students here
are such pages (they draw nothing, so they keep up). A student counts the bytes and the websocket
messages it receives; a message is one window of the page's updates, a frame when the server batches
a frame at once (a desk draws each frame in one batch).

The students run in a process of their own (threads there), so that the server's CPU is the server's:
this process runs the server (its event thread, viser's loop, the teacher's world's process and the
class's world hosts), and reads each world's latest step from ``app.lesson.worlds``. CPU and memory are
read from /proc (Linux), as :mod:`.hosted_bench` does.
"""

from __future__ import annotations

import contextlib
import http.client
import multiprocessing
import os
import re
import statistics
import threading
import time
from typing import Any

from sandbox.app.world.hosted import CLASS_FPS, CLASS_STEPS_PER_FRAME
from sandbox.cli import UserError
from sandbox.commands.hosted_bench import cpu_seconds, memory_mb
from sandbox.model.config import Config

#: Seconds from the last student's desk to the measurement (the worlds' first frames, the pages' calm).
WARM_UP = 5.0
#: Longest wait (s) for the class to be seated: K worlds built in the hosts' queues.
SEATING_SECONDS = 600.0
#: The measurement is also told in windows of this many seconds (``by_window``): a world's step costs
#: several times more while its robots push the boxes (issue 58: 590 us against 60-150 us, steps
#: 4,000-7,000 of the paper's world), and a mean over the whole measurement hides when.
WINDOW = 10.0
#: A page that keeps up says so after its first second of drawing (page/report.js).
CALM_AFTER = 1.0
TOKEN = "class-bench-token"
DRAWN = re.compile(rb'__phototaxisDrawn = "(/__drawn/[A-Za-z0-9_\-]+)"')


# ------------------------------------------------------------------ the students (their own process)
class Student:
    """One student's page without a browser: its seat, its websocket, what it received."""

    def __init__(self, port: int):
        self.port = port
        self.identity = ""
        self.bytes = 0
        self.messages = 0
        self.calm = False
        self.error = ""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="class-bench-student", daemon=True)

    def join(self) -> None:
        """Ask the students' link for a seat (one line of error if it is refused)."""
        connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=30)
        connection.request("GET", "/join")
        response = connection.getresponse()
        response.read()
        location = response.getheader("Location") or ""
        if response.status != 302 or "/seat/" not in location:
            raise RuntimeError(f"the students' link answered {response.status} {location!r}")
        self.identity = location.rsplit("/", 1)[1]
        self._thread.start()

    def _run(self) -> None:
        import msgspec
        import zstandard
        from importlib.metadata import version
        from websockets.sync.client import connect

        origin = f"http://127.0.0.1:{self.port}"
        try:
            with connect(f"ws://127.0.0.1:{self.port}/seat/{self.identity}", subprotocols=[
                    f"viser-v{version('viser')}"], additional_headers={"Origin": origin}, origin=None,
                    max_size=None, open_timeout=60) as ws:
                ws.send(msgspec.msgpack.encode(hello()))
                report, since = None, time.monotonic()
                while not self._stop.is_set():
                    try:
                        raw = ws.recv(timeout=0.5)
                    except TimeoutError:
                        continue
                    self.bytes += len(raw)
                    self.messages += 1
                    if report is None:  # the reporting script comes at connect, in the first messages
                        report = reporting_address(raw, zstandard)
                        since = time.monotonic()
                    elif not self.calm and time.monotonic() - since >= CALM_AFTER:
                        self.calm = say_calm(self.port, report, origin)
        except Exception as exc:  # noqa: BLE001 - reported with the counts
            self.error = f"{type(exc).__name__}: {exc}"

    def counts(self) -> tuple[str, int, int, str]:
        return self.identity, self.bytes, self.messages, self.error

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)


def hello() -> dict:
    """The first camera message: viser counts a page as connected only after it."""
    return {"type": "ViewerCameraMessage", "wxyz": (1.0, 0.0, 0.0, 0.0), "position": (0.0, 0.0, 10.0),
            "fov": 1.0, "near": 0.01, "far": 1000.0, "image_height": 800, "image_width": 1280,
            "look_at": (0.0, 0.0, 0.0), "up_direction": (0.0, 0.0, 1.0)}


def reporting_address(raw: bytes, zstandard: Any) -> str | None:
    """Where the page reports its drawing (the pacing script's address), if this message carries it."""
    inner_size = int.from_bytes(raw[0:8], "little")
    compressed_size = int.from_bytes(raw[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(raw[16:16 + compressed_size], max_output_size=inner_size)
    found = DRAWN.search(inner)
    return found.group(1).decode() if found else None


def say_calm(port: int, address: str, origin: str) -> bool:
    """Tell the server this page keeps up (page/report.js does so once, after a second of drawing)."""
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    connection.request("GET", address + "?calm", headers={"Origin": origin})
    connection.getresponse().read()
    return True


def crowd(port: int, students: int, pipe: Any) -> None:
    """The students' process: seat ``students`` pages one after another, then answer the bench's asks
    ("counts": every page's (identity, bytes, messages, error) and how many said calm; "stop")."""
    pages: list[Student] = []
    try:
        for _ in range(students):
            page = Student(port)
            page.join()
            pages.append(page)
            pipe.send(("joined", page.identity))
            if pipe.poll() and pipe.recv() == "stop":
                return
        while True:
            ask = pipe.recv()
            if ask == "stop":
                return
            pipe.send(([page.counts() for page in pages], sum(page.calm for page in pages)))
    except Exception as exc:  # noqa: BLE001 - the bench says it in one line
        pipe.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        for page in pages:
            page.close()


class Crowd:
    """The students' process, from the bench's side."""

    def __init__(self, port: int):
        self.pipe, self._theirs = multiprocessing.get_context("spawn").Pipe()
        self.port = port
        self.process: Any = None

    def seat(self, students: int) -> list[str]:
        """Start the students' process, which seats them one after another; returns once all have seats."""
        context = multiprocessing.get_context("spawn")
        self.process = context.Process(target=crowd, args=(self.port, students, self._theirs),
                                       name="class-bench-students", daemon=True)
        self.process.start()
        return [self._expect("joined") for _ in range(students)]

    def _expect(self, what: str, timeout: float = 120.0) -> Any:
        if not self.pipe.poll(timeout):
            raise UserError(f"the class benchmark's students did not answer within {timeout:.0f} s")
        kind, value = self.pipe.recv()
        if kind == "error":
            raise UserError(f"a student could not join: {value}")
        return value

    def counts(self) -> tuple[dict[str, tuple[int, int, str]], int]:
        self.pipe.send("counts")
        if not self.pipe.poll(60):
            raise UserError("the class benchmark's students did not answer within 60 s")
        rows, calm = self.pipe.recv()
        return {identity: (sent, messages, error) for identity, sent, messages, error in rows}, calm

    def stop(self) -> None:
        if self.process is None:
            return
        with contextlib.suppress(OSError):
            self.pipe.send("stop")
        self.process.join(10)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(5)


# ------------------------------------------------------------------ the teacher's page (optional)
WALL_WATCH_JS = """() => { window.__wallPictures = []; new MutationObserver((changes) => {
  for (const c of changes) if (c.target.tagName === "IMG" && c.attributeName === "src")
    window.__wallPictures.push(performance.now()); })
  .observe(document.body, {subtree: true, attributes: true, attributeFilter: ["src"]}); }"""


# ------------------------------------------------------------------ the server's side
class WallClock:
    """When the teacher's wall sent a new picture (wraps the wall's refresh; on the event thread)."""

    def __init__(self, wall: Any):
        self.wall, self.sent, self.refreshes = wall, [], 0
        refresh = wall.refresh

        def counted() -> None:
            before = wall._drawn_key
            refresh()
            self.refreshes += 1
            if wall._drawn_key != before:
                self.sent.append(time.monotonic())

        wall.refresh = counted


class DeskFrames:
    """How many frames each student's desk drew for its page (wraps the classroom's frame handler, on
    the event thread): between the world's frames and the page's messages."""

    def __init__(self, lesson: Any):
        self.drawn: dict[str, int] = {}
        on_frame = lesson._on_frame

        def counted(world: Any, snap: Any) -> None:
            on_frame(world, snap)
            self.drawn[world.identity] = self.drawn.get(world.identity, 0) + 1

        lesson._on_frame = counted


def published_now(app: Any, identities: list[str]) -> dict[str, int]:
    """The frames each student's world has sent the server so far."""
    worlds = dict(app.lesson.worlds)
    return {identity: getattr(worlds[identity].runner, "frames_published", 0) for identity in identities
            if identity in worlds}


def steps_now(app: Any, identities: list[str]) -> dict[str, int]:
    worlds = dict(app.lesson.worlds)  # (read from this thread: a copy of the event thread's dict)
    return {identity: worlds[identity].runner.latest.step for identity in identities if identity in worlds}


def server_pids(app: Any) -> dict[str, list[int]]:
    """The server's processes: this one, the teacher's world's, and the class's world hosts."""
    pool = app.lesson.pool
    hosts = [host.process.pid for host in pool.hosts if not host.dead] if pool is not None else []
    teacher = getattr(getattr(app.runner, "process", None), "pid", None)
    return {"server": [os.getpid()], "teachers_world": [teacher] if teacher else [], "hosts": hosts}


def browser_pids() -> list[int]:
    """The teacher's Chromium: every Chromium process under this one (Playwright's driver starts it)."""
    found = []
    for pid in descendants(os.getpid()):
        with contextlib.suppress(OSError):
            with open(f"/proc/{pid}/comm") as fh:
                if "chrom" in fh.read():
                    found.append(pid)
    return found


def rss_of(pids: list[int]) -> float:
    return sum(memory_mb(pid)[0] for pid in pids)


def pss_of(pids: list[int]) -> float:
    """PSS shares out the pages the processes share (the hosts and the teacher's world with the fork
    server they were forked from)."""
    return sum(memory_mb(pid)[1] for pid in pids)


def intervals(times: list[float]) -> list[float]:
    return [b - a for a, b in zip(times, times[1:])]


def wait_for(condition: Any, seconds: float, what: str) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            raise UserError(f"the class benchmark gave up waiting for {what} after {seconds:.0f} s")
        time.sleep(0.1)


def descendants(pid: int) -> list[int]:
    """Every process started under ``pid`` (the fork server, and what it forked: the hosts, the teacher's
    world, the challenge's reference pools), read from /proc."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            children.setdefault(ppid, []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def spread_out(app: Any, identities: list[str], steps: int) -> None:
    """Run student i of K's world to step ``steps`` x i / K (each a *Run to the end* in its host's queue of
    builds), as a class's worlds are when its students started at different times: the worlds then pass
    through the dense phases, where a step costs several times more, at different times, not all at once."""
    from sandbox.app.world.orders import SkipAhead

    def submit() -> list:
        worlds = app.lesson.worlds
        return [worlds[identity].runner.submit(SkipAhead(steps * i // len(identities)))
                for i, identity in enumerate(identities, 1)]

    for future in app.events.call(submit):
        future.result(timeout=SEATING_SECONDS)


def class_challenge(app: Any, round_steps: int, timeout: float = 600.0) -> dict[str, Any]:
    """A class challenge of ``round_steps`` steps for every seated student, to the end of the last
    reference run: the peak memory (PSS) of the server and every process under it while it runs, and the
    most processes, against before it started."""
    lesson = app.lesson
    lesson.round_steps = round_steps

    def tree() -> tuple[float, int]:
        pids = [os.getpid(), *descendants(os.getpid())]
        total = 0.0
        for pid in pids:
            with contextlib.suppress(OSError):
                total += memory_mb(pid)[1]
        return total, len(pids)

    def referenced() -> bool:  # every round scored, beside the paper's score or why there is none
        folders = [desk.panel.challenge for desk in list(lesson.desks.values())]
        return all(f.round is not None and f.round.score is not None
                   and (f.round.paper is not None or "no reference" in f.status.content) for f in folders)

    before, processes_before = tree()
    entrants = app.events.call(lesson.start_challenge)
    peak, most = before, processes_before
    started = time.monotonic()
    while not referenced():
        if time.monotonic() - started > timeout:
            raise UserError(f"the class challenge's references did not end within {timeout:.0f} s")
        total, count = tree()
        peak, most = max(peak, total), max(most, count)
        time.sleep(0.2)
    return {"students": len(entrants), "round_steps": round_steps, "seconds": round(time.monotonic() - started, 1),
            "pss_mb_before": round(before, 1), "pss_mb_peak": round(peak, 1),
            "pss_mb_peak_beyond_before": round(peak - before, 1),
            "processes_before": processes_before, "processes_peak": most,
            "reference_runs": getattr(getattr(lesson, "references", None), "runs", None)}


def run(config: Config, students: int, seconds: float = 20.0, *, teacher_browser: bool = False,
        fps: float = 30.0, steps_per_frame: int = 25, warm_up: float | None = None,
        challenge_steps: int | None = None, spread: int = 0) -> dict[str, Any]:
    """A class server with ``students`` students' pages (and the teacher's in Chromium if
    ``teacher_browser``), measured over ``seconds`` after the warm-up; ``fps`` and ``steps_per_frame``:
    the teacher's world's (the students' run at a class's pace); ``challenge_steps``: then a class
    challenge of that many steps, its memory to the end of its reference runs (:func:`class_challenge`);
    ``spread``: student i of K's world first run to step ``spread`` x i / K (:func:`spread_out`)."""
    from sandbox.app.lesson.classroom import Classroom
    from sandbox.app.web.access import Access
    from sandbox.commands.live_bench import _browser_page
    from sandbox.commands.serve import App, free_port
    from sandbox.processes import start_fork_server

    if students < 1 or not seconds > 0:
        raise UserError(f"--class needs at least one student and --seconds > 0 (got {students}, {seconds})")
    warm_up = WARM_UP if warm_up is None else warm_up
    start_fork_server()
    with contextlib.ExitStack() as stack:
        page = stack.enter_context(_browser_page()) if teacher_browser else None
        lesson = Classroom()
        access = Access.for_server("127.0.0.1", token=TOKEN)
        access.seats = lesson.seats
        app = App(config, port=free_port(), fps=fps, steps_per_frame=steps_per_frame, access=access,
                  lesson=lesson)
        wall = WallClock(app.lesson.wall)  # before start(): the refresh it schedules is the counted one
        desks = DeskFrames(app.lesson)
        app.start()
        stack.callback(app.stop)
        if page is not None:
            page.goto(app.url)
            page.wait_for_selector("canvas", timeout=60_000)
            page.evaluate(WALL_WATCH_JS)
        crowd_ = Crowd(app.port)
        stack.callback(crowd_.stop)
        started = time.monotonic()
        # The first student alone: the memory the first world costs; then the rest.
        first = crowd_.seat(1)
        wait_for(lambda: first[0] in app.lesson.desks and steps_now(app, first).get(first[0], 0) > 0,
                 SEATING_SECONDS, "the first student's world")
        time.sleep(min(warm_up, 3.0))
        pids = server_pids(app)
        first_memory = {name: rss_of(group) for name, group in pids.items()}
        first_pss = sum(pss_of(group) for group in pids.values())
        rest = Crowd(app.port)
        stack.callback(rest.stop)
        identities = first + (rest.seat(students - 1) if students > 1 else [])
        crowds = [crowd_, rest] if students > 1 else [crowd_]
        wait_for(lambda: all(i in app.lesson.desks for i in identities)
                 and all(s > 0 for s in steps_now(app, identities).values())
                 and len(steps_now(app, identities)) == students, SEATING_SECONDS, "every student's world")
        seated_after = time.monotonic() - started
        if spread > 0:
            spread_out(app, identities, spread)
        time.sleep(warm_up)
        result = measure(app, crowds, identities, wall, desks, seconds, page)
        pids = server_pids(app)
        memory = {name: rss_of(group) for name, group in pids.items()}
        pss = sum(pss_of(group) for group in pids.values())
        if challenge_steps:
            result["class_challenge"] = class_challenge(app, challenge_steps)
    result["spread_over_steps"] = spread
    beyond = students - 1
    total, first_total = sum(memory.values()), sum(first_memory.values())
    result.update({
        "students": students, "seconds": seconds, "seated_after_seconds": round(seated_after, 1),
        "robots": config.robots, "boxes": config.boxes, "teacher_browser": teacher_browser,
        "hosts": len(pids["hosts"]),
        "rss_mb": {name: round(value, 1) for name, value in memory.items()} | {"total": round(total, 1)},
        "first_world_rss_mb": {name: round(value, 1) for name, value in first_memory.items()}
        | {"total": round(first_total, 1)},
        "rss_per_student_world_beyond_first_mb": round((total - first_total) / beyond, 1) if beyond else None,
        "pss_mb_total": round(pss, 1), "first_world_pss_mb_total": round(first_pss, 1),
        "pss_per_student_world_beyond_first_mb": round((pss - first_pss) / beyond, 1) if beyond else None,
    })
    return result


def measure(app: Any, crowds: list[Crowd], identities: list[str], wall: WallClock, desks: DeskFrames,
            seconds: float, page: Any) -> dict[str, Any]:
    """Over ``seconds``: each world's steps, each page's bytes and messages, the wall, the server's CPU."""
    pids = server_pids(app)
    cpu0 = {name: sum(cpu_seconds(pid) for pid in group) for name, group in pids.items()}
    students_cpu0 = sum(cpu_seconds(c.process.pid) for c in crowds)
    steps0, published0, drawn0 = steps_now(app, identities), published_now(app, identities), dict(desks.drawn)
    counts0 = merged(crowds)
    if page is not None:
        page.evaluate("() => { window.__wallPictures = []; }")
    wall_from = len(wall.sent)
    browser = browser_pids() if page is not None else []
    browser_cpu0 = sum(cpu_seconds(pid) for pid in browser)
    t0 = time.perf_counter()
    windows = by_window(app, identities, seconds, t0)
    wall_seconds = time.perf_counter() - t0
    browser_cpu = sum(cpu_seconds(pid) for pid in browser) - browser_cpu0
    steps1, published1, drawn1 = steps_now(app, identities), published_now(app, identities), dict(desks.drawn)
    counts1, calm = merged(crowds, calm=True)
    cpu1 = {name: sum(cpu_seconds(pid) for pid in group) for name, group in server_pids(app).items()}
    students_cpu = sum(cpu_seconds(c.process.pid) for c in crowds) - students_cpu0
    browser_pictures = page.evaluate("() => window.__wallPictures") if page is not None else None
    step_rates = [(steps1.get(i, 0) - steps0.get(i, 0)) / wall_seconds for i in identities]
    frame_rates = [(counts1[i][1] - counts0[i][1]) / wall_seconds for i in identities]
    published_rates = [(published1.get(i, 0) - published0.get(i, 0)) / wall_seconds for i in identities]
    drawn_rates = [(drawn1.get(i, 0) - drawn0.get(i, 0)) / wall_seconds for i in identities]
    byte_rates = [(counts1[i][0] - counts0[i][0]) / wall_seconds for i in identities]
    sent = wall.sent[wall_from:]
    shown = [t / 1000.0 for t in browser_pictures] if browser_pictures is not None else None
    spent = {name: cpu1.get(name, 0.0) - cpu0.get(name, 0.0) for name in cpu0}
    steps_done = max(sum(step_rates) * wall_seconds, 1.0)
    frames_got = max(sum(frame_rates) * wall_seconds, 1.0)
    target = len(identities) * CLASS_FPS * CLASS_STEPS_PER_FRAME
    return {
        "real_time_factor": summary([rate * app.config.dt for rate in step_rates], 2),
        "steps_per_second": summary(step_rates, 1),
        "frames_per_second": summary(frame_rates, 1),  # websocket messages each page received
        # on their way: the frames each world sent the server, and those the server drew on its desk
        "world_frames_per_second": summary(published_rates, 1),
        "desk_frames_per_second": summary(drawn_rates, 1),
        "kb_per_second_per_student": {"max": round(max(byte_rates) / 1000, 1),
                                      "median": round(statistics.median(byte_rates) / 1000, 1)},
        "students_below_3x": sum(rate * app.config.dt < 2.95 for rate in step_rates),
        "students_below_8_fps": sum(rate < 8 for rate in frame_rates),
        "pages_calm": calm,
        "page_errors": sorted({counts1[i][2] for i in identities if counts1[i][2]}),
        "wall_refresh_seconds": {"median": _median(intervals(sent)), "max": _max(intervals(sent)),
                                 "pictures": len(sent)},
        "wall_refresh_seconds_in_browser": None if shown is None else {
            "median": _median(intervals(shown)), "max": _max(intervals(shown)), "pictures": len(shown)},
        "cpu_seconds": {name: round(cpu1.get(name, 0.0) - cpu0.get(name, 0.0), 2) for name in cpu0},
        "cpu_cores_used": round(sum(spent.values()) / wall_seconds, 2),
        # What a loaded machine changes little: the CPU a step costs in the hosts, a page's frame in the
        # server, and so the cores the class would need at its pace (the teacher's world as measured).
        "hosts_cpu_us_per_step": round(spent["hosts"] / steps_done * 1e6, 1),
        "server_cpu_ms_per_page_frame": round(spent["server"] / frames_got * 1e3, 2),
        "cores_needed_at_3x_and_10_fps": round((spent["hosts"] / steps_done * target + spent["server"]
                                                / frames_got * len(identities) * CLASS_FPS
                                                + spent["teachers_world"] / wall_seconds), 2),
        "students_process_cpu_cores": round(students_cpu / wall_seconds, 2),
        "browser_cpu_cores": round(browser_cpu / wall_seconds, 2) if page is not None else None,
        # each window of WINDOW seconds: the least and the median real-time factor of the worlds in it
        "real_time_factor_by_window": windows,
        "load_average": [round(x, 2) for x in os.getloadavg()],
        "cores": os.cpu_count(),
    }


def by_window(app: Any, identities: list[str], seconds: float, t0: float) -> list[tuple[float, float]]:
    """Sleep until ``seconds`` after ``t0``, reading each world's steps every :data:`WINDOW` seconds: each
    window's least and median real-time factor (a last window shorter than half of one is not told)."""
    windows, before, began = [], steps_now(app, identities), t0
    while (left := t0 + seconds - time.perf_counter()) > 0:
        time.sleep(min(WINDOW, left))
        now, steps = time.perf_counter(), steps_now(app, identities)
        if now - began >= WINDOW / 2:
            factors = [(steps.get(i, 0) - before.get(i, 0)) / (now - began) * app.config.dt for i in identities]
            windows.append((round(min(factors), 2), round(statistics.median(factors), 2)))
        before, began = steps, now
    return windows


def merged(crowds: list[Crowd], calm: bool = False) -> Any:
    rows, pages_calm = {}, 0
    for crowd_ in crowds:
        counts, said = crowd_.counts()
        rows.update(counts)
        pages_calm += said
    return (rows, pages_calm) if calm else rows


def summary(values: list[float], digits: int) -> dict[str, float]:
    return {"min": round(min(values), digits), "median": round(statistics.median(values), digits)}


def _median(values: list[float]) -> float | None:
    return round(statistics.median(values), 2) if values else None


def _max(values: list[float]) -> float | None:
    return round(max(values), 2) if values else None
