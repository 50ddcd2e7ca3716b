"""The top-down scene: one viser node per kind of thing, updated from snapshots.
Runs on the app's event thread (the main thread builds it before the queue opens).

Layout (z up, arena on z = 0, camera above looking down):

- ``/arena/lights``   the 64 x 64 light grid, every light off, as one PNG texture (sent once)
- ``/arena/lit``      the lights that are on: one square point per light, in its colour
- ``/arena/field``    the sensed luminosity as a heat map (toggle)
- ``/arena/walls``, ``/arena/box_wall``   outer wall and the box-only wall
- ``/goal``, ``/light_outline``   goal outline and current light outline
- ``/swarm/robots``, ``/swarm/headings``   point clouds
- ``/swarm/boxes/*``  the boxes as hexagons, in chunks (:mod:`.hexagons`)
- ``/inspect/*``   each viewer's followed robot, in that viewer's own scene (:mod:`.panel.inspector`);
  the shape being drawn is :mod:`.draw_view`'s ``/draw/*``
- ``/caption``   what is running: case, strategies, step (also in recordings)

One frame is one instant: the lit lights travel with the bodies, outline and
caption in the same batch of messages, and the page applies a batch in one
go. (They were a PNG texture, which the page decodes asynchronously and
shows later than the points: the lit band trailed the robots by 2-5 cells.)

Every viewer receives every update, so the moving parts are sent compactly
(see :class:`CompactSender`): half-precision points relative to the arena's
centre (1.6 cm steps at the walls, under a pixel when the whole arena is in
view), and only what changed since the last frame.

Works on any viser scene API (the live server, or a headless server that is
only being recorded).

Runs on the app's event thread (or on the one thread of ``phototaxis
record``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sandbox.app.view import palette as pal
from sandbox.app.view.hexagons import Hexagons
from sandbox.app.world.snapshot import PAPER_PROGRAM, Snapshot, caption
from sandbox.model.config import Config

Z_FIELD, Z_LIGHTS, Z_LIT, Z_BOXES, Z_ROBOTS, Z_MARKS, Z_LINES, Z_TOP = -0.01, 0.0, 0.01, 0.02, 0.04, 0.05, 0.08, 0.12
Z_LEGEND = 0.10  # the presenter's legend: over the bodies and lines, under the caption and the followed robot's ring


#: The construction view shows this many times the construction area's side: the area, the pile and
#: the band's last sweeps over it (the action of a class demo; the arena is 4x wider and mostly empty).
CONSTRUCTION_VIEW = 1.4


#: A classroom's caption (two lines over the construction area): letters this high (m). The presenter
#: layout at 1024 x 768 frames the 16 m construction area about 480 px high: 30 px a metre, 25 px letters.
CLASSROOM_CAPTION_HEIGHT = 0.85

#: Floor (m) between the running world's arena and compare mode's second one, to its right.
COMPARE_GAP = 6.0
#: The narrowest view the far plane allows for: a phone upright.
PHONE_ASPECT_NARROWEST = 0.4

#: Views narrower than this (width / height) are framed for a phone (see :func:`top_down_camera`):
#: a phone upright is 0.45-0.6; a desktop window's canvas beside the docked panel is rarely below 0.75.
PHONE_ASPECT = 0.75


def top_down_camera(config: Config, aspect: float = 1.4, fov_deg: float = 50.0, *, whole: bool = True,
                    also: tuple[float, float, float, float] | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera position, look-at point and vertical field of view (radians) that
    frame the whole arena (or, ``whole`` False, the construction area) from
    straight above (tilted a hair so orbiting works), in a view ``aspect``
    (width / height) wide: high enough for its height and, in a narrow view,
    for its width. A view much taller than wide (narrower than :data:`PHONE_ASPECT`: a phone,
    where viser lays its panel over the lower half of the page) has the framed square at its top,
    not in its middle. (The server learns only the canvas's shape, not whether the panel covers
    it: a desktop window that narrow gets the same framing, whole but high.) ``also``: a floor box
    (left, right, bottom, top) framed too (a person's lamp). Compare mode's two worlds: :func:`compare_camera`."""
    if whole:
        c, half = config.arena_size / 2.0, config.arena_size * 0.56  # arena plus a margin
    else:
        c, half = config.centre, config.construction_size * CONSTRUCTION_VIEW / 2.0
    box = (c - half, c + half, c - half, c + half)
    return camera_over(box if also is None else union(box, also), aspect, fov_deg, top_on_phone=True)


