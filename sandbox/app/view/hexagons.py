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


def turned_each(drawn: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Each box's difference (degrees) between its hexagon drawn at ``drawn`` and its ``angles`` (of a
    hexagon's 60-degree symmetry)."""
    sixty = np.pi / 3
    return np.degrees(np.abs(np.mod(np.asarray(angles, float) - drawn + sixty / 2, sixty) - sixty / 2))


class Hexagons:
    """The boxes of one world as chunks of a batched mesh under ``path`` (``/swarm/boxes``).

    What each chunk's node was last sent is kept in one array per property, chunk after chunk (its
    *slots*: chunk k's boxes are ``order[starts[k]:starts[k + 1]]``), so that a frame finds the chunks to
    send in a few whole-array operations, not a few per chunk: a class's server draws 30 pages' boxes
    10 times a second (79 against 178 us a frame of the paper's world before, 900 frames, the same
    assignments in the same order)."""

    def __init__(self, scene: Any, path: str, count: int, circumradius: float, position: tuple):
        self.scene, self.path, self.count = scene, path, int(count)
        self._mesh = hexagon(circumradius)
        self._position = position
        self._frame = 0
        #: (handle, the boxes it shows in index order)
        self.chunks: list[list] = []
        self._order = np.zeros(0, np.intp)  # the boxes, chunk after chunk
        self._starts = np.zeros(0, np.intp)  # where each chunk's slots begin
        self._positions = np.zeros((0, 3), np.uint32)  # each slot's position as last sent (its bits)
        self._colours = np.zeros((0, 3), np.uint8)
        self._drawn = np.zeros(0)  # each slot's angle as drawn
        self._restate = np.zeros(0, bool)  # chunks whose boxes changed: their rotations are sent again

    def update(self, points: np.ndarray, angles: np.ndarray, colours: np.ndarray, centre: np.ndarray) -> None:
        """Show the boxes at ``points`` ((m, 3) relative to the node, already on the sending grid),
        turned by ``angles``, in ``colours``; ``centre`` is where the chunks are grouped around."""
        positions = points.astype(np.float32)
        if not self.chunks:
            self._build(positions, angles, colours, centre)
        elif self._frame % REGROUP == 0:
            self._regroup(positions, centre)
        self._frame += 1
        order, starts = self._order, self._starts
        bits = positions.view(np.uint32)[order]  # compared bit for bit, as the bytes sent
        shades = np.asarray(colours)[order]
        slot_angles = np.asarray(angles, dtype=float)[order]
        moved = np.logical_or.reduceat((bits != self._positions).any(axis=1), starts)
        recoloured = np.logical_or.reduceat((shades != self._colours).any(axis=1), starts)
        turned_most = np.maximum.reduceat(turned_each(self._drawn, slot_angles), starts)
        turn = self._restate | (turned_most > ANGLE_TOLERANCE)
        for k in np.flatnonzero(moved | turn | recoloured):
            handle, idx = self.chunks[k]
            slots = slice(starts[k], starts[k] + len(idx))
            if moved[k]:
                handle.batched_positions = positions[idx]
                self._positions[slots] = bits[slots]
            if turn[k]:
                handle.batched_wxyzs = wxyz(angles[idx])
                self._drawn[slots] = slot_angles[slots]
            if recoloured[k]:
                handle.batched_colors = colours[idx]
                self._colours[slots] = shades[slots]
        self._restate[:] = False

    def _build(self, positions: np.ndarray, angles: np.ndarray, colours: np.ndarray, centre: np.ndarray) -> None:
        vertices, faces = self._mesh
        groups = self._groups(positions, centre)
        for k, idx in enumerate(groups):
            handle = self.scene.add_batched_meshes_simple(
                f"{self.path}/{k}", vertices, faces, batched_wxyzs=wxyz(angles[idx]), batched_positions=positions[idx],
                batched_colors=colours[idx], lod="off", material="standard", flat_shading=True, side="double",
                cast_shadow=False, receive_shadow=False, position=self._position)
            self.chunks.append([handle, idx])
        self._order = np.concatenate(groups)
        self._starts = np.cumsum([0] + [len(idx) for idx in groups[:-1]])
        self._positions = positions.view(np.uint32)[self._order].copy()
        self._colours = np.asarray(colours)[self._order].copy()
        self._drawn = np.asarray(angles, dtype=float)[self._order].copy()
        self._restate = np.zeros(len(groups), bool)

    def _groups(self, positions: np.ndarray, centre: np.ndarray) -> list[np.ndarray]:
        """The boxes by distance from the centre, CHUNK at a time (each in index order)."""
        order = np.argsort(np.hypot(*(positions[:, :2] - centre).T), kind="stable")
        return [np.sort(order[start:start + CHUNK]) for start in range(0, self.count, CHUNK)]

    def _regroup(self, positions: np.ndarray, centre: np.ndarray) -> None:
        """Boxes at alike distances from the centre share a chunk; a chunk keeps its node and its size
        (its slots): what its node was last sent is compared with its new boxes."""
        for k, (chunk, idx) in enumerate(zip(self.chunks, self._groups(positions, centre))):
            if not np.array_equal(idx, chunk[1]):
                chunk[1] = idx  # other boxes: their rotations are sent again (_restate)
                self._order[self._starts[k]:self._starts[k] + len(idx)] = idx
                self._restate[k] = True

    def remove(self) -> None:
        for handle, _ in self.chunks:
            handle.remove()
        self.chunks = []

