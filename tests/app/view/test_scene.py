"""What the scene sends to every viewer: only what changed, compactly."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sandbox.app.world.runner import Runner
from sandbox.app.world.orders import SetPlaying, StepOnce
from sandbox.app.view.scene import (LABEL_GAP, POINT_GRID, CompactSender, SceneView, compare_camera, compare_offset,
                                    top_down_camera)
from sandbox.app.world.snapshot import caption, case_name
from sandbox.model.config import Config


class FakeHandle:
    """Stands in for a viser handle: records every property assignment (one message each)."""

    def __init__(self, log: list, path: str, **props):
        object.__setattr__(self, "_log", log)
        object.__setattr__(self, "_path", path)
        for k, v in props.items():
            object.__setattr__(self, k, v)

    def __setattr__(self, name, value):
        self._log.append((self._path, name))
        object.__setattr__(self, name, value)

    def remove(self):
        pass


class FakeScene:
    def __init__(self):
        self.sent: list[tuple[str, str]] = []

    def __getattr__(self, name):
        if not name.startswith("add_"):
            raise AttributeError(name)

        def add(path, *args, **kwargs):
            props = {"visible": kwargs.get("visible", True), "points": args[0] if args else None}
            return FakeHandle(self.sent, path, **props)
        return add


@pytest.fixture(scope="module")
def snapshot():
    r = Runner(Config(robots=12, boxes=20, update_every=10, hold_steps=3), shape=None, fps=60, steps_per_frame=2)
    r.start()
    try:
        r.submit(SetPlaying(False))
        r.ask(StepOnce(5))
        snap = r.latest
        while snap.step == 0:
            snap = r.latest
        return snap
    finally:
        r.stop()


def test_sender_sends_a_value_only_when_it_changed():
    log = []
    handle = FakeHandle(log, "/x")
    sender = CompactSender()
    a = np.arange(6, dtype=np.float16)
    assert sender.send(handle, "points", a)
    assert not sender.send(handle, "points", a.copy())
    assert sender.send(handle, "points", a + 1)
    assert sender.send(handle, "text", "step 1") and not sender.send(handle, "text", "step 1")
    assert log == [("/x", "points"), ("/x", "points"), ("/x", "text")]


def test_points_are_half_precision_on_a_grid_exact_to_the_walls():
    xy = np.array([[31.99, -31.99], [0.004, 12.3456]])
    pts = SceneView._points(2, xy)
    assert pts.dtype == np.float16 and pts.shape == (2, 3)
    # 1/64 m steps are exact in half precision up to 32 m from the centre (2 ** 11 steps).
    np.testing.assert_array_equal(pts[:, :2].astype(float) / POINT_GRID, np.round(xy / POINT_GRID))
    assert pts[1, 0] == 0.0  # a 4 mm offset rounds to the grid point
    resting = np.array([[10.0, -20.0], [0.5, 3.25]])  # a box that only trembles, by 3 mm either way
    assert SceneView._points(2, resting + 0.003).tobytes() == SceneView._points(2, resting - 0.003).tobytes()


def test_colours_and_counts_use_the_same_charge_classes():
    """Issue 24, item 3: a robot is drawn green, amber or red by the classes the page counts."""
    from sandbox.app.view import palette as pal

    capacity = 20.0
    charges = np.array([0.0, 1e-6, 5.0, 10.0, 10.01, 20.0])
    colours = [tuple(c) for c in pal.robot_colours(charges, capacity)]
    assert colours == [pal.ROBOT_EMPTY, pal.ROBOT_LOW, pal.ROBOT_LOW, pal.ROBOT_LOW, pal.ROBOT_CHARGED,
                       pal.ROBOT_CHARGED]
    assert pal.charge_counts(charges, capacity) == (2, 3, 1)
    assert [name for name, _, _ in pal.CHARGE_CLASSES] == ["charged", "low", "empty"]
    assert "half" in pal.CHARGE_CLASSES[0][2]  # the legend states the threshold


def test_an_unchanged_frame_sends_only_nothing(snapshot):
    scene = FakeScene()
    SceneView(scene, snapshot).update(snapshot)
    built = list(scene.sent)
    view = SceneView(scene, snapshot)
    scene.sent.clear()
    view.update(snapshot)
    assert scene.sent == [], "the same snapshot again must send nothing"
    moved = dataclasses.replace(snapshot, robot_positions=snapshot.robot_positions + 0.5, step=snapshot.step + 1)
    view.update(moved)
    sent = set(scene.sent)
    assert ("/swarm/robots", "points") in sent and ("/swarm/headings", "points") in sent
    assert ("/caption", "text") in sent
    assert not any(path.startswith("/swarm/boxes") for path, _ in sent) and ("/arena/lit", "points") not in sent
    assert built  # the first frame did build and send


def test_caption_names_the_case_and_the_step(snapshot):
    assert case_name("star", {"switch": 0.25}) == "star-switch (star + switch 0.25)"
    assert case_name("circle", {}) == "circle"
    assert case_name("heart", {"flare": 1.5}) == "heart + flare 1.5"
    assert case_name("static/shapes/notched/own/K.txt", {}) == "K.txt"  # fits a phone's one-line caption
    text = caption(snapshot)
    assert text.startswith("circle | step ") and "cycle 0" in text and "% in goal" in text
    # Another program lights the floor: the caption says so instead of the paper's phase.
    from dataclasses import replace

    from sandbox.app.world.snapshot import LAMP_PROGRAM

    assert "| lit by your lamp |" in caption(replace(snapshot, program=LAMP_PROGRAM))
    assert "| lit by ShrinkingRing |" in caption(replace(snapshot, program="examples/ring.py:ShrinkingRing"))
    # A band that gathers the robots: one word on the floor, the sides in the panel's phase line.
    gathering = replace(snapshot, phase="dilating, gathering beside the left and right", gathering="LR")
    assert "| gathering, cycle 0 |" in caption(gathering)


def test_lit_lights_are_points_sent_with_the_bodies(snapshot):
    """The lit lights travel as points in the frame's own messages (a texture is decoded later
    than the points it came with), in the grid picture's colours."""
    from sandbox.app.view import palette as pal

    scene = FakeScene()
    view = SceneView(scene, snapshot)
    lit = view.handles["lit"]
    cfg = snapshot.world_config
    on = snapshot.intensities > 0
    assert on.any() and lit.visible
    assert len(lit.points) == on.sum() and len(lit.colors) == on.sum()
    # Each point lies in its light's cell.
    cells = np.floor((lit.points[:, :2].astype(float) + cfg.arena_size / 2) / cfg.light_pitch).astype(int)
    assert {tuple(c) for c in cells} == {tuple(c) for c in np.argwhere(on)}
    picture = pal.light_grid_image(snapshot.intensities, cell_pixels=8, top_first=False)
    ix, iy = cells[0]
    np.testing.assert_array_equal(lit.colors[0], picture[iy * 8 + 4, ix * 8 + 4])
    scene.sent.clear()
    dark = dataclasses.replace(snapshot, intensities=np.zeros_like(snapshot.intensities), lights_key=("dark",))
    view.update(dark)
    assert not lit.visible and ("/arena/lights", "image") not in scene.sent
    view.set_show_field(True, snapshot)
    assert not lit.visible, "the heat map hides the lights"