def camera_over(box: tuple[float, float, float, float], aspect: float, fov_deg: float = 50.0, *,
                top_on_phone: bool = False) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera position, look-at point and field of view that frame the floor rectangle ``box``
    (left, right, bottom, top) in a view ``aspect`` wide, as large as it fits; ``top_on_phone``: in a
    phone's view the rectangle sits at the view's top (see :func:`top_down_camera`)."""
    x0, x1, y0, y1 = box
    fov = np.radians(fov_deg)
    aspect = max(aspect, 0.1)
    half_height = max((y1 - y0) / 2.0, (x1 - x0) / 2.0 / aspect)
    height = half_height / np.tan(fov / 2.0)
    cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
    if top_on_phone and aspect < PHONE_ASPECT:
        cy = y1 - half_height  # the rectangle's top edge at the view's top edge
    return np.array([cx, cy - 1e-3 * height, height]), np.array([cx, cy, 0.0]), float(fov)


def frame_arena(client: Any, config: Config, whole: bool = True, also: tuple | None = None) -> None:
    """Point one viewer's camera at the whole arena (or the construction area; and the floor box ``also``),
    for its own window's shape."""
    aspect = float(getattr(client.camera, "aspect", 0.0) or 1.4)
    aim_camera(client, *top_down_camera(config, aspect, whole=whole, also=also))


def aim_camera(client: Any, position: np.ndarray, look_at: np.ndarray, fov: float) -> None:
    """Move one viewer's camera, in one batch."""
    with client.atomic():
        client.camera.fov = fov
        client.camera.position = tuple(position)
        client.camera.look_at = tuple(look_at)


def _geometry_key(cfg: Config, n: int, m: int) -> tuple:
    """What the static scene depends on: a change rebuilds the nodes (a gain does not)."""
    return (cfg.arena_size, cfg.construction_size, cfg.centre, cfg.light_pitch, cfg.robot_radius, cfg.box_circumradius,
            n, m)


#: Width (m) of the legend drawn on the floor beside the arena's left wall in recordings: a replay has
#: no panel, so it carries its legend in the scene.
FLOOR_LEGEND_WIDTH = 16.0


def add_floor_legend(scene: Any, config: Config, presenter: bool = False, box: tuple | None = None) -> Any:
    """The legend as a picture on the floor: left of the arena, its top level with the arena's top wall
    (in view beside the arena in any window wider than 1.3 : 1, as a replay's usually is); or, for the
    presenter layout, left of the construction area (:func:`presenter_legend_box`), or in ``box``
    (left, right, bottom, top: compare mode's, :func:`compare_legend_box`)."""
    from sandbox.app.view.legend import legend_picture

    picture = np.ascontiguousarray(legend_picture()[::-1])  # an image's first row lies at the floor's -y side
    if presenter:
        left, right, bottom, top = box or presenter_legend_box(config, picture.shape[0] / picture.shape[1])
        # Over the robots that roam there: on a projector the legend must stay readable.
        width, height, position = right - left, top - bottom, ((left + right) / 2.0, (bottom + top) / 2.0, Z_LEGEND)
    else:
        width = FLOOR_LEGEND_WIDTH
        height = width * picture.shape[0] / picture.shape[1]
        position = (-1.0 - width / 2.0, config.arena_size - height / 2.0, Z_LIGHTS)
    return scene.add_image("/legend", picture, width, height, format="png", position=position,
                           cast_shadow=False, receive_shadow=False)


#: The presenter layout's legend: its width as a share of the construction area's side, and its gap
#: (m) to the construction wall.
PRESENTER_LEGEND_SHARE, PRESENTER_LEGEND_GAP = 0.6, 1.0


def presenter_legend_box(config: Config, height_per_width: float) -> tuple[float, float, float, float]:
    """(left, right, bottom, top) of the presenter layout's floor legend: left of the construction
    wall, its top level with the wall's top, large enough to read on a projector."""
    half = config.construction_size / 2.0
    width = PRESENTER_LEGEND_SHARE * config.construction_size
    right = config.centre - half - PRESENTER_LEGEND_GAP
    top = config.centre + half
    return right - width, right, top - width * height_per_width, top


