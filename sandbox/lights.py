"""The overhead light grid and the luminosity it casts on the floor (SPEC §3).

A floor point ``p`` receives ``Lum(p) = sum_i I_i / d_i^k * sin(theta_i)`` from
every light ``i`` within ``light_range`` in x and in y, where ``d_i`` is the
3-D distance and ``sin(theta_i) = height / d_i``.

The pattern changes only when the controller updates it, so the field is
kept on a regular sample grid (``field_samples`` points per light pitch) and
read by bilinear interpolation. Because lights sit on sample points, every
light contributes the same kernel shifted by whole samples; a pattern change
only adds or removes the kernels of the lights that changed.
"""

from __future__ import annotations

import numpy as np

from .config import Config


def light_centres(config: Config) -> np.ndarray:
    """Centres of all lights, shape (n, n, 2), indexed [ix, iy]."""
    n = config.lights_per_side
    c = (np.arange(n) + 0.5) * config.light_pitch
    gx, gy = np.meshgrid(c, c, indexing="ij")
    return np.stack([gx, gy], axis=-1)


def brightness_kernel(dx: np.ndarray, dy: np.ndarray, height: float, falloff: float) -> np.ndarray:
    """What a light of intensity 1 gives a point at horizontal offset (dx, dy):
    ``1 / d^k * height / d``."""
    d2 = dx * dx + dy * dy + height * height
    return height * d2 ** (-(falloff + 1.0) / 2.0)


def luminosity_direct(points: np.ndarray, intensities: np.ndarray, config: Config) -> np.ndarray:
    """Evaluate the SPEC §3 formula exactly at ``points`` (m, 2). Slow; the reference."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    centres = light_centres(config).reshape(-1, 2)
    weights = np.asarray(intensities, dtype=float).reshape(-1)
    on = weights != 0
    centres, weights = centres[on], weights[on]
    dx = points[:, None, 0] - centres[None, :, 0]
    dy = points[:, None, 1] - centres[None, :, 1]
    in_range = (np.abs(dx) <= config.light_range + 1e-9) & (np.abs(dy) <= config.light_range + 1e-9)
    b = brightness_kernel(dx, dy, config.light_height, config.light_falloff) * in_range
    return b @ weights


class LightField:
    """Light intensities and the sampled luminosity field they produce."""

    def __init__(self, config: Config):
        self.config = config
        n = config.lights_per_side
        self.samples_per_pitch = config.field_samples
        self.spacing = config.light_pitch / config.field_samples
        # Kernel half-width in samples: offsets up to light_range are in range.
        self.reach = int(np.floor(config.light_range / self.spacing + 1e-9))
        offsets = np.arange(-self.reach, self.reach + 1) * self.spacing
        kx, ky = np.meshgrid(offsets, offsets, indexing="ij")
        self.kernel = brightness_kernel(kx, ky, config.light_height, config.light_falloff)
        self.size = n * config.field_samples + 1  # sample points per side, edges included
        # Padded so every light's kernel fits without clipping.
        self._padded = np.zeros((self.size + 2 * self.reach,) * 2)
        r = self.reach
        #: Luminosity at sample points, shape (size, size), indexed [ix, iy]
        #: (a view: it follows every pattern change).
        self.field = self._padded[r : r + self.size, r : r + self.size]
        self._flat_field = np.zeros(self.size * self.size)
        self.intensities = np.zeros((n, n))
        self.rebuilds = 0
        self.cache_hits = 0
        # Cached fields are float32: their rounding (~1e-7 of the value) is far
        # below the interpolation error the tests allow (1 % of the maximum).
        self._cache: dict[bytes, np.ndarray] = {}
        self._cache_capacity = int(config.field_cache_mb * 2**20 // max(self.field.size * 4, 1))

    def sample_points(self) -> np.ndarray:
        """Coordinates of the sample grid along one axis."""
        return np.arange(self.size) * self.spacing

    def set_intensities(self, intensities: np.ndarray) -> bool:
        """Switch to a new pattern; returns whether anything changed."""
        new = np.asarray(intensities, dtype=float)
        if new.shape != self.intensities.shape:
            raise ValueError(f"expected intensities of shape {self.intensities.shape}, got {new.shape}")
        delta = new - self.intensities
        changed = np.argwhere(delta != 0)
        if len(changed) == 0:
            return False
        key = new.tobytes()
        cached = self._cache.pop(key, None)
        if cached is not None:
            self._cache[key] = cached  # most recently used last
            self._padded.fill(0.0)
            self.field[:] = cached
            self.cache_hits += 1
        elif len(changed) > np.count_nonzero(new):
            # Cheaper (and free of accumulated rounding) to start afresh.
            self._padded.fill(0.0)
            self._add_lights(np.argwhere(new != 0), new)
        else:
            self._add_lights(changed, delta)
        if cached is None:
            self._remember(key)
        self.intensities = new.copy()
        self._flat_field[:] = self.field.reshape(-1)
        self.rebuilds += 1
        return True

    def _remember(self, key: bytes) -> None:
        """Keep this pattern's field: the controller's cycle repeats the same
        sequence of patterns, so most later pattern changes become a copy."""
        if self._cache_capacity <= 0:
            return
        while len(self._cache) >= self._cache_capacity:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = self.field.astype(np.float32)

    def _add_lights(self, indices: np.ndarray, weights: np.ndarray) -> None:
        s, half, k = self.samples_per_pitch, self.samples_per_pitch // 2, self.kernel
        width = k.shape[0]
        for ix, iy in indices:
            # Light (ix, iy) sits on sample (ix*s + s/2, iy*s + s/2); in the padded
            # array its kernel starts ``reach`` earlier, i.e. at ix*s + s/2.
            x0, y0 = ix * s + half, iy * s + half
            self._padded[x0 : x0 + width, y0 : y0 + width] += weights[ix, iy] * k

    def sample(self, points: np.ndarray) -> np.ndarray:
        """Luminosity at floor points (..., 2) by bilinear interpolation.
        Points outside the arena read the nearest edge value."""
        pts = np.asarray(points, dtype=float)
        # Hot path (every step, every robot): few, flat numpy operations.
        uv = pts * (1.0 / self.spacing)
        uv.clip(0.0, self.size - 1.000001, out=uv)
        ij = uv.astype(np.intp)
        frac = uv - ij
        fu, fv = frac[..., 0], frac[..., 1]
        flat = ij[..., 0] * self.size + ij[..., 1]
        f = self._flat_field
        f00 = f.take(flat)
        f10 = f.take(flat + self.size) - f00
        f01 = f.take(flat + 1) - f00
        f11 = f.take(flat + (self.size + 1)) - f00 - f10 - f01
        return f00 + fu * f10 + fv * (f01 + fu * f11)

    @property
    def maximum(self) -> float:
        return float(self.field.max())