# ------------------------------------------------------------------ hexagons
def test_a_box_is_the_recordings_hexagon():
    from sandbox.app.view.hexagons import hexagon, wxyz

    vertices, faces = hexagon(0.25)
    assert vertices.shape == (7, 3) and faces.shape == (6, 3)
    np.testing.assert_allclose(np.hypot(*vertices[1:, :2].T), 0.25, atol=1e-6)
    np.testing.assert_allclose(vertices[1, :2], [0.25, 0.0], atol=1e-7)  # a corner at angle 0, as frames.py
    a, b, c = vertices[faces[0]]
    assert np.cross(b - a, c - a)[2] > 0  # faces up
    q = wxyz(np.array([np.pi / 2]))[0]  # a quarter turn about z
    np.testing.assert_allclose(q, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], atol=1e-6)


def test_boxes_are_chunked_by_distance_and_resting_chunks_send_nothing():
    """Issue 24, item 6: hexagons cost 31 bytes a box where a disc cost 9, so a chunk that rests sends
    nothing, and a box turned less than the tolerance is not sent again."""
    from sandbox.app.view.hexagons import ANGLE_TOLERANCE, CHUNK, REGROUP, Hexagons

    rng = np.random.default_rng(3)
    m = 4 * CHUNK + 7
    points = np.zeros((m, 3), np.float16)
    points[:, :2] = np.round(rng.uniform(-8, 8, (m, 2)) * 64) / 64
    angles = rng.uniform(0, 2 * np.pi, m)
    colours = np.zeros((m, 3), np.uint8)
    scene = FakeScene()
    boxes = Hexagons(scene, "/swarm/boxes", m, 0.25, (32, 32, 0.02))
    boxes.update(points, angles, colours, np.zeros(2))  # built; the first regroup by distance
    boxes.update(points, angles, colours, np.zeros(2))
    shown = np.concatenate([idx for _, idx in boxes.chunks])
    assert sorted(shown) == list(range(m)) and [len(idx) for _, idx in boxes.chunks] == [CHUNK] * 4 + [7]
    # Nearer boxes in earlier chunks.
    far = [np.hypot(*points[idx, :2].astype(float).T).max() for _, idx in boxes.chunks]
    near = [np.hypot(*points[idx, :2].astype(float).T).min() for _, idx in boxes.chunks]
    assert all(f <= n for f, n in zip(far, near[1:]))
    for _ in range(3):  # frames until the next regrouping
        boxes.update(points, angles, colours, np.zeros(2))
    scene.sent.clear()
    boxes.update(points, angles, colours, np.zeros(2))
    assert scene.sent == [], "nothing moved: nothing sent"
    # One box moves and another turns a little, a third turns a lot.
    handle, idx = boxes.chunks[2]
    moved, slight, much = idx[0], boxes.chunks[3][1][0], boxes.chunks[1][1][0]
    points[moved, 0] += np.float16(0.25)
    angles[slight] += np.radians(ANGLE_TOLERANCE / 2)
    angles[much] += np.radians(2 * ANGLE_TOLERANCE)
    boxes.update(points, angles, colours, np.zeros(2))
    sent = sorted((path, prop) for path, prop in scene.sent)
    paths = {boxes.chunks[k][0]._path for k in (1, 2)}
    assert {path for path, _ in sent} == paths and len(sent) == 2, sent
    assert (boxes.chunks[2][0]._path, "batched_positions") in sent
    assert (boxes.chunks[1][0]._path, "batched_wxyzs") in sent
    assert REGROUP > 4  # no regrouping in between


