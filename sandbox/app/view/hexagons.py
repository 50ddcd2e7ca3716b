"""The boxes as hexagons, as the paper's and the recordings' boxes are. Pure geometry; any thread.

Each box is an instance of one flat hexagon (viser's batched meshes), turned
by the box's angle and coloured by whether it is in the goal. An instance
costs 31 bytes on the wire (position 12, rotation 16, colour 3: viser sends
float32 and uint8) where a disc cost 9, and viser sends a node's whole array
when one instance changes. So:

- the boxes are split into chunks of :data:`CHUNK` by distance from the
  centre (regrouped every :data:`REGROUP` frames): the band pushes a ring of
  boxes at a time while the pile inside and the strays outside rest, and a
  resting chunk sends nothing;
- a chunk's rotations are sent again only when one of its boxes has turned
  more than :data:`ANGLE_TOLERANCE` from the angle drawn (then all of them,
  exactly); positions go on the scene's grid, like every other point.

Measured on the default world, 600 frames of 25 steps (about one cycle),
bytes of box updates per frame: discs 1,150; hexagons in one node 4,580; in
chunks of 50 by distance 3,130; in chunks of 25 with rotations within 6
degrees, 2,290.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Boxes per chunk (one batched-mesh node each).
CHUNK = 25
#: Frames between two regroupings of the boxes by distance from the centre.
REGROUP = 30
#: A box is drawn turned by at most this many degrees from its angle (of a hexagon's 60-degree symmetry).
ANGLE_TOLERANCE = 6.0


def hexagon(circumradius: float) -> tuple[np.ndarray, np.ndarray]:
    """A flat regular hexagon in the xy plane, corners at 0, 60, ... degrees (the recordings' hexagon
    at angle 0): (vertices, faces) of a fan around its centre."""
    a = np.arange(6) * np.pi / 3
    vertices = np.zeros((7, 3), np.float32)
    vertices[1:, 0], vertices[1:, 1] = circumradius * np.cos(a), circumradius * np.sin(a)
    faces = np.array([(0, 1 + k, 1 + (k + 1) % 6) for k in range(6)], np.uint32)
    return vertices, faces


def wxyz(angles: np.ndarray) -> np.ndarray:
    """(n, 4) float32 quaternions turning about z by each angle."""
    a = np.asarray(angles, dtype=float)
    out = np.zeros((len(a), 4), np.float32)
    out[:, 0], out[:, 3] = np.cos(a / 2), np.sin(a / 2)
    return out


def turned(drawn: np.ndarray, angles: np.ndarray) -> float:
    """The largest difference (degrees) between hexagons drawn at ``drawn`` and the boxes' ``angles``."""
    sixty = np.pi / 3
    d = np.mod(np.asarray(angles, dtype=float) - drawn + sixty / 2, sixty) - sixty / 2
    return float(np.degrees(np.abs(d).max())) if len(d) else 0.0


class Hexagons:
    """The boxes of one world as chunks of a batched mesh under ``path`` (``/swarm/boxes``)."""

    def __init__(self, scene: Any, path: str, count: int, circumradius: float, position: tuple, sender: Any):
        self.scene, self.path, self.count = scene, path, int(count)
        self._mesh = hexagon(circumradius)
        self._position = position
        self._sender = sender
        self._frame = 0
        #: (handle, the boxes it shows in index order, the angles drawn)
        self.chunks: list[list] = []

    def update(self, points: np.ndarray, angles: np.ndarray, colours: np.ndarray, centre: np.ndarray) -> None:
        """Show the boxes at ``points`` ((m, 3) relative to the node, already on the sending grid),
        turned by ``angles``, in ``colours``; ``centre`` is where the chunks are grouped around."""
        positions = points.astype(np.float32)
        if not self.chunks:
            self._build(positions, angles, colours, centre)
        elif self._frame % REGROUP == 0:
            self._regroup(positions, centre)
        self._frame += 1
        for chunk in self.chunks:
            handle, idx, drawn = chunk
            self._sender.send(handle, "batched_positions", positions[idx])
            if drawn is None or turned(drawn, angles[idx]) > ANGLE_TOLERANCE:
                handle.batched_wxyzs = wxyz(angles[idx])
                chunk[2] = np.asarray(angles[idx], dtype=float).copy()
            self._sender.send(handle, "batched_colors", colours[idx])

    def _build(self, positions: np.ndarray, angles: np.ndarray, colours: np.ndarray, centre: np.ndarray) -> None:
        vertices, faces = self._mesh
        for k, idx in enumerate(self._groups(positions, centre)):
            handle = self.scene.add_batched_meshes_simple(
                f"{self.path}/{k}", vertices, faces, batched_wxyzs=wxyz(angles[idx]), batched_positions=positions[idx],
                batched_colors=colours[idx], lod="off", material="standard", flat_shading=True, side="double",
                cast_shadow=False, receive_shadow=False, position=self._position)
            self._sender.remember(handle, "batched_positions", positions[idx])
            self._sender.remember(handle, "batched_colors", colours[idx])
            self.chunks.append([handle, idx, np.asarray(angles[idx], dtype=float).copy()])

    def _groups(self, positions: np.ndarray, centre: np.ndarray) -> list[np.ndarray]:
        """The boxes by distance from the centre, CHUNK at a time (each in index order)."""
        order = np.argsort(np.hypot(*(positions[:, :2] - centre).T), kind="stable")
        return [np.sort(order[start:start + CHUNK]) for start in range(0, self.count, CHUNK)]

    def _regroup(self, positions: np.ndarray, centre: np.ndarray) -> None:
        """Boxes at alike distances from the centre share a chunk; a chunk keeps its node and its size."""
        for chunk, idx in zip(self.chunks, self._groups(positions, centre)):
            if not np.array_equal(idx, chunk[1]):
                chunk[1], chunk[2] = idx, None  # other boxes: their angles are sent with their positions

    def remove(self) -> None:
        for handle, _, _ in self.chunks:
            handle.remove()
        self.chunks = []
