"""The teacher's wall: the Class folder of the teacher's panel, every student's world at once.
Built on the main thread with the panel; refreshed on the app's event thread, once a second.

Each student's tile is a small picture of their floor (drawn with Pillow on the server,
:func:`sandbox.app.view.frames.render`, sent as a JPEG about once a second, only when their world moved),
their label, step and share in the goal, and two buttons: *Show on the projector* (the teacher's floor
shows that world, live) and *Send the scene* (to this student alone). Above the tiles: how they are
sorted, the scene to send (the teacher's world or a paper case) to everyone, and the class challenge
with its ranking. The folder is in the shared GUI, which a student's page is never sent
(:mod:`sandbox.app.web.gate`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import viser

from sandbox.app.panel.plain import plain
from sandbox.app.view.frames import render
from sandbox.app.view.scene import CONSTRUCTION_VIEW

#: Side of a tile's picture (pixels) and its JPEG quality: about 3-5 KB a picture.
THUMBNAIL = 160
JPEG_QUALITY = 70
SORTS = ("arrival", "name", "share in the goal", "step")


class Tile:
    """One student's tile on the wall."""

    def __init__(self, gui: Any, label: str, snap: Any, on_project: Any, on_send: Any):
        with gui.add_folder(label) as self.folder:
            self.picture = gui.add_image(_picture(snap), format="jpeg", jpeg_quality=JPEG_QUALITY)
            self.line = gui.add_markdown("")
            self.project = gui.add_button("Show on the projector", icon=viser.Icon.PRESENTATION)
            self.send = gui.add_button("Send the scene", icon=viser.Icon.SEND)
        self.project.on_click(lambda event: on_project())
        self.send.on_click(lambda event: on_send())
        self.drawn: tuple | None = None  # (world, step) of the picture shown

    def show(self, snap: Any, state: str) -> None:
        key = (snap.world_key, snap.step)
        if key != self.drawn:
            self.drawn = key
            self.picture.image = _picture(snap)
        share = 100.0 * float(snap.sample.fraction_in_goal)
        text = f"step {snap.step:,} · **{share:.0f} %** in the goal · {plain(state)}"
        if self.line.content != text:
            self.line.content = text


