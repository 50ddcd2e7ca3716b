"""The overhead light grid and the luminosity it casts on the floor (SPEC §3).

A floor point ``p`` receives ``Lum(p) = sum_i I_i / d_i^k * a_i`` from every
light ``i`` that reaches it, where ``d_i`` is the 3-D distance and ``a_i``
the angle factor. Two readings of the model (see ``Config``):

* paper text: ``a = sin(theta) = height / d``, and a light reaches ``p`` when it
  is within ``light_range`` of it in x and in y;
* the authors' program: ``a = sin(atan2(height, hypot(dx^2, dy^2)))``, the
  horizontal offsets entering *squared* (so beyond a metre or two the field
  falls off about as 1 / rho^4), and a light reaches ``p`` when its cell
  index is within ``floor(p / pitch) - W .. floor(p / pitch) + W - 1`` in x and
  in y (``W = floor(light_range / pitch)``, one more cell below than above)
  and it is not in the grid's last row or column, which the program's loop
  bound never reaches.

The pattern changes only when the controller updates it, so the field is
kept at sample points and read by bilinear interpolation. Two things make
that exact enough (within 1 % of the field's maximum, tested):

* The hard range cut-off makes the true field jump wherever a row or
  column of lights enters or leaves range: along the lines where the
  distance to a light column is exactly ``light_range``. Those lines repeat
  every light pitch, so each pitch is split into *strips* between them, and
  every strip gets its own samples, both ends included. Inside a strip the
  set of lights in range is fixed and the field is smooth, so interpolation
  never straddles a jump.
* The layout repeats every pitch and lights sit one pitch apart, so every
  light adds the same precomputed block of values, shifted by whole
  pitches; a pattern change adds or removes only the lights that changed.
"""

from __future__ import annotations

import numpy as np

from sandbox.lazy_numba import compiled_at_first_use
from sandbox.model.config import Config


def light_centres(config: Config) -> np.ndarray:
    """Centres of all lights, shape (n, n, 2), indexed [ix, iy]."""
    n = config.lights_per_side
    c = (np.arange(n) + 0.5) * config.light_pitch
    gx, gy = np.meshgrid(c, c, indexing="ij")
    return np.stack([gx, gy], axis=-1)


def brightness_kernel(dx: np.ndarray, dy: np.ndarray, height: float, falloff: float,
                      angle: str = "elevation") -> np.ndarray:
    """What a light of intensity 1 gives a point at horizontal offset (dx, dy):
    ``1 / d^k`` times the angle factor, ``height / d`` ('elevation') or
    ``height / sqrt(height^2 + dx^4 + dy^4)`` ('squared-offsets', the
    program's ``sin(atan2(h, hypot(dx * dx, dy * dy)))``)."""
    d2 = dx * dx + dy * dy + height * height
    if angle == "elevation":
        return height * d2 ** (-(falloff + 1.0) / 2.0)
    dx2, dy2 = dx * dx, dy * dy
    return d2 ** (-falloff / 2.0) * height / np.sqrt(height * height + dx2 * dx2 + dy2 * dy2)


def window_cells(config: Config) -> int:
    """W of the program's window: a point in light cell c is reached by cells c - W .. c + W - 1."""
    return int(np.floor(config.light_range / config.light_pitch + 1e-9))


def reaching_lights(config: Config) -> np.ndarray:
    """(n, n) mask of the lights that can light anything: all of them, but for
    the program's window, which never reaches the grid's last row and column."""
    mask = np.ones((config.lights_per_side,) * 2, dtype=bool)
    if config.light_window == "cells":
        mask[-1, :] = mask[:, -1] = False
    return mask


def in_window(points: np.ndarray, centres: np.ndarray, config: Config) -> np.ndarray:
    """Whether each light (centres, (L, 2)) reaches each point (points, (m, 2)): shape (m, L)."""
    d = np.abs(points[:, None, :] - centres[None, :, :])
    near = (d <= config.light_range + 1e-9).all(axis=-1)
    if config.light_window == "range":
        return near
    pitch, w = config.light_pitch, window_cells(config)
    point_cell = np.floor(points / pitch).astype(int)[:, None, :]
    light_cell = np.floor(centres / pitch).astype(int)[None, :, :]
    offset = light_cell - point_cell
    return near & ((offset >= -w) & (offset <= w - 1)).all(axis=-1)