def test_a_recoloured_box_and_a_regrouping_send_only_their_chunks():
    from sandbox.app.view.hexagons import CHUNK, REGROUP, Hexagons

    m = 3 * CHUNK
    points = np.zeros((m, 3), np.float32)
    points[:, 0] = np.arange(m) / 4.0  # box i at i/4 m from the centre: chunk k holds boxes 25k..25k+24
    angles, colours = np.zeros(m), np.zeros((m, 3), np.uint8)
    scene = FakeScene()
    boxes = Hexagons(scene, "/swarm/boxes", m, 0.25, (32, 32, 0.02))
    boxes.update(points, angles, colours, np.zeros(2))
    assert [list(idx) for _, idx in boxes.chunks] == [list(range(k * CHUNK, (k + 1) * CHUNK)) for k in range(3)]
    scene.sent.clear()
    colours[CHUNK + 3] = (255, 0, 0)  # a box of the middle chunk enters the goal
    boxes.update(points, angles, colours, np.zeros(2))
    assert scene.sent == [(boxes.chunks[1][0]._path, "batched_colors")]
    for _ in range(REGROUP - 2):
        boxes.update(points, angles, colours, np.zeros(2))
    scene.sent.clear()
    # The first chunk's last box and the middle chunk's first swap places, and so chunks. Each node
    # still shows the same positions and colours in the same order (the boxes are alike): only their
    # rotations are sent again, as other boxes' are. Then one box of the first chunk moves: its
    # positions alone.
    points[[CHUNK - 1, CHUNK], 0] = points[[CHUNK, CHUNK - 1], 0]
    boxes.update(points, angles, colours, np.zeros(2))
    first, middle = boxes.chunks[0][0]._path, boxes.chunks[1][0]._path
    assert list(boxes.chunks[0][1])[-1] == CHUNK and list(boxes.chunks[1][1])[0] == CHUNK - 1
    assert sorted(scene.sent) == [(first, "batched_wxyzs"), (middle, "batched_wxyzs")], scene.sent
    scene.sent.clear()
    points[0, 1] += 0.5
    boxes.update(points, angles, colours, np.zeros(2))
    assert scene.sent == [(first, "batched_positions")]