def presenter_camera(config: Config, aspect: float, height_per_width: float, fov_deg: float = 50.0,
                     also: tuple | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera position, look-at point and field of view framing the construction area and the
    presenter's legend beside it (and the floor box ``also``), as large as the view's ``aspect`` allows
    (a margin all round). Compare mode's two worlds: :func:`compare_camera`."""
    left, _, bottom, _ = presenter_legend_box(config, height_per_width)
    half = config.construction_size * CONSTRUCTION_VIEW / 2.0
    margin = half - config.construction_size / 2.0
    box = (left - margin, config.centre + half, min(bottom, config.centre - config.construction_size / 2.0) - margin,
           config.centre + half)
    return camera_over(box if also is None else union(box, also), aspect, fov_deg)


# ------------------------------------------------------- compare mode's layout (issue 41, item 1)
#: Compare mode's readouts: each world's share in the goal under its construction area, and the
#: difference between the two in the floor's gap between the worlds. Their font is sized in metres
#: (viser's scene-sized labels), so that they grow and shrink with the framing and never run into
#: each other or the other world, however small the page: at a projector's compare framing (1024 px,
#: about 10 px a metre) a readout is about 35 px high. The captions stay sized in screen pixels (a
#: line of text must stay readable on a phone that frames both arenas).
READOUT_HEIGHT, DIFFERENCE_HEIGHT = 3.2, 2.7
#: Side by side, each world's caption is sized in metres too: letters this high, 26 px at a projector's
#: compare framing (1024 x 768, the panel folded: about 10.4 px a metre), read from the back of a room
#: (issue 56, item 10: they were 13 px); each stays over its own world, however small the page (its
#: longest line, :data:`CAPTION_CHARS`, fits between the construction wall and the arena's: 2.5 m at most).
COMPARE_CAPTION_HEIGHT = 2.5
#: A label's block is this many times its font's height (the line's height and viser's padding).
LABEL_BLOCK = 1.45
#: Gap (m) between a construction wall and the label above or below it.
LABEL_GAP = 0.4
#: The presenter's legend in compare mode: at most this wide (m); side by side, under both arenas, at most
#: :data:`SIDE_LEGEND_WIDTH` (a wider one made the framing taller than the view: everything smaller).
COMPARE_LEGEND_WIDTH, SIDE_LEGEND_WIDTH = 30.0, 18.0

Box = tuple[float, float, float, float]  # (left, right, bottom, top) on the floor


def compare_offset(config: Config, stacked: bool = False) -> tuple[float, float]:
    """Where compare mode's second world lies (m, along the floor): right of the running world's
    arena, or below it (``stacked``: for a view taller than wide)."""
    step = config.arena_size + COMPARE_GAP
    return (0.0, -step) if stacked else (step, 0.0)


def is_stacked(offset: tuple[float, float]) -> bool:
    return abs(offset[1]) > abs(offset[0])


def caption_anchor(offset: tuple[float, float], second: bool) -> str:
    """Where a compared world's caption hangs: side by side, under the arena's bottom wall (off the
    floor the lit band sweeps), the first world's from below the construction wall's left corner
    growing right, the second's from below its right corner growing left, each towards the gap between
    the worlds and sized in metres (:data:`COMPARE_CAPTION_HEIGHT`), so that each stays under its own
    world and out of the view's top left, where viser stacks its notices (they were screen-sized over
    the walls, grown from both left corners: over the lit band, and beside the open panel the first ran
    over the second world); stacked, from the wall's top middle in screen pixels (a tall view is
    narrow: a caption grown from a corner ran off it). The framing makes room for them
    (:func:`compare_camera`)."""
    if is_stacked(offset):
        return "bottom-center"
    return "top-right" if second else "top-left"


def caption_anchor_point(config: Config, anchor: str) -> tuple[float, float]:
    """The point on the floor a compared world's caption hangs from (its ``anchor``, :func:`caption_anchor`)."""
    low, high, _, top = construction_box(config)
    if anchor == "bottom-center":
        return (low + high) / 2.0, top + 0.3
    return (low if anchor == "top-left" else high), -LABEL_GAP  # under the arena's bottom wall


def union(*boxes: Box) -> Box:
    return (min(b[0] for b in boxes), max(b[1] for b in boxes), min(b[2] for b in boxes), max(b[3] for b in boxes))


def shifted(box: Box, offset: tuple[float, float]) -> Box:
    return (box[0] + offset[0], box[1] + offset[0], box[2] + offset[1], box[3] + offset[1])


def construction_box(config: Config, share: float = 1.0) -> Box:
    """The construction area (times ``share`` its side, about its centre)."""
    half = config.construction_size * share / 2.0
    return (config.centre - half, config.centre + half, config.centre - half, config.centre + half)


def readout_anchor(config: Config) -> tuple[float, float]:
    """Where a world's readout hangs from (its top's centre), under its construction wall."""
    return config.centre, config.centre - config.construction_size / 2.0 - LABEL_GAP


def readout_box(config: Config, text_chars: int = 14) -> Box:
    """The floor a world's readout covers, about (its width estimated from a character's, 0.5 em)."""
    x, top = readout_anchor(config)
    half = 0.5 * READOUT_HEIGHT * text_chars / 2.0  # a figure's width: 0.47 em measured ("2.5 % in goal")
    return (x - half, x + half, top - LABEL_BLOCK * READOUT_HEIGHT, top)


def difference_anchor(config: Config, offset: tuple[float, float]) -> tuple[float, float]:
    """The difference's centre: the middle of the floor between the two worlds' construction areas;
    side by side, under the gap between the arenas, below their bottom walls and the captions (it is
    wider than the gap: between the worlds it lay over both arenas' walls and floor, and in the view's
    top left, where viser stacks its notices)."""
    if is_stacked(offset):
        return config.centre + offset[0] / 2.0, config.centre + offset[1] / 2.0
    captions = CAPTION_LINES_EM * COMPARE_CAPTION_HEIGHT  # their block, under the arenas' bottom walls
    return config.centre + offset[0] / 2.0, -2 * LABEL_GAP - captions - LABEL_BLOCK * DIFFERENCE_HEIGHT / 2.0


def difference_box(config: Config, offset: tuple[float, float], text_chars: int = 26) -> Box:
    x, y = difference_anchor(config, offset)
    half_w, half_h = 0.6 * DIFFERENCE_HEIGHT * text_chars / 2.0, LABEL_BLOCK * DIFFERENCE_HEIGHT / 2.0
    return (x - half_w, x + half_w, y - half_h, y + half_h)


def compare_legend_box(config: Config, offset: tuple[float, float], height_per_width: float) -> Box:
    """The presenter's legend in compare mode: side by side, below both arenas and the difference, under
    the gap between them (between the worlds it covered the first one's lit band: issue 56, item 10), at most
    :data:`COMPARE_LEGEND_WIDTH` wide and no wider than the framing's height leaves room for; stacked,
    left of both construction areas, level with the gap between them (a phone's or a tall screen's
    width has room there, not between)."""
    view = construction_box(config, CONSTRUCTION_VIEW)
    gx, gy = difference_anchor(config, offset)
    if is_stacked(offset):
        width = COMPARE_LEGEND_WIDTH
        right = min(view[0], difference_box(config, offset)[0]) - LABEL_GAP
        height = width * height_per_width
        return (right - width, right, gy - height / 2.0, gy + height / 2.0)
    gap = (view[0] + offset[0]) - view[1]  # between the two construction views
    width = max(4.0, min(SIDE_LEGEND_WIDTH, gap - 4.0))
    top = difference_box(config, offset)[2] - LABEL_GAP  # under the difference, under the arenas' bottom walls
    return (gx - width / 2.0, gx + width / 2.0, top - width * height_per_width, top)


def compare_floor_box(config: Config, offset: tuple[float, float], whole: bool,
                      legend_height_per_width: float | None = None) -> Box:
    """The floor compare mode frames: both arenas (``whole``), or both construction areas with their
    captions' walls, readouts and the difference between them (and the presenter's legend, given its
    picture's height per width)."""
    if whole:
        c, half = config.arena_size / 2.0, config.arena_size * 0.56
        one = (c - half, c + half, c - half, c + half)
        return union(one, shifted(one, offset), difference_box(config, offset))
    one = union(construction_box(config, CONSTRUCTION_VIEW), readout_box(config))
    parts = [one, shifted(one, offset), difference_box(config, offset)]
    if legend_height_per_width is not None:
        parts.append(compare_legend_box(config, offset, legend_height_per_width))
    return union(*parts)


#: A compare caption's longest line, in characters, as framed for ("step 14,700 | contracting, cycle 12": 35),
#: and a character's width in ems (viser's sans-serif: "step 5,425 | contracting, cycle 0" measured 0.44).
CAPTION_CHARS, CHAR_EM = 35, 0.45
#: A compare caption's two lines and viser's padding, in ems.
CAPTION_LINES_EM = 2.6


def caption_box(config: Config, offset: tuple[float, float], second: bool, view_height: float,
                chars: int = CAPTION_CHARS) -> Box:
    """The floor a compare caption covers: two lines of text (a character :data:`CHAR_EM` wide, a line
    1.2 em, and viser's padding); side by side sized in metres (:data:`COMPARE_CAPTION_HEIGHT`), stacked
    in screen pixels in a view ``view_height`` metres high (12 px x 1.2 an em in an 800 px high view,
    scaled with the view)."""
    em = 12 * 1.2 / 800 * view_height if is_stacked(offset) else COMPARE_CAPTION_HEIGHT
    width, height = CHAR_EM * em * chars, CAPTION_LINES_EM * em
    anchor = caption_anchor(offset, second)
    x, y = caption_anchor_point(config, anchor)
    left = {"top-left": x, "bottom-center": x - width / 2.0}.get(anchor, x - width)
    box = (left, left + width, y, y + height) if anchor.startswith("bottom") else (left, left + width, y - height, y)
    return shifted(box, offset) if second else box


def compare_camera(config: Config, aspect: float, offset: tuple[float, float], *, whole: bool,
                   legend_height_per_width: float | None = None,
                   fov_deg: float = 50.0) -> tuple[np.ndarray, np.ndarray, float]:
    """Camera position, look-at point and field of view that frame both of compare mode's worlds
    (:func:`compare_floor_box`) in a view ``aspect`` wide, with their captions: sized in screen pixels,
    they cover more floor the more floor is in view (so the box grows twice, with the view it makes)."""
    floor = compare_floor_box(config, offset, whole, legend_height_per_width)
    box = floor
    for _ in range(40):  # converges: a caption is narrower than the view it is framed for
        height = max(box[3] - box[2], (box[1] - box[0]) / max(aspect, 0.1))
        box = union(floor, caption_box(config, offset, False, height), caption_box(config, offset, True, height))
    pad = 0.01 * max(box[1] - box[0], box[3] - box[2])  # and what the last round would still add
    return camera_over((box[0] - pad, box[1] + pad, box[2] - pad, box[3] + pad), aspect, fov_deg, top_on_phone=True)


def configure_scene(server: Any, config: Config, whole: bool = True) -> None:
    """z up, flat true colours (no shading lights, an even ambient light) and a
    top-down initial camera framing the arena. Also recorded into replays."""
    server.scene.set_up_direction("+z")
    server.scene.world_axes.visible = False
    server.scene.configure_default_lights(False)
    server.scene.configure_environment_map(None)
    server.scene.add_light_ambient("/ambient", intensity=3.14159)
    position, look_at, fov = top_down_camera(config, whole=whole)
    server.initial_camera.position = tuple(position)
    server.initial_camera.look_at = tuple(look_at)
    server.initial_camera.fov = fov
    # Far enough for the whole arena's framing even when a page starts on the construction area
    # (the View buttons switch; a nearer far plane left the floor unseen from above the arena), and for
    # compare mode's two arenas on a phone (from higher still: at 4x the first, the floor was beyond it).
    server.initial_camera.far = float(max(top_down_camera(config)[0][2] * 4, *(
        1.5 * compare_camera(config, aspect, compare_offset(config, stacked), whole=True)[0][2]
        for aspect in (PHONE_ASPECT_NARROWEST, 3.0) for stacked in (False, True))))


#: Texture size of the light grid (pixels per side, about): crisp cells with seams at any usual zoom.
LIGHT_TEXTURE_PIXELS = 512
#: Moving points are sent on a grid this fine (m): exact in half precision up to 32 m from the
#: centre, a fifth of a pixel with the whole arena in view, and coarse enough that sub-centimetre
#: jitter of resting boxes sends nothing.
POINT_GRID = 1.0 / 64.0
def readout(snap: Snapshot) -> str:
    """A world's share of the boxes in the goal, as compare mode shows it large."""
    return f"{100 * snap.sample.fraction_in_goal:.1f} % in goal"


class CompactSender:
    """Assigns a handle's property only when its value changed since it was
    last sent: each assignment is a message to every viewer."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, str], Any] = {}

    def send(self, handle: Any, prop: str, value: Any) -> bool:
        if not self.remember(handle, prop, value):
            return False
        setattr(handle, prop, value)
        return True

    def remember(self, handle: Any, prop: str, value: Any) -> bool:
        """Note that the viewers have ``value`` (a node was just made with it); False if they had it."""
        key = (id(handle), prop)
        fingerprint = value.tobytes() if isinstance(value, np.ndarray) else value
        if self._last.get(key) == fingerprint:
            return False
        self._last[key] = fingerprint
        return True


class SceneView:
    """Draws snapshots into a viser scene."""

    def __init__(self, scene: Any, snapshot: Snapshot, *, show_field: bool = False,
                 caption_over_construction: bool = False, root: str = "", offset: tuple[float, float] = (0.0, 0.0)):
        """``root`` and ``offset``: a second world (compare mode) is drawn under its own node, moved
        ``offset`` metres along the floor."""
        self.scene = scene
        self.root, self.offset = root, (float(offset[0]), float(offset[1]))
        self.show_field = show_field
        #: Where the caption sits: above the arena's top-right corner, or (classroom, whose pages frame
        #: the construction area) above the construction wall's, where both framings show it.
        self.caption_over_construction = caption_over_construction
        self._own_caption_place = caption_over_construction
        #: Whose world it shows, before the caption (class mode's projector: a student's label), or None.
        self.label: str | None = None
        #: Compare mode: the caption's anchor over the construction wall (it is in two lines), the share
        #: in the goal under the wall in large figures (:meth:`set_compared`); None: not compared.
        self.compared: str | None = None
        self._built_for: tuple | None = None
        self._lights_key: tuple | None = None
        self._field_key: tuple | None = None
        self._goal_key: int | None = None
        self._outline_shape: tuple | None = None
        self._outline_bytes: bytes | None = None
        self._n: tuple[int, int] | None = None
        self.handles: dict[str, Any] = {}
        self.hexagons: Hexagons | None = None
        self.update(snapshot)

    # ------------------------------------------------------------ static
    def _build(self, snap: Snapshot) -> None:
        cfg = snap.world_config
        s, c = cfg.arena_size, cfg.arena_size / 2.0
        sc = self.scene
        self._remove_nodes()
        self._sent = CompactSender()
        if self.root:
            self.handles["root"] = sc.add_frame(self.root, show_axes=False, position=(*self.offset, 0.0))
        r0 = self.root
        placeholder = np.zeros((8, 8, 3), np.uint8)
        # The grid of lights, all off, as one PNG texture sent once; the lit ones are square points over
        # it, sent with the bodies (a PNG is decoded later than the points it came with).
        self.handles["lights"] = sc.add_image(
            f"{r0}/arena/lights", self._light_picture(cfg), s, s, format="png", position=(c, c, Z_LIGHTS),
            cast_shadow=False, receive_shadow=False, visible=not self.show_field)
        self.handles["lit"] = sc.add_point_cloud(
            f"{r0}/arena/lit", self._points(1), np.zeros((1, 3), np.uint8), point_size=self._lit_size(cfg),
            point_shape="square", point_shading="flat", position=(c, c, Z_LIT), visible=False)
        self.handles["field"] = sc.add_image(
            f"{r0}/arena/field", placeholder, s, s, format="png", position=(c, c, Z_FIELD),
            cast_shadow=False, receive_shadow=False, visible=self.show_field)
        self.handles["walls"] = sc.add_line_segments(
            f"{r0}/arena/walls", pal.closed_segments(pal.square(c, c), Z_LINES), pal.ARENA_WALL, thickness=0.25)
        self.handles["box_wall"] = sc.add_line_segments(
            f"{r0}/arena/box_wall", pal.closed_segments(pal.square(cfg.centre, cfg.construction_size / 2.0), Z_LINES),
            pal.BOX_WALL, thickness=0.1)
        n, m = len(snap.robot_positions), len(snap.box_positions)
        # A robot is a round point, its heading a dark dot near its front rim (viser draws a point of
        # size d as wide as an object 2d wide, so sizes are radii); a box a hexagon (sandbox.app.view.hexagons).
        r = cfg.robot_radius
        self.handles["robots"] = sc.add_point_cloud(
            f"{r0}/swarm/robots", self._points(max(n, 1)), np.zeros((max(n, 1), 3), np.uint8), point_size=r, point_shape="circle",
            point_shading="flat", position=(c, c, Z_ROBOTS), visible=n > 0)
        self.handles["headings"] = sc.add_point_cloud(
            f"{r0}/swarm/headings", self._points(max(n, 1)), pal.HEADING_MARK, point_size=0.3 * r,
            point_shape="circle", point_shading="flat", position=(c, c, Z_MARKS), visible=n > 0)
        self.hexagons = Hexagons(sc, f"{r0}/swarm/boxes", m, cfg.box_circumradius, (c, c, Z_BOXES))
        self.handles["caption"] = self._add_caption(snap)
        self.handles["readout"] = self._add_readout(snap)
        empty = np.zeros((1, 2, 3), np.float32)
        self.handles["goal"] = sc.add_line_segments(f"{r0}/goal", empty, pal.GOAL_LINE, thickness=0.18)
        self.handles["light_outline"] = sc.add_line_segments(f"{r0}/light_outline", empty, pal.LIGHT_LINE, thickness=0.08)
        self._built_for = _geometry_key(cfg, n, m)
        self._lights_key = self._field_key = self._goal_key = None
        self._outline_bytes = None
        self._n = (n, m)

    def _add_caption(self, snap: Snapshot) -> Any:
        """What runs, above the arena's top-right corner (viser stacks its notifications at the page's
        top left), or the construction wall's (:attr:`caption_over_construction`). In compare mode
        (:attr:`compared`) it sits directly above the construction wall, each world's over its own
        area, in two lines (:func:`caption_anchor`): a caption is sized in screen pixels, and two on one
        line ran into each other once the arenas were narrower than them."""
        cfg = snap.world_config
        if self.compared in ("top-left", "top-right"):  # side by side: sized in metres (caption_anchor)
            return self.scene.add_label(f"{self.root}/caption", self._caption(snap),
                                        position=(*caption_anchor_point(cfg, self.compared), Z_TOP),
                                        anchor=self.compared, font_size_mode="scene",
                                        font_scene_height=COMPARE_CAPTION_HEIGHT)
        if self.caption_over_construction or self.compared:
            low, high, gap = cfg.centre - cfg.construction_size / 2.0, cfg.centre + cfg.construction_size / 2.0, 0.3
        else:
            low, high, gap = 0.0, cfg.arena_size, 0.8
        if self.caption_over_construction and not self.compared:
            # A classroom's: two lines over the construction area in letters sized in metres, as large as
            # the presenter layout leaves room for (25 px at 1024 x 768: read from the back of a room),
            # and never wider than a phone's framing of the same area.
            return self.scene.add_label(f"{self.root}/caption", self._caption(snap),
                                        position=((low + high) / 2.0, high + gap, Z_TOP), anchor="bottom-center",
                                        font_size_mode="scene", font_scene_height=CLASSROOM_CAPTION_HEIGHT)
        anchor = self.compared or "bottom-right"
        position = ({"bottom-left": low, "bottom-center": (low + high) / 2.0}.get(anchor, high), high + gap)
        # Its size is in screen pixels: at 1.2 it still fits a phone's width (a larger one, for a
        # projector, would run off a phone that watches the same classroom).
        return self.scene.add_label(f"{self.root}/caption", self._caption(snap), position=(*position, Z_TOP),
                                    anchor=anchor, font_screen_scale=1.2)

    def _caption(self, snap: Snapshot) -> str:
        """The caption's text: one line, or in compare mode two (the case's name, then its step and what
        lights it; the share in the goal is the readout's, large)."""
        text = caption(snap) if self.label is None else f"{self.label}: {caption(snap)}"
        if self.caption_over_construction and not self.compared:  # a classroom's: case and step, then the rest
            name, step, *rest = text.split(" | ")
            return f"{name} | {step}\n" + " | ".join(rest)
        if not self.compared:
            return text
        name, *rest = text.split(" | ")
        return name + "\n" + " | ".join(rest[:-1])

    def _add_readout(self, snap: Snapshot) -> Any:
        """Compare mode's share in the goal, large, under the construction wall (hidden otherwise)."""
        x, y = readout_anchor(snap.world_config)
        return self.scene.add_label(f"{self.root}/readout", readout(snap), position=(x, y, Z_TOP),
                                    anchor="top-center", font_size_mode="scene", font_scene_height=READOUT_HEIGHT,
                                    visible=self.compared is not None)

    def set_compared(self, offset: tuple[float, float] | None, snap: Snapshot, second: bool = False) -> None:
        """Compare mode began, the second world at ``offset`` (this world is it: ``second``), or ended
        (None): the caption moves over the construction wall in two lines, and the readout shows, or back."""
        anchor = None if offset is None else caption_anchor(offset, second)
        if anchor == self.compared:
            return
        self.compared = anchor
        if "caption" in self.handles:
            self.handles["caption"].remove()
            self.handles["caption"] = self._add_caption(snap)
            self._sent.remember(self.handles["caption"], "text", self._caption(snap))
            self.handles["readout"].visible = anchor is not None

    def set_label(self, label: str | None, snap: Snapshot) -> None:
        """Show whose world it is (class mode's projector: a student's label before the caption, the caption
        over the construction area, which the presenter layout frames), or (None) its own again."""
        if label == self.label:
            return
        self.label = label
        self.caption_over_construction = self._own_caption_place or label is not None
        if "caption" in self.handles:
            self.handles["caption"].remove()
            self.handles["caption"] = self._add_caption(snap)
            self._sent.remember(self.handles["caption"], "text", self._caption(snap))

    def _remove_nodes(self) -> None:
        for h in [*([self.hexagons] if self.hexagons else []), *reversed(self.handles.values())]:  # the root last
            try:
                h.remove()
            except Exception:
                pass
        self.handles = {}
        self.hexagons = None

    def remove(self) -> None:
        """Take this world's nodes off the scene (compare mode ends)."""
        self._remove_nodes()
        self._built_for = None

    # ----------------------------------------------------------- dynamic
    def update(self, snap: Snapshot) -> None:
        cfg = snap.world_config
        n, m = len(snap.robot_positions), len(snap.box_positions)
        if self._built_for != _geometry_key(cfg, n, m):
            self._build(snap)
        h = self.handles
        if snap.lights_key != self._lights_key:
            self._show_lit(snap)
            self._lights_key = snap.lights_key
        if self.show_field and snap.field is not None and snap.lights_key != self._field_key:
            h["field"].image = pal.field_image(snap.field, top_first=False)
            self._field_key = snap.lights_key
        if snap.goal_key != self._goal_key:
            h["goal"].points = pal.closed_segments(snap.goal_outline, Z_LINES + 0.01)
            self._goal_key = snap.goal_key
        outline_bytes = snap.outline.tobytes()
        if outline_bytes != self._outline_bytes:
            h["light_outline"].points = pal.closed_segments(snap.outline, Z_LINES)
            self._outline_bytes = outline_bytes
        # The orange line is the paper's controller's outline: while a light program or a person's lamp
        # lights the floor, it is not what the lights follow.
        paper = snap.program == PAPER_PROGRAM
        if h["light_outline"].visible != paper:
            h["light_outline"].visible = paper
        centre = cfg.arena_size / 2.0
        send = self._sent.send
        if n:
            send(h["robots"], "points", self._points(n, snap.robot_positions - centre))
            send(h["robots"], "colors", pal.robot_colours(snap.robot_charges, cfg.capacity))
            front = 0.6 * cfg.robot_radius * np.stack([np.cos(snap.robot_headings),
                                                        np.sin(snap.robot_headings)], axis=1)
            send(h["headings"], "points", self._points(n, snap.robot_positions - centre + front))
        if m:
            self.hexagons.update(self._points(m, snap.box_positions - centre), snap.box_angles,
                                 pal.box_mesh_colours(snap.box_in_goal), np.full(2, cfg.centre - centre))
        send(h["caption"], "text", self._caption(snap))
        if self.compared:
            send(h["readout"], "text", readout(snap))

    def set_show_field(self, show: bool, snap: Snapshot) -> None:
        self.show_field = bool(show)
        if not show:
            self._field_key = None
        elif snap.field is not None and snap.lights_key != self._field_key:
            self.handles["field"].image = pal.field_image(snap.field, top_first=False)
            self._field_key = snap.lights_key
        self.handles["field"].visible = self.show_field
        self.handles["lights"].visible = not self.show_field
        self._show_lit(snap)

    def _show_lit(self, snap: Snapshot) -> None:
        """The lit lights as square points (none: the node hides; under the heat map too)."""
        cfg = snap.world_config
        centres, colours = pal.lit_cells(snap.intensities, cfg.light_pitch, max(cfg.light_intensity, 1e-9))
        h = self.handles["lit"]
        if len(centres):
            # Centred on the part of the cell that the texture's seam (its left and bottom pixel) leaves.
            seam = cfg.light_pitch / (2 * self._cell_pixels(cfg))
            h.points = self._points(len(centres), centres + seam - cfg.arena_size / 2.0)
            h.colors = colours
        visible = bool(len(centres)) and not self.show_field
        if h.visible != visible:
            h.visible = visible

    @staticmethod
    def _cell_pixels(cfg: Config) -> int:
        return max(2, LIGHT_TEXTURE_PIXELS // cfg.lights_per_side)

    @classmethod
    def _lit_size(cls, cfg: Config) -> float:
        """A lit light's square: the cell less the texture's seam, as a radius (points are sized by
        half their width)."""
        return 0.5 * cfg.light_pitch * (1.0 - 1.0 / cls._cell_pixels(cfg))

    @classmethod
    def _light_picture(cls, cfg: Config) -> np.ndarray:
        """The grid with every light off."""
        dark = np.zeros((cfg.lights_per_side,) * 2)
        return pal.light_grid_image(dark, cell_pixels=cls._cell_pixels(cfg), top_first=False)

    @staticmethod
    def _points(n: int, xy: np.ndarray | None = None) -> np.ndarray:
        """(n, 3) half-precision points on the node's plane, relative to the arena's centre,
        on a grid of POINT_GRID metres: a box that only trembles is not sent again."""
        out = np.zeros((n, 3), np.float16)
        if xy is not None:
            out[:, :2] = np.round(np.asarray(xy) / POINT_GRID) * POINT_GRID
        return out