def luminosity_direct(points: np.ndarray, intensities: np.ndarray, config: Config) -> np.ndarray:
    """Evaluate the SPEC §3 formula exactly at ``points`` (m, 2). Slow; the reference."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    centres = light_centres(config).reshape(-1, 2)
    weights = (np.asarray(intensities, dtype=float) * reaching_lights(config)).reshape(-1)
    on = weights != 0
    centres, weights = centres[on], weights[on]
    dx = points[:, None, 0] - centres[None, :, 0]
    dy = points[:, None, 1] - centres[None, :, 1]
    b = brightness_kernel(dx, dy, config.light_height, config.light_falloff, config.light_angle)
    return (b * in_window(points, centres, config)) @ weights



class _AxisLayout:
    """Sample positions along one axis (the same for x and y).

    Samples are grouped by *layout cell*: one light pitch starting at a
    range boundary ``origin``. A cell is split into strips at the other
    boundary (if any); each strip has ``count`` intervals and its own end
    samples, so a boundary position has two samples, one for each side.
    """

    def __init__(self, config: Config):
        pitch, reach = config.light_pitch, config.light_range
        target = pitch / config.field_samples
        # Where, within a pitch, a light column enters or leaves range; the
        # program's window also changes at every cell edge (offset 0).
        cuts = {round((0.5 * pitch + reach) % pitch, 12), round((0.5 * pitch - reach) % pitch, 12)}
        if config.light_window == "cells":
            cuts.add(0.0)
        cuts = sorted(cuts)
        self.pitch = pitch
        self.origin = cuts[0]
        edges = [c - self.origin for c in cuts] + [pitch]
        offsets: list[float] = []
        self.strip_lo, self.strip_first, self.strip_count, self.strip_step, mids = [], [], [], [], []
        for lo, hi in zip(edges[:-1], edges[1:]):
            count = max(1, int(np.ceil((hi - lo) / target - 1e-9)))
            self.strip_lo.append(lo)
            self.strip_first.append(len(offsets))
            self.strip_count.append(count)
            self.strip_step.append((hi - lo) / count)
            offsets.extend(lo + (hi - lo) * np.arange(count + 1) / count)
            mids.append(0.5 * (lo + hi))
        self.offsets = np.array(offsets)
        self.per_cell = len(offsets)
        self.strip_bounds = np.array(edges[1:-1])  # strip j starts at strip_bounds[j-1]
        strip_of_sample = np.repeat(np.arange(len(mids)), np.array(self.strip_count) + 1)
        # Light columns t cells to the right of a layout cell's first light:
        # relative position of light centre to the cell start is t*pitch + 0.5*pitch - origin.
        t_max = int(np.ceil((reach + pitch) / pitch)) + 1
        t = np.arange(t_max, -t_max - 1, -1)  # largest first: cells lx - t then ascend
        centre_rel = t * pitch + 0.5 * pitch - self.origin  # light centre minus cell start
        mids_arr = np.array(mids)[strip_of_sample]
        in_range = np.abs(centre_rel[:, None] - mids_arr[None, :]) <= reach
        if config.light_window == "cells":
            # The origin is then a cell edge, so t is the light's cell minus the point's.
            w = window_cells(config)
            in_range &= ((t >= -w) & (t <= w - 1))[:, None]
        keep = in_range.any(axis=1)
        #: For a light in column lx, cells lx - t (t in ``light_offsets``) hold samples it reaches.
        self.light_offsets = t[keep]
        #: dx from the light to each sample, and whether the sample's strip has the light in range.
        self.dx = self.offsets[None, :] - centre_rel[keep][:, None]
        self.member = in_range[keep]
        n = config.lights_per_side
        # Layout cells covering [0, arena]: cell k spans [origin + k*pitch, origin + (k+1)*pitch).
        self.first_cell = int(np.floor((0.0 - self.origin) / pitch))
        self.n_cells = int(np.floor((n * pitch - self.origin) / pitch)) - self.first_cell + 1
        self.pad = int(self.light_offsets.max()) + 1  # cells of padding on each side
        self.length = (self.n_cells + 2 * self.pad) * self.per_cell
        self.limit = n * pitch
        # Knots of the position -> sample-coordinate map used by locate().
        knots_x, knots_g = [], []
        for lo, step, first, count in zip(self.strip_lo, self.strip_step, self.strip_first, self.strip_count):
            knots_x += [lo, lo + step * count]
            knots_g += [first, first + count]
        self.knots_x, self.knots_g = np.array(knots_x), np.array(knots_g, dtype=float)
        self.row_base = (self.pad - self.first_cell) * self.per_cell

    def locate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Row index of the sample at or before each ``x`` in its strip, and the
        fraction of the way to the next sample. Hot path: few numpy calls.

        Within a layout cell, sample coordinates are a piecewise-linear
        function of position, jumping by one at each strip boundary (where
        a sample is doubled); ``np.interp`` evaluates it in one call."""
        x = x.clip(0.0, self.limit) - self.origin
        cell = np.floor(x * (1.0 / self.pitch))
        g = np.interp(x - cell * self.pitch, self.knots_x, self.knots_g)
        i = g.astype(np.intp)
        row = cell.astype(np.intp) * self.per_cell + (self.row_base + i)
        return row, g - i


