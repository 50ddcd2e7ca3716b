"""Colours and picture-making shared by the live page, the recordings and the
headless GIF / MP4 frames, so every view of a run looks the same. Constants and pure functions; any thread.

Pure numpy: nothing here imports viser or touches a running simulation.
"""

from __future__ import annotations

import numpy as np

# RGB, 0..255.
BACKGROUND = (24, 26, 32)
LIGHT_OFF = (58, 61, 70)
LIGHT_ON = (255, 212, 38)
CELL_EDGE = (36, 38, 45)
BOX_OUT = (236, 238, 242)
BOX_IN = (255, 92, 168)
GOAL_LINE = (64, 200, 255)
LIGHT_LINE = (255, 140, 30)
BOX_WALL = (150, 160, 185)
ARENA_WALL = (205, 210, 220)
HEADING_MARK = (20, 22, 28)
SELECTED = (190, 90, 255)
#: A robot's colour says which of three charge classes it is in, and the page counts the same classes:
#: charged (more than CHARGED_ABOVE of a full store), low (some charge, up to that), empty (none: it
#: cannot move). One threshold for the colour, the legend and the count, so they cannot disagree.
ROBOT_CHARGED = (46, 204, 64)
ROBOT_LOW = (255, 165, 0)
ROBOT_EMPTY = (230, 40, 40)
CHARGED_ABOVE = 0.5
CHARGE_CLASSES = (("charged", ROBOT_CHARGED, "more than half full"), ("low", ROBOT_LOW, "some charge, half or less"),
                  ("empty", ROBOT_EMPTY, "no charge, cannot move"))
#: The followed robot's four photocell dots on the floor, in the order of its photocells' names
#: (front-left, front-right, back-left, back-right; or front, back, left, right), and their names.
SENSOR_COLOURS = np.array([[255, 255, 255], [90, 90, 90], [64, 200, 255], [255, 140, 30]], dtype=np.uint8)
SENSOR_COLOUR_NAMES = ("white", "dark grey", "blue", "orange")

#: Pixels per light cell in the light-grid texture (cells stay crisp even with
#: the browser's linear texture filtering because each cell is a flat block).
CELL_PIXELS = 8


def charge_class(charges: np.ndarray, capacity: float) -> np.ndarray:
    """(n,) index into CHARGE_CLASSES: 0 charged (more than CHARGED_ABOVE of ``capacity``), 1 low
    (above zero), 2 empty."""
    c = np.asarray(charges, dtype=float)
    charged = c > CHARGED_ABOVE * capacity if capacity > 0 else np.ones(c.shape, bool)
    return np.where(charged, 0, np.where(c > 0, 1, 2))


def charge_counts(charges: np.ndarray, capacity: float) -> tuple[int, int, int]:
    """How many robots are charged, low and empty: the robots drawn green, amber and red."""
    counts = np.bincount(charge_class(charges, capacity), minlength=3)
    return int(counts[0]), int(counts[1]), int(counts[2])


_ROBOT_COLOURS = np.array([ROBOT_CHARGED, ROBOT_LOW, ROBOT_EMPTY], dtype=np.uint8)


def robot_colours(charges: np.ndarray, capacity: float) -> np.ndarray:
    """(n, 3) uint8: the colour of each robot's charge class (green charged, amber low, red empty)."""
    return _ROBOT_COLOURS[charge_class(charges, capacity)]


def box_colours(in_goal: np.ndarray) -> np.ndarray:
    """(m, 3) uint8: pink when the box centre is inside the goal, white otherwise."""
    return np.where(np.asarray(in_goal, dtype=bool)[:, None], np.uint8(BOX_IN), np.uint8(BOX_OUT)).astype(np.uint8)


# ------------------------------------------------------- lit meshes in the page
# The page draws meshes lit (an even ambient light, sandbox.app.view.scene) and tone-mapped (three.js's ACES
# filmic curve, React Three Fiber's default); points, lines and pictures it draws as they are. A mesh's
# colour is therefore chosen so that what the page shows is the palette's colour (as near as the curve
# lets: its brightest white is about 226 of 255).
_ACES_IN = np.array([[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]])
_ACES_OUT = np.array([[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]])


def _srgb(linear: np.ndarray) -> np.ndarray:
    c = np.clip(np.asarray(linear, dtype=float), 0.0, 1.0)
    return np.where(c <= 0.0031308, c * 12.92, 1.055 * c ** (1 / 2.4) - 0.055)