def test_a_portrait_view_frames_the_arena_at_its_top_above_the_panel():
    """On a phone viser's panel covers the lower half: the arena goes to the top of the view, whole."""
    import numpy as np

    from sandbox.model.config import Config

    config = Config()
    c, half = config.arena_size / 2, config.arena_size * 0.56
    for aspect in (1.6, 1.0, 0.8):  # landscape, square, a canvas beside the panel: centred, the height fills it
        position, look_at, fov = top_down_camera(config, aspect)
        assert look_at[:2].tolist() == [c, c]
        assert position[2] * np.tan(fov / 2) * min(aspect, 1.0) == pytest.approx(half)
    position, look_at, fov = top_down_camera(config, 390 / 844)
    top_of_view = look_at[1] + position[2] * np.tan(fov / 2)
    width_of_view = 2 * position[2] * np.tan(fov / 2) * 390 / 844
    assert top_of_view == pytest.approx(c + half) and width_of_view == pytest.approx(2 * half)
    assert look_at[1] < c - half / 2 and position[1] < look_at[1]  # looking down, tilted a hair forward


def test_the_caption_sits_where_every_framing_of_the_page_shows_it(snapshot):
    """Above the arena's top-right corner, away from viser's notifications (top left); a classroom's
    pages frame the construction area, so there it sits above the construction wall's corner."""
    labels = {}

    class LabelScene(FakeScene):
        def add_label(self, path, text, **kwargs):
            labels[path] = kwargs
            return FakeHandle(self.sent, path, visible=True, points=None)

    cfg = snapshot.world_config
    SceneView(LabelScene(), snapshot)
    assert labels["/caption"]["position"][:2] == (cfg.arena_size, cfg.arena_size + 0.8)
    assert labels["/caption"]["anchor"] == "bottom-right"
    classroom = SceneView(LabelScene(), snapshot, caption_over_construction=True)
    wall = cfg.centre + cfg.construction_size / 2
    # A classroom's: over the construction wall's middle, two lines in letters sized in metres (issue 56,
    # item 11: 14 px at 1024 x 768; 0.85 m is 25 px there).
    assert labels["/caption"]["position"][:2] == (cfg.centre, wall + 0.3)
    assert labels["/caption"]["anchor"] == "bottom-center" and labels["/caption"]["font_size_mode"] == "scene"
    assert labels["/caption"]["font_scene_height"] == 0.85 and classroom._caption(snapshot).count("\n") == 1
    # Beside a compared world, each world's share in the goal is large under its construction wall and its
    # caption under the arena's bottom wall, off the lit floor, in two lines (two captions on one line ran
    # into each other) sized in metres, the first world's from below the construction wall's left corner
    # (issue 56, item 10: 13 px at a projector, over the lit band, and beside the open panel the first ran
    # over the second world), and back when compare mode ends.
    view = SceneView(LabelScene(), snapshot)
    assert labels["/readout"]["visible"] is False
    view.set_compared((70.0, 0.0), snapshot)
    low = cfg.centre - cfg.construction_size / 2
    assert labels["/caption"]["position"][:2] == (low, -LABEL_GAP) and labels["/caption"]["anchor"] == "top-left"
    assert labels["/caption"]["font_size_mode"] == "scene"
    assert view.handles["readout"].visible and labels["/readout"]["font_size_mode"] == "scene"
    assert view._caption(snapshot).count("\n") == 1 and "% in goal" not in view._caption(snapshot)
    view.set_compared((0.0, -70.0), snapshot, second=True)  # one below the other: from the wall's middle
    assert labels["/caption"]["position"][:2] == (cfg.centre, wall + 0.3)
    assert labels["/caption"]["anchor"] == "bottom-center"
    view.set_compared(None, snapshot)
    assert labels["/caption"]["anchor"] == "bottom-right" and not view.handles["readout"].visible
    # The compared world's nodes live under its own root, moved along the floor.
    SceneView(LabelScene(), snapshot, root="/compare", offset=(70.0, 0.0))
    assert labels["/compare/caption"]["position"][:2] == (cfg.arena_size, cfg.arena_size + 0.8)