def add_blocks(values: np.ndarray, kernel: np.ndarray, x0: np.ndarray, y0: np.ndarray,
               weights: np.ndarray) -> None:
    """``values[x0[i]:, y0[i]:][:w, :w] += weights[i] * kernel`` for each light i in turn: what one
    numpy add per light computes, bit for bit (the same float32 operations, in the same order for
    each sample; a weight of 1 or -1 adds or subtracts the kernel as it is).

    Compiled (:data:`compiled_add_blocks`), it goes row by row of ``values``, adding every light's
    kernel row there while the row stays in the processor's cache: a light's block is 240 x 240
    samples (230 KB), a pattern change adds 55 lights on average, and adding them block by block
    streamed each block through memory (33 µs a light)."""
    width = kernel.shape[0]
    if x0.shape[0] == 0:
        return
    first, last = x0.min(), x0.max() + width
    for x in range(first, last):
        for i in range(x0.shape[0]):
            r = x - x0[i]
            if r < 0 or r >= width:
                continue
            # A slice, indexed from 0 by the loop: numba then needs no negative-index check and the
            # loop vectorises (indexing the whole row at y + j ran 5x slower).
            segment, k, w = values[x, y0[i]:y0[i] + width], kernel[r], weights[i]
            if w == 1.0:
                for j in range(width):
                    segment[j] = segment[j] + k[j]
            elif w == -1.0:
                for j in range(width):
                    segment[j] = segment[j] - k[j]
            else:
                scaled = np.float32(w)
                for j in range(width):
                    segment[j] = segment[j] + scaled * k[j]


#: :func:`add_blocks` compiled at its first use: the web server imports this module, never changes a
#: pattern, and does not load numba.
compiled_add_blocks = compiled_at_first_use(add_blocks)


#: The most points a side of :meth:`LightField.display_grid` has.
DISPLAY_MOST = 1025