def shown_on_mesh(rgb: tuple | np.ndarray) -> np.ndarray:
    """The colour (0..255 floats) the page shows for a mesh given colour ``rgb``: taken as linear
    light (viser hands instance colours to three.js as they are), lit to itself, then three.js's
    ACESFilmicToneMapping (exposure 1), then sRGB. Measured: (255, 92, 168) shows as (231, 181, 209)."""
    v = _ACES_IN @ (np.asarray(rgb, dtype=float) / 255.0 / 0.6)
    v = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)
    return 255.0 * _srgb(_ACES_OUT @ v)


#: The colours to give the page's lit hexagon meshes so that they show BOX_IN and BOX_OUT (or the
#: nearest the page can show): the bounded least-squares solutions of shown_on_mesh(x) = colour, solved
#: once (tests/app/view/test_pictures.py solves them again) rather than at every start: scipy.optimize alone
#: takes 0.9 s to import.
BOX_IN_MESH = (255, 17, 80)
BOX_OUT_MESH = (255, 255, 255)


def box_mesh_colours(in_goal: np.ndarray) -> np.ndarray:
    """(m, 3) uint8: :func:`box_colours` for the page's hexagons (lit meshes: see :data:`BOX_IN_MESH`)."""
    inside, outside = np.uint8(BOX_IN_MESH), np.uint8(BOX_OUT_MESH)
    return np.where(np.asarray(in_goal, dtype=bool)[:, None], inside, outside).astype(np.uint8)


def light_grid_image(intensities: np.ndarray, cell_pixels: int = CELL_PIXELS, peak: float = 1.0,
                     top_first: bool = True) -> np.ndarray:
    """RGB image (rows = y from the top, or from the bottom when ``top_first``
    is False as viser's scene images want; columns = x) of the light grid:
    each light a flat block, grey when off through yellow when fully on,
    with a thin darker seam between cells."""
    level = np.clip(np.asarray(intensities, dtype=float) / (peak if peak > 0 else 1.0), 0.0, 1.0)
    off, on = np.array(LIGHT_OFF, float), np.array(LIGHT_ON, float)
    cells = off + level[..., None] * (on - off)  # [ix, iy, 3]
    cells = np.transpose(cells, (1, 0, 2))  # [row from bottom, col, 3]
    if top_first:
        cells = cells[::-1]
    img = np.repeat(np.repeat(cells, cell_pixels, axis=0), cell_pixels, axis=1)
    if cell_pixels >= 4:
        img[::cell_pixels, :] = CELL_EDGE
        img[:, ::cell_pixels] = CELL_EDGE
    return img.astype(np.uint8)


_HEAT_LUT: np.ndarray | None = None


