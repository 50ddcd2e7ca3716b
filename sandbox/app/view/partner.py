"""The compared world on the floor (compare mode, :mod:`sandbox.app.world.lockstep`): its runner,
held in the lockstep with the running one, and its nodes in the scene beside the running world's, with
the difference between the two. Runs on the app's event thread, but for :meth:`Comparison.begin`: a
worker (or, at start-up, the main thread) starts the new world's process and hands it over."""

from __future__ import annotations

import threading
from typing import Any, Callable

from sandbox.app.view.scene import DIFFERENCE_HEIGHT, Z_TOP, SceneView, compare_offset, difference_anchor
from sandbox.app.world.lockstep import Lockstep, side_name
from sandbox.app.world.snapshot import Snapshot
from sandbox.model.config import Config

def difference(left: Snapshot, right: Snapshot) -> str:
    """What compare mode shows between the worlds: which one has more boxes in the goal, by how much."""
    ahead = 100 * (right.sample.fraction_in_goal - left.sample.fraction_in_goal)
    if abs(ahead) < 0.05:
        return "level: the same share in goal"
    name = side_name(right if ahead > 0 else left)
    return f"{name} +{abs(ahead):.1f} points"


class Comparison:
    """The compared world: its runner (held in :class:`Lockstep` with the running one), and its nodes
    in the scene, right of the running world's arena or below it (:attr:`offset`).

    ``make_runner(config, shape=..., seed=..., playing=...)`` builds a runner like the app's (a
    process of its own); :meth:`draw` is called as the app draws a frame, on its event thread;
    ``on_layout(offset)`` hears where the second world lies (None: gone), to frame the pages."""

    ROOT = "/compare"

    def __init__(self, server: Any, lockstep: Lockstep, make_runner: Callable[..., Any],
                 on_layout: Callable[[float | None], None],
                 on_crash: Callable[[str], None] = lambda why: None, caption_over_construction: bool = False,
                 *, events: Any):
        """``on_crash(why)`` hears that the compared world's process died (compare mode then ends: a
        restarted world would start again from step 0, far behind the running one);
        ``caption_over_construction``: where its caption sits, as the running world's (a classroom's
        pages frame the construction areas); ``events``: the app's event queue, where the compared
        world is adopted and dropped."""
        self.caption_over_construction = caption_over_construction
        self.server, self.lockstep, self._make_runner = server, lockstep, make_runner
        self._on_layout, self._on_crash = on_layout, on_crash
        self._events = events
        self.view: Any = None
        self.label: str | None = None
        #: Whether the second world lies below the first (chosen by the page that asked for it).
        self.stacked = False
        self._difference: Any = None  # the label between the worlds
        self._drawn: int | None = None  # the compared world's frame last drawn
        # Shared by the threads that call begin() (the Compare folder's workers, the main thread at
        # start-up); nothing behind it: one new world's process starting at a time.
        self._starting = threading.Lock()

    @property
    def runner(self) -> Any:
        return self.lockstep.partner

    @property
    def offset(self) -> tuple[float, float]:
        """Where the compared world is drawn (m along the floor from the running one)."""
        return compare_offset(self.lockstep.main.latest.world_config, self.stacked)

    def covers(self, point: tuple[float, float]) -> bool:
        """Whether a floor point lies on the compared world's arena (a click there acts on nothing)."""
        if self.runner is None:
            return False
        size = self.lockstep.main.latest.world_config.arena_size
        (dx, dy), (x, y) = self.offset, point
        return bool(dx - 1.0 <= x <= dx + size + 1.0 and dy - 1.0 <= y <= dy + size + 1.0)

    def begin(self, config: Config, shape: Any, label: str, stacked: bool = False) -> None:
        """Compare with a world of ``config`` and ``shape`` from the running world's seed: both start
        again from step 0, playing if the running one was; ``stacked``: the second world below the
        first (for the asking page's tall view) instead of right of it. Blocks while the new world's
        process starts (a second or two): call it off the event thread (the start happens here, the
        adoption on the event thread)."""
        with self._starting:
            seed = self.lockstep.main.latest.seed
            partner = self._make_runner(config, shape=shape, seed=seed, playing=False)
            try:
                partner.start()
                self._events.call(self._adopt, partner, label, stacked, timeout=60.0)
            except BaseException:
                partner.stop()
                raise

    def _adopt(self, partner: Any, label: str, stacked: bool = False) -> None:
        """Pair the started ``partner`` with the running world and draw it (on the event thread)."""
        self._end()
        self.stacked = stacked
        playing = self.lockstep.main.playing
        with self.server.atomic():
            view = SceneView(self.server.scene, partner.latest, root=self.ROOT, offset=self.offset,
                             caption_over_construction=self.caption_over_construction)
            view.set_compared(self.offset, partner.latest, second=True)
            x, y = difference_anchor(self.lockstep.main.latest.world_config, self.offset)
            self._difference = self.server.scene.add_label(
                "/compare_difference", difference(self.lockstep.main.latest, partner.latest), position=(x, y, Z_TOP),
                anchor="center-center", font_size_mode="scene", font_scene_height=DIFFERENCE_HEIGHT)
        self.view, self.label, self._drawn = view, label, partner.latest.frame
        if hasattr(partner, "on_crash"):  # a process of its own
            partner.on_crash(lambda why, partner=partner: self._crashed(partner, why))  # on the event queue
        self.lockstep.pair(partner)
        # Both from step 0 (held there while they are built), then playing if the running world was;
        # also if a world could not be rebuilt (its process died, say).
        self.lockstep.reset(None, on_done=lambda _: self.lockstep.set_playing(playing),
                            on_error=lambda _: self.lockstep.set_playing(playing))
        self._on_layout(self.offset)

    def end(self) -> None:
        """The running world goes on alone."""
        if self._end():
            self._on_layout(None)

    def _crashed(self, partner: Any, why: str) -> None:
        if partner is not self.runner:
            return
        self._on_crash(why)
        self.end()

    def _end(self) -> bool:
        partner = self.lockstep.unpair()
        view, self.view, self.label = self.view, None, None
        if view is not None:
            view.remove()
        if self._difference is not None:
            self._difference.remove()
            self._difference = None
        if partner is not None:
            partner.stop()
        return partner is not None

    def draw(self) -> None:
        """Draw the compared world's newest frame, if it has a new one: the app calls this as it draws
        the running world's, in the same batch, so that the page gets both in one picture (viser's
        page asks for a picture per batch: a batch for each world would ask for two)."""
        view, partner = self.view, self.runner
        if view is None or partner is None:
            return
        snap = partner.latest
        if snap.frame != self._drawn:
            self._drawn = snap.frame
            view.update(snap)
            text = difference(self.lockstep.main.latest, snap)
            if self._difference is not None and self._difference.text != text:
                self._difference.text = text