def test_compare_mode_frames_both_arenas(snapshot):
    """The camera over two arenas side by side: centred between them, as high as their width needs."""
    config = snapshot.world_config
    s, offset = config.arena_size, compare_offset(config)
    position, look_at, fov = compare_camera(config, 1.4, offset, whole=True)
    assert look_at[0] == pytest.approx(s / 2 + offset[0] / 2)  # halfway between the two arenas' centres
    half_width = (1.12 * s + offset[0]) / 2 * 1.02  # both arenas, their margins and a pad for the captions
    assert position[2] == pytest.approx(half_width / 1.4 / np.tan(fov / 2))
    one, _, _ = top_down_camera(config, 1.4)
    assert position[2] > one[2]


# ------------------------------------------------ compare mode for a room (issue 41, item 1)
def visible_floor(position, look_at, fov, aspect):
    """(left, right, bottom, top) of the floor a top-down camera shows in a view ``aspect`` wide."""
    half_h = position[2] * np.tan(fov / 2)
    return (look_at[0] - half_h * aspect, look_at[0] + half_h * aspect, look_at[1] - half_h, look_at[1] + half_h)


def inside(box, frame, tolerance=1e-6) -> bool:
    return (frame[0] - tolerance <= box[0] and box[1] <= frame[1] + tolerance and frame[2] - tolerance <= box[2]
            and box[3] <= frame[3] + tolerance)


def overlap(a, b) -> bool:
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


#: Canvases (width, height in CSS px): a projector with the panel folded or open beside it, a wide screen,
#: a tall screen and a phone upright.
CANVASES = {"projector, presenter": (984, 768), "projector, panel open": (604, 768), "wide screen": (1560, 1000),
            "wide screen, panel open": (1180, 1000), "tall screen": (768, 1024),
            "tall screen, panel open": (348, 1024), "phone": (390, 844)}


@pytest.mark.parametrize("canvas", CANVASES)
@pytest.mark.parametrize("view", ["whole", "construction", "presenter"])
def test_compare_framing_shows_every_caption_and_readout_apart(snapshot, canvas, view):
    """Both worlds, each with its caption over it, its share in the goal under it and the difference
    between them, all in the page's view and none over another; the layout is the one a page of this shape
    asks for (below on a page taller than wide). On a projector, none lies where viser stacks its notices
    (the canvas's top-left 310 x 150 px)."""
    from sandbox.app.panel.compare import TALL
    from sandbox.app.view.scene import (caption_box, compare_camera, compare_legend_box, construction_box,
                                   difference_box, readout_box, shifted)

    config = snapshot.world_config
    width, height = CANVASES[canvas]
    if view == "presenter" and "panel open" in canvas:
        pytest.skip("the presenter layout folds the panel")
    aspect = width / height
    offset = compare_offset(config, stacked=aspect < TALL)
    legend = 368 / 380 if view == "presenter" else None
    position, look_at, fov = compare_camera(config, aspect, offset, whole=view == "whole", legend_height_per_width=legend)
    frame = visible_floor(position, look_at, fov, aspect)
    view_height = frame[3] - frame[2]
    labels = {"left caption": caption_box(config, offset, False, view_height),
              "right caption": caption_box(config, offset, True, view_height),
              "left readout": readout_box(config), "right readout": shifted(readout_box(config), offset),
              "difference": difference_box(config, offset)}
    areas = {"left area": construction_box(config), "right area": shifted(construction_box(config), offset)}
    if legend:
        areas["legend"] = compare_legend_box(config, offset, legend)
    for name, box in {**labels, **areas}.items():
        assert inside(box, frame), f"{name} {np.round(box, 1)} is not all in view {np.round(frame, 1)}"
    names = list(labels) + list(areas)
    boxes = {**labels, **areas}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            if a in labels or b in labels:
                assert not overlap(boxes[a], boxes[b]), f"{a} {np.round(boxes[a], 1)} covers {b} {np.round(boxes[b], 1)}"
    if canvas == "projector, presenter":
        scale = width / (frame[1] - frame[0])  # px per m
        notices = (frame[0], frame[0] + 310 / scale, frame[3] - 150 / scale, frame[3])
        for name, box in labels.items():
            assert not overlap(box, notices), f"{name} lies under viser's notices"
    # As large as the room needs: at a projector's 1024 x 768 each construction area is at least 150 px wide.
    if canvas == "projector, presenter" and view != "whole":
        assert config.construction_size * width / (frame[1] - frame[0]) >= 150