class Wall:
    """The Class folder (see the module docstring) for ``classroom``'s seats; ``scenes``: the names of
    the scenes the teacher may send."""

    def __init__(self, gui: Any, classroom: Any, scenes: tuple[str, ...]):
        self.gui, self.classroom = gui, classroom
        self.tiles: dict[str, Tile] = {}
        with gui.add_folder("Class", order=-1.0) as self.folder:
            self.link = gui.add_markdown(self._link_text(0))
            self.sort = gui.add_dropdown("Sort by", SORTS, initial_value=SORTS[0])
            self.scene = gui.add_dropdown("Scene to send", scenes, initial_value=scenes[0],
                                          hint="A paper case over your settings, or your world as it is now")
            self.send_all = gui.add_button("Send to everyone", icon=viser.Icon.USERS)
            self.challenge = gui.add_button("Start a class challenge", icon=viser.Icon.FLAG,
                                            hint="The same round for every student: the paper's seed, the "
                                                 "same steps; their scores ranked here")
            self.ranking = gui.add_markdown("")
            self.projector = gui.add_markdown("On the projector: **your world**")
            self.back = gui.add_button("Back to my world", icon=viser.Icon.ARROW_BACK, visible=False)
            self.students = gui.add_folder("Students")  # the tiles, sorted within
        self.sort.on_update(lambda event: self.refresh())
        self.send_all.on_click(lambda event: self._send(None, event.client))
        self.challenge.on_click(lambda event: self._challenge(event.client))
        self.back.on_click(lambda event: classroom.project(None))

    # ------------------------------------------------------------ refresh
    def refresh(self) -> None:
        """Every tile afresh (its picture only when its world moved), in the order chosen."""
        classroom = self.classroom
        seats = [seat for seat in classroom.seats.all() if seat.identity in classroom.worlds]
        with self.students:
            for seat in seats:
                if seat.identity not in self.tiles:
                    identity = seat.identity
                    self.tiles[identity] = Tile(
                        self.gui, seat.label, classroom.worlds[identity].runner.latest,
                        on_project=lambda identity=identity: classroom.project(identity),
                        on_send=lambda identity=identity: self._send([identity], None))
        snaps = {seat.identity: classroom.worlds[seat.identity].runner.latest for seat in seats}
        for seat in seats:
            page = "page open" if seat.identity in classroom.page_of else "page closed"
            self.tiles[seat.identity].show(snaps[seat.identity], page)
        for rank, seat in enumerate(sort_seats(seats, snaps, self.sort.value)):
            tile = self.tiles[seat.identity]
            if tile.folder.order != float(rank):
                tile.folder.order = float(rank)
        self.link.content = self._link_text(len(seats))
        projected = classroom.seats.get(classroom.projected) if classroom.projected else None
        self.projector.content = f"On the projector: **{plain(projected.label) if projected else 'your world'}**"
        self.back.visible = projected is not None
        if classroom.entrants:
            self.ranking.content = ranking_text(classroom.challenge_results())

    def _link_text(self, count: int) -> str:
        link = self.classroom.students_link(self.classroom.app.url)
        noun = "student" if count == 1 else "students"
        return f"Students open **{plain(link)}**: each gets a world of their own. {count:,} {noun} so far."

    # ------------------------------------------------------------ actions
    def _send(self, identities: list[str] | None, client: Any) -> None:
        name = str(self.scene.value)
        scene = self.classroom.scene_named(name)
        sent = self.classroom.send(scene, identities)
        if client is not None:
            client.add_notification("Scene sent", f"{name} to {len(sent)} student"
                                    f"{'' if len(sent) == 1 else 's'}.", color="blue", auto_close_seconds=5.0)

    def _challenge(self, client: Any) -> None:
        entrants = self.classroom.start_challenge()
        self.ranking.content = ranking_text(self.classroom.challenge_results()) if entrants else \
            "No student has a page open: nobody to play."


def sort_seats(seats: list, snaps: dict, how: str) -> list:
    """The seats in the order the teacher chose: arrival, name, share in the goal (most first), step."""
    if how == "name":
        return sorted(seats, key=lambda seat: seat.label.lower())
    if how == "share in the goal":
        return sorted(seats, key=lambda seat: (-float(snaps[seat.identity].sample.fraction_in_goal), seat.number))
    if how == "step":
        return sorted(seats, key=lambda seat: (-int(snaps[seat.identity].step), seat.number))
    return sorted(seats, key=lambda seat: seat.number)


def ranking_text(rows: list) -> str:
    """The class challenge's ranking, one line a student, best first."""
    lines = ["**Class challenge**"]
    for place, (label, score, doing) in enumerate(rows, 1):
        if score is None:
            lines.append(f"- {plain(label)}: {plain(doing)}")
        else:
            noun = "box" if abs(score.brought) == 1 else "boxes"
            lines.append(f"{place:d}. **{plain(label)}**: {score.brought:,} {noun} brought in "
                         f"({100 * score.share:.0f} %)")
    return "\n".join(lines)


def _picture(snap: Any) -> np.ndarray:
    """The construction area (where the boxes are built) and a margin, :data:`THUMBNAIL` pixels a side."""
    cfg = snap.world_config
    side = min(cfg.arena_size, cfg.construction_size * CONSTRUCTION_VIEW)
    whole = int(round(THUMBNAIL * cfg.arena_size / side))
    k = whole / cfg.arena_size
    left = int(round((cfg.centre - side / 2) * k))
    top = int(round(whole - (cfg.centre + side / 2) * k))
    left, top = max(0, min(left, whole - THUMBNAIL)), max(0, min(top, whole - THUMBNAIL))
    return np.asarray(render(snap, whole).crop((left, top, left + THUMBNAIL, top + THUMBNAIL)))