def lit_cells(intensities: np.ndarray, pitch: float, peak: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The lights that are on, as ((k, 2) centres in metres from the grid's corner, (k, 3) uint8
    colours): the same colours as :func:`light_grid_image`, cell by cell, for the lights above zero."""
    level = np.clip(np.asarray(intensities, dtype=float) / (peak if peak > 0 else 1.0), 0.0, 1.0)
    ix, iy = np.nonzero(level > 0)
    centres = (np.stack([ix, iy], axis=1) + 0.5) * pitch
    off, on = np.array(LIGHT_OFF, float), np.array(LIGHT_ON, float)
    colours = (off + level[ix, iy, None] * (on - off)).astype(np.uint8)
    return centres, colours


#: matplotlib's "inferno" colour map at 256 levels, rounded to 8 bits (RGB after RGB), written out
#: here because importing matplotlib for it took a sixth of the server's start (tests/app/view/test_pictures.py
#: checks it against matplotlib's).
INFERNO_HEX = (
    "00000401000501010601010802010a02020c02020e03021004031204031405041706041907051b08051d09061f0a0722"
    "0b07240c08260d08290e092b10092d110a30120a32140b34150b37160b39180c3c190c3e1b0c411c0c431e0c451f0c48"
    "210c4a230c4c240c4f260c51280b53290b552b0b572d0b592f0a5b310a5c320a5e340a5f3609613809623909633b0964"
    "3d09653e0966400a67420a68440a68450a69470b6a490b6a4a0c6b4c0c6b4d0d6c4f0d6c510e6c520e6d540f6d550f6d"
    "57106e59106e5a116e5c126e5d126e5f136e61136e62146e64156e65156e67166e69166e6a176e6c186e6d186e6f196e"
    "71196e721a6e741a6e751b6e771c6d781c6d7a1d6d7c1d6d7d1e6d7f1e6c801f6c82206c84206b85216b87216b88226a"
    "8a226a8c23698d23698f24699025689225689326679526679727669827669a28659b29649d29649f2a63a02a63a22b62"
    "a32c61a52c60a62d60a82e5fa92e5eab2f5ead305dae305cb0315bb1325ab3325ab43359b63458b73557b93556ba3655"
    "bc3754bd3853bf3952c03a51c13a50c33b4fc43c4ec63d4dc73e4cc83f4bca404acb4149cc4248ce4347cf4446d04545"
    "d24644d34743d44842d54a41d74b3fd84c3ed94d3dda4e3cdb503bdd513ade5238df5337e05536e15635e25734e35933"
    "e45a31e55c30e65d2fe75e2ee8602de9612bea632aeb6429eb6628ec6726ed6925ee6a24ef6c23ef6e21f06f20f1711f"
    "f1731df2741cf3761bf37819f47918f57b17f57d15f67e14f68013f78212f78410f8850ff8870ef8890cf98b0bf98c0a"
    "f98e09fa9008fa9207fa9407fb9606fb9706fb9906fb9b06fb9d07fc9f07fca108fca309fca50afca60cfca80dfcaa0f"
    "fcac11fcae12fcb014fcb216fcb418fbb61afbb81dfbba1ffbbc21fbbe23fac026fac228fac42afac62df9c72ff9c932"
    "f9cb35f8cd37f8cf3af7d13df7d340f6d543f6d746f5d949f5db4cf4dd4ff4df53f4e156f3e35af3e55df2e661f2e865"
    "f2ea69f1ec6df1ed71f1ef75f1f179f2f27df2f482f3f586f3f68af4f88ef5f992f6fa96f8fb9af9fc9dfafda1fcffa4"
)


def _heat_lut() -> np.ndarray:
    global _HEAT_LUT
    if _HEAT_LUT is None:
        _HEAT_LUT = np.frombuffer(bytes.fromhex(INFERNO_HEX), dtype=np.uint8).reshape(256, 3)
    return _HEAT_LUT


def field_image(field: np.ndarray, scale: float | None = None, top_first: bool = True) -> np.ndarray:
    """Heat map (RGB, rows = y from the top) of the luminosity field the robots
    sense, indexed [ix, iy] on the sample grid. ``scale`` maps to full colour
    (default: the field's maximum)."""
    f = np.asarray(field, dtype=np.float32)
    top = float(scale if scale else f.max()) or 1.0
    idx = np.clip(np.sqrt(np.clip(f / top, 0.0, 1.0)) * 255.0, 0, 255).astype(np.uint8)
    return _heat_lut()[idx.T[::-1] if top_first else idx.T]


def closed_segments(vertices: np.ndarray, z: float = 0.0) -> np.ndarray:
    """(k, 2, 3) line segments around a closed polygon at height z."""
    v = np.asarray(vertices, dtype=np.float32).reshape(-1, 2)
    if len(v) < 2:
        return np.zeros((0, 2, 3), dtype=np.float32)
    a, b = v, np.roll(v, -1, axis=0)
    out = np.empty((len(v), 2, 3), dtype=np.float32)
    out[:, 0, :2], out[:, 1, :2] = a, b
    out[:, :, 2] = z
    return out


def open_segments(vertices: np.ndarray, z: float = 0.0) -> np.ndarray:
    """(k-1, 2, 3) line segments along an open polyline at height z."""
    v = np.asarray(vertices, dtype=np.float32).reshape(-1, 2)
    if len(v) < 2:
        return np.zeros((0, 2, 3), dtype=np.float32)
    out = np.empty((len(v) - 1, 2, 3), dtype=np.float32)
    out[:, 0, :2], out[:, 1, :2] = v[:-1], v[1:]
    out[:, :, 2] = z
    return out


def square(centre: float, half: float) -> np.ndarray:
    return np.array([[centre - half, centre - half], [centre + half, centre - half],
                     [centre + half, centre + half], [centre - half, centre + half]])