class LightField:
    """Light intensities and the sampled luminosity field they produce."""

    #: float32 halves the memory traffic of pattern changes (the cost that
    #: matters); its rounding (~1e-7 of the value) is far below the 1 %
    #: agreement with the formula that the tests demand.
    DTYPE = np.float32
    #: Rebuild from scratch at least this often rather than patching.
    FRESH_EVERY = 64

    def __init__(self, config: Config):
        self.config = config
        n = config.lights_per_side
        self.axis = ax = _AxisLayout(config)
        # Every light adds this block (rows: x samples, columns: y samples).
        k = brightness_kernel(ax.dx.reshape(-1, 1), ax.dx.reshape(1, -1), config.light_height, config.light_falloff,
                              config.light_angle)
        self.kernel = (k * (ax.member.reshape(-1, 1) & ax.member.reshape(1, -1))).astype(self.DTYPE)
        self._values = np.zeros((ax.length, ax.length), dtype=self.DTYPE)
        #: The sampled field as one flat array (a view), for compiled samplers.
        self.values_flat = self._values.reshape(-1)
        self.intensities = np.zeros((n, n))
        #: Lights whose light reaches the floor at all (see reaching_lights).
        self._reaching = reaching_lights(config)
        self.rebuilds = 0
        self._incremental = 0

    def set_intensities(self, intensities: np.ndarray) -> bool:
        """Switch to a new pattern; returns whether anything changed."""
        new = np.asarray(intensities, dtype=float)
        if new.shape != self.intensities.shape:
            raise ValueError(f"expected intensities of shape {self.intensities.shape}, got {new.shape}")
        if (new == self.intensities).all():
            return False
        effective = new * self._reaching
        delta = effective - self.intensities * self._reaching
        changed = np.argwhere(delta != 0)
        self._incremental += 1
        if len(changed) > np.count_nonzero(effective) or self._incremental > self.FRESH_EVERY:
            # Cheaper, or due: start afresh (also clears float32 rounding
            # that adding and removing lights accumulates).
            self._values.fill(0.0)
            self._add_lights(np.argwhere(effective != 0), effective)
            self._incremental = 0
        else:
            self._add_lights(changed, delta)
        self.intensities = new.copy()
        self.rebuilds += 1
        return True

    def _add_lights(self, indices: np.ndarray, weights: np.ndarray) -> None:
        """Add ``weights[ix, iy]`` times the kernel block of each light in ``indices``, in that order."""
        x0, y0 = self._block_starts(indices)
        compiled_add_blocks(self._values, self.kernel, x0, y0, weights[indices[:, 0], indices[:, 1]])

    def _block_starts(self, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where each light's block starts in the sample array (x row, y column)."""
        ax = self.axis
        # Light column lx reaches layout cells lx - t for t in light_offsets
        # (largest t first), i.e. starting at cell lx - t_max.
        start_cell = -int(ax.light_offsets.max()) - ax.first_cell + ax.pad
        starts = (np.asarray(indices, dtype=np.intp).reshape(-1, 2) + start_cell) * ax.per_cell
        return np.ascontiguousarray(starts[:, 0]), np.ascontiguousarray(starts[:, 1])

    def sample(self, points: np.ndarray) -> np.ndarray:
        """Luminosity at floor points (..., 2) by bilinear interpolation within
        strips. Points outside the arena read the nearest edge value."""
        pts = np.asarray(points, dtype=float)
        n = self.axis.length
        rows, frac = self.axis.locate(pts)  # x and y located together
        flat = rows[..., 0] * n + rows[..., 1]
        fu, fv = frac[..., 0], frac[..., 1]
        f = self.values_flat
        f00 = f.take(flat)
        f10 = f.take(flat + n) - f00
        f01 = f.take(flat + 1) - f00
        f11 = f.take(flat + (n + 1)) - f00 - f10 - f01
        return f00 + fu * f10 + fv * (f01 + fu * f11)

    def display_grid(self, per_pitch: int = 8, most: int = DISPLAY_MOST) -> np.ndarray:
        """The field on a regular grid over the whole floor, ``per_pitch`` points
        per light pitch plus the far edge, at most ``most`` points a side, indexed
        [ix, iy] (for display: 1,025 points a side are finer than a page shows, and
        4 per pitch of 2,000 lights a side would be 64 million points, 5 GB)."""
        cfg = self.config
        c = np.linspace(0.0, cfg.arena_size, min(cfg.lights_per_side * per_pitch + 1, most))
        gx, gy = np.meshgrid(c, c, indexing="ij")
        return self.sample(np.stack([gx, gy], axis=-1))
